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

std::vector<KeyframeId> KeyframeDatabase::ids() const {
  std::vector<KeyframeId> held;
  for (const KeyframeId id : ids_)
    if (const auto it = position_.find(id); it != position_.end() && ids_[it->second] == id) held.push_back(id);
  return held;
}

void KeyframeDatabase::remove(KeyframeId id) {
  const std::uint32_t position = position_.at(id);
  for (const BowEntry& e : bows_[position]) {
    auto& postings = inverted_[e.word];
    std::erase_if(postings, [&](const Posting& p) { return p.keyframe == position; });
  }
  bows_[position] = {};
  position_.erase(id);
  if (ids_.size() > 2 * position_.size() + 16) compact();
}

// Positions renumbered over the kept keyframes, in their order.
void KeyframeDatabase::compact() {
  std::vector<KeyframeId> ids;
  std::vector<BowVector> bows;
  for (std::uint32_t j = 0; j < ids_.size(); ++j)
    if (const auto it = position_.find(ids_[j]); it != position_.end() && it->second == j) {
      ids.push_back(ids_[j]);
      bows.push_back(std::move(bows_[j]));
    }
  ids_.clear();
  bows_.clear();
  position_.clear();
  inverted_.clear();
  for (std::size_t j = 0; j < ids.size(); ++j) add(ids[j], std::move(bows[j]));
  inverted_.shrink_to_fit();
}

std::vector<LoopCandidate> KeyframeDatabase::candidates(KeyframeId query_id, const BowVector& bow,
                                                        KeyframeId previous_id, double min_eta) const {
  const auto previous = position_.find(previous_id);
  if (previous == position_.end()) return {};
  return candidates(query_id, bow, bows_[previous->second], min_eta, previous->second);
}

std::vector<LoopCandidate> KeyframeDatabase::candidates(KeyframeId query_id, const BowVector& bow,
                                                        const BowVector& previous_bow, double min_eta,
                                                        std::uint32_t excluded) const {
  const double reference = score(bow, previous_bow);
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
    if (j == excluded || bows_[j].empty()) continue;  // removed ones too
    const double s = std::clamp(common[j], 0.0, 1.0);
    if (const double eta = s / reference; eta > min_eta) out.push_back({ids_[j], s, eta});
  }
  // Stable: equal η keep insertion order.
  std::stable_sort(out.begin(), out.end(),
                   [](const LoopCandidate& a, const LoopCandidate& b) { return a.eta > b.eta; });
  return out;
}

}  // namespace cvo::loop_closure
