#include "libcvo/loop_closure/loop_detector.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace cvo::loop_closure {
namespace {

// γ's kernel, as the tracker's (keyframe_odometry.cpp): the CVO kernel with γ's looser signal.
core::CvoParameters gamma_parameters(const LoopDetectorParameters& p) {
  core::CvoParameters c = p.cvo;
  c.sigma = p.keyframe_tracking.gamma_sigma;
  return c;
}

}  // namespace

LoopDetector::LoopDetector(Vocabulary vocabulary, const LoopDetectorParameters& parameters)
    : vocabulary_(std::move(vocabulary)),
      parameters_(parameters),
      registration_(registration::Capacities{parameters.odometry.max_points}, parameters.cvo),
      gamma_registration_(registration::Capacities{parameters.odometry.max_points, 0}, gamma_parameters(parameters)) {}

double LoopDetector::coverage(std::int64_t covering, std::int64_t covered, const core::SE3& T) {
  const auto& c = keyframes_.at(covering).cloud;
  const auto& k = keyframes_.at(covered).cloud;
  const double ell = parameters_.keyframe_tracking.gamma_ell;
  const std::size_t stride = parameters_.keyframe_tracking.gamma_stride;
  const double norms = gamma_registration_.inner_product(c, c, core::SE3(), ell, stride) *
                       gamma_registration_.inner_product(k, k, core::SE3(), ell, stride);
  if (!(norms > 0)) return 0;
  return gamma_registration_.inner_product(c, k, T, ell, stride) / std::sqrt(norms);
}

std::vector<LoopClosure> LoopDetector::add_keyframe(std::int64_t id, const core::RgbdFrame& frame,
                                                    const registration::PointCloud& cloud, const core::SE3& pose) {
  if (previous_ && id <= *previous_)
    throw std::invalid_argument("LoopDetector::add_keyframe: id " + std::to_string(id) + " is not above " +
                                std::to_string(*previous_));
  return add_keyframe(KeyframePlacement{id, previous_, pose, 0, std::nullopt}, frame, cloud);
}

std::vector<LoopClosure> LoopDetector::add_keyframe(const KeyframePlacement& placement, const core::RgbdFrame& frame,
                                                    const registration::PointCloud& cloud) {
  const std::int64_t id = placement.id;
  if (keyframes_.contains(id))
    throw std::invalid_argument("LoopDetector::add_keyframe: keyframe " + std::to_string(id) + " is stored already");
  attempts_.clear();
  confirmations_.clear();
  const OrbFeatures features = extract_orb(frame.bgr, parameters_.verification);
  LoopKeyframe keyframe = make_loop_keyframe(id, features, frame, cloud, placement.pose, parameters_);
  keyframe.piece = placement.piece;
  BowVector bow = vocabulary_.transform(features.descriptors);

  std::vector<LoopCandidate> candidates;
  const double eta = parameters_.loop.similarity_threshold;
  if (placement.previous && database_.contains(*placement.previous))
    candidates = placement.previous_is_candidate
                     ? database_.candidates(id, bow, database_.bow(*placement.previous), eta)
                     : database_.candidates(id, bow, *placement.previous, eta);
  auto loops = verify(keyframe, candidates, placement.candidates_below);
  database_.add(id, std::move(bow));
  keyframes_.emplace(id, std::move(keyframe));
  previous_ = id;
  return loops;
}

std::vector<LoopClosure> LoopDetector::detect_first(std::int64_t first, std::int64_t next) {
  attempts_.clear();
  confirmations_.clear();
  const auto& keyframe = keyframes_.at(first);
  if (!keyframes_.contains(next))
    throw std::out_of_range("LoopDetector::detect_first: no keyframe " + std::to_string(next));
  const auto candidates =
      database_.candidates(first, database_.bow(first), next, parameters_.loop.similarity_threshold);
  return verify(keyframe, candidates, std::nullopt);
}

std::vector<LoopClosure> LoopDetector::verify(const LoopKeyframe& keyframe,
                                              const std::vector<LoopCandidate>& candidates,
                                              std::optional<std::int64_t> candidates_below) {
  std::vector<LoopClosure> loops;
  const int max_refinements = parameters_.verification.max_refinements;
  int refinements = 0;
  for (const auto& c : candidates) {  // best η first
    if (candidates_below && c.id >= *candidates_below) continue;
    if (max_refinements > 0 && refinements == max_refinements) break;
    auto v = verify_loop(keyframe, keyframes_.at(c.id), parameters_, registration_);
    if (v.refinement.iterations > 0) ++refinements;
    v.attempt.eta = c.eta;
    attempts_.push_back(v.attempt);
    if (v.confirmation) {
      v.confirmation->eta = c.eta;
      confirmations_.push_back(*v.confirmation);
    }
    if (v.closure) {
      v.closure->eta = c.eta;
      loops.push_back(*v.closure);
    }
  }
  return loops;
}

void LoopDetector::remove_keyframe(std::int64_t id) {
  if (keyframes_.erase(id) == 0)
    throw std::out_of_range("LoopDetector::remove_keyframe: keyframe " + std::to_string(id) + " is not stored");
  database_.remove(id);
  if (previous_ == id) previous_.reset();
}

void LoopDetector::update_poses(const std::map<std::int64_t, core::SE3>& poses) {
  for (const auto& [id, pose] : poses)
    if (const auto it = keyframes_.find(id); it != keyframes_.end()) it->second.pose = pose;
}

void LoopDetector::update_poses(const std::map<std::int64_t, PlacedPose>& poses) {
  for (const auto& [id, placed] : poses)
    if (const auto it = keyframes_.find(id); it != keyframes_.end()) {
      it->second.pose = placed.pose;
      it->second.piece = placed.piece;
    }
}

}  // namespace cvo::loop_closure
