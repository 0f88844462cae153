#include "libcvo/loop_closure/keyframe_database.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace cvo::loop_closure {

void KeyframeDatabase::add(KeyframeId id, BowVector bow) {
  if (position_.contains(id))
    throw std::invalid_argument("keyframe database: keyframe " + std::to_string(id) + " added twice");
  for (std::size_t e = 0; e < bow.size(); ++e)
    if ((e > 0 && bow[e].word <= bow[e - 1].word) || !std::isfinite(bow[e].weight) || !(bow[e].weight > 0))
      throw std::invalid_argument("keyframe database: keyframe " + std::to_string(id) +
                                  ": not a BoW vector (words unsorted or repeated, or a weight not positive)");
  const auto position = static_cast<std::uint32_t>(ids_.size());
  if (!bow.empty() && inverted_.size() <= bow.back().word) inverted_.resize(std::size_t{bow.back().word} + 1);
  for (const BowEntry& e : bow) inverted_[e.word].push_back({position, e.weight});
  position_.emplace(id, position);
  ids_.push_back(id);
  bows_.push_back(std::move(bow));
}

std::vector<LoopCandidate> KeyframeDatabase::candidates(KeyframeId query_id, const BowVector& bow,
                                                        KeyframeId previous_id, double min_eta) const {
  const auto previous = position_.find(previous_id);
  if (previous == position_.end()) return {};
  const double reference = score(bow, bows_[previous->second]);
  if (!(reference > 0)) return {};
  const auto query = position_.find(query_id);
  const std::size_t earlier = query == position_.end() ? ids_.size() : query->second;

  // Σ_w min(v_i,w, v_j,w) over the words of v_i, in word order, exactly as score() adds them.
  std::vector<double> common(earlier, 0.0);
  for (const BowEntry& e : bow) {
    if (e.word >= inverted_.size()) continue;
    for (const Posting& p : inverted_[e.word])
      if (p.keyframe < earlier) common[p.keyframe] += std::min(e.weight, p.weight);
  }
  std::vector<LoopCandidate> out;
  for (std::uint32_t j = 0; j < earlier; ++j) {
    if (j == previous->second) continue;
    const double s = std::clamp(common[j], 0.0, 1.0);
    if (const double eta = s / reference; eta > min_eta) out.push_back({ids_[j], s, eta});
  }
  // Stable: equal η keep insertion order.
  std::stable_sort(out.begin(), out.end(),
                   [](const LoopCandidate& a, const LoopCandidate& b) { return a.eta > b.eta; });
  return out;
}

}  // namespace cvo::loop_closure
