#include "libcvo/odometry/keyframe_odometry.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "libcvo/core/units.hpp"
#include "libcvo/odometry/motion_redundancy.hpp"
#include "libcvo/odometry/variance_factor.hpp"
#include "libcvo/registration/edge_covariance.hpp"

namespace cvo::odometry {
namespace {

using Clock = core::SteadyClock;
using core::ms_since;

bool usable(registration::SelectionStatus s) {
  return s == registration::SelectionStatus::kOk || s == registration::SelectionStatus::kCapacityClamped;
}

// A frame whose points the compensations move: a rolling shutter, or depth not taken with the colour.
bool compensates(const core::RgbdFrame& frame) {
  return frame.intrinsics.rolling_shutter() || (frame.depth_timestamp > 0 && frame.depth_timestamp != frame.timestamp);
}

// γ compares two inner products of different frame pairs. Evaluated with the tracker's tight
// kernel (a pair counts only when k_s k_c > 0.83) it rests on a few hundred near-identical pairs
// and jumps by a factor of two from frame to frame on fr1/rpy; with the looser signal
// `gamma_sigma` (σ² = 0.1: pairs count above 0.083) it sums ~100k pairs and is smooth.
core::CvoParameters gamma_parameters(const KeyframeOdometryParameters& p) {
  core::CvoParameters c = p.cvo;
  c.sigma = p.tracking.gamma_sigma;
  return c;
}

double mean_depth(const registration::PointCloud& cloud) {
  if (cloud.size() == 0) return 0.0;
  double sum = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) sum += cloud.z()[i];
  return sum / static_cast<double>(cloud.size());
}

}  // namespace

const char* to_string(KeyframeReason reason) {
  switch (reason) {
    case KeyframeReason::kNone: return "none";
    case KeyframeReason::kFirst: return "first frame";
    case KeyframeReason::kGamma: return "inner-product ratio below threshold";
    case KeyframeReason::kTranslation: return "translation above threshold";
    case KeyframeReason::kRotation: return "rotation above threshold";
    case KeyframeReason::kKeyframeLost: return "keyframe registration failed";
    case KeyframeReason::kRestart: return "restart after a tracking failure";
    case KeyframeReason::kGraphFull: return "local graph full";
  }
  return "unknown";
}

KeyframeOdometry::KeyframeOdometry(int width, int height, const KeyframeOdometryParameters& parameters)
    : parameters_(parameters),
      selector_(width, height, parameters.selection),
      registration_(registration::Capacities{parameters.odometry.max_points}, parameters.cvo),
      gamma_registration_(registration::Capacities{parameters.odometry.max_points, 0}, gamma_parameters(parameters)),
      clouds_{registration::PointCloud(parameters.odometry.max_points),
              registration::PointCloud(parameters.odometry.max_points),
              registration::PointCloud(parameters.odometry.max_points)},
      graphs_{LocalGraph(parameters.tracking.local_graph_capacity),
              LocalGraph(parameters.tracking.local_graph_capacity)} {}

void KeyframeOdometry::reset() {
  for (auto& graph : graphs_) graph.clear();
  graph_ = 0;
  start_over();
}

std::optional<HandedLocalGraph> KeyframeOdometry::finish() {
  const bool open = !graphs_[graph_].empty() && keyframe_id_ >= 0;
  const HandedLocalGraph handed{keyframe_id_, &graphs_[graph_]};
  if (open) graph_ = 1 - graph_;  // it stays put, as a closed graph, until a later one closes
  graphs_[graph_].clear();        // the next session's open graph: finish() again hands out nothing
  start_over();
  if (!open) return std::nullopt;
  return handed;
}

// Everything but the graphs to the state of a new tracker (previous_images_ lets go of the
// caller's images).
void KeyframeOdometry::start_over() {
  graph_closed_ = false;
  keyframe_id_ = -1;
  previous_images_ = core::RgbdFrame{};
  keyframe_ = 0;
  previous_ = 1;
  current_ = 2;
  have_keyframe_ = have_previous_ = have_frame_ = false;
  keyframe_frame_ = previous_frame_ = 0;
  keyframe_pose_ = previous_pose_ = T_m_previous_ = velocity_ = last_pose_ = core::SE3();
  previous_timestamp_ = velocity_dt_ = gamma_reference_ = gamma_ = 0;
  compensation_velocity_ = last_compensation_velocity_ = core::SE3();
  compensation_dt_ = last_compensation_dt_ = 0;
  current_uncompensated_ = previous_uncompensated_ = false;
  reason_ = KeyframeReason::kNone;
  covariance_chain_ = PoseCovarianceChain{};
  variance_factor_ = VarianceFactor{};
  motion_redundancy_ = MotionRedundancy{};
  smooth_position_ = SmoothPosition{};
}

void KeyframeOdometry::start_keyframe(int cloud, std::uint64_t index, double timestamp, const core::SE3& pose,
                                      KeyframeReason why) {
  if (!graphs_[graph_].empty()) {  // close the open graph; it stays readable until the next one
    graph_ = 1 - graph_;
    graph_closed_ = true;
  }
  ++keyframe_id_;
  graphs_[graph_].clear();
  graphs_[graph_].add_node({index, timestamp, pose});
  keyframe_ = cloud;
  keyframe_frame_ = index;
  keyframe_pose_ = pose;
  gamma_reference_ = 0;
  reason_ = why;
  have_keyframe_ = true;
}

double KeyframeOdometry::gamma_inner_product(const registration::PointCloud& keyframe, const core::SE3& T_mn) {
  return gamma_registration_.inner_product(keyframe, clouds_[current_], T_mn, parameters_.tracking.gamma_ell,
                                           parameters_.tracking.gamma_stride);
}

// The one-node local graph: minimise |log(T T_kf^-1)|²_{H_kf} + w |log(T C^-1)|²_{H_c} over T, with
// left perturbations in the keyframe's frame (the solver's convention, registration.hpp). The
// chain C = T_m^{n-1} T_{n-1}^n with T_{n-1}^n = exp(η) T̂ has C = exp(Ad(T_m^{n-1}) η) Ĉ, so its
// information there is H_c = Ad⁻ᵀ H_f2f Ad⁻¹. One Gauss-Newton step from T_kf is exact for the
// linearised problem: ξ = (H_kf + w H_c)⁻¹ w H_c log(C T_kf⁻¹), T = exp(ξ) T_kf. Fixed-size 6x6
// algebra: no allocation.
core::SE3 KeyframeOdometry::fuse_with_chain(const registration::RegistrationResult& kf,
                                            const registration::RegistrationResult& f2f, const core::SE3& chain,
                                            core::Matrix6d& chain_information) const {
  double w = parameters_.tracking.chain_weight;
  if (parameters_.tracking.chain_full_weight_deg > 0) {
    const double ramp = core::degrees(chain.angle()) / parameters_.tracking.chain_full_weight_deg;
    w *= std::min(1.0, ramp * ramp);
  }
  if (!(w > 0)) return kf.transform;
  const core::Matrix6d Ad_inv = T_m_previous_.inverse().adjoint();
  const core::Matrix6d H_chain = w * (Ad_inv.transpose() * f2f.hessian * Ad_inv);
  const core::Vector6d d = (chain * kf.transform.inverse()).log();
  const core::Matrix6d H = kf.hessian + H_chain;
  const core::Vector6d xi = H.ldlt().solve(H_chain * d);
  if (!xi.allFinite()) return kf.transform;
  const core::SE3 fused = core::SE3::exp(xi) * kf.transform;
  if (!fused.is_finite()) return kf.transform;
  chain_information = H_chain;
  return fused;
}

// The camera's motion from the colour image's time to the depth image's, at the last measured
// velocity: identity before there is one, when the stamps are missing or implausible, and when
// they are equal (the source declares the two images simultaneous: rendered frames, synchronised
// sensors; depth_time_offset_s describes how a Kinect's depth stamps lag). Capped at
// kMaxCompensationDeg: a wrong compensation corrupts the next velocity, which would feed back.
core::SE3 KeyframeOdometry::colour_T_depth(const core::RgbdFrame& frame) const {
  constexpr double kMaxDt = 0.05, kMaxCompensationDeg = 5.0;
  if (!have_previous_ || !(compensation_dt_ > 0) || !(frame.depth_timestamp > 0) ||
      frame.depth_timestamp == frame.timestamp)
    return {};
  const double dt = frame.depth_timestamp - frame.timestamp + parameters_.selection.depth_time_offset_s;
  if (!(std::abs(dt) <= kMaxDt) || dt == 0) return {};
  const core::SE3 motion = core::SE3::exp((dt / compensation_dt_) * compensation_velocity_.log());
  if (!motion.is_finite() || core::degrees(motion.angle()) > kMaxCompensationDeg) return {};
  return motion;
}

// The camera's motion per second at the last measured velocity, for a rolling-shutter camera's
// rows (PointSelector::select): zero before there is one and for a global shutter. A rate beyond
// kMaxRateDegS is no camera's motion but a wrong velocity (it would feed back): the twist is then
// scaled down to it, never dropped. (It used to be dropped where the first or last row turned
// more than 2°: at a 20 ms readout from 200 °/s on, the fast turns the compensation is for.)
core::Vector6d KeyframeOdometry::twist(const core::RgbdFrame& frame) const {
  constexpr double kMaxRateDegS = 1000.0;  // 2.8 turns a second
  if (!frame.intrinsics.rolling_shutter() || !have_previous_ || !(compensation_dt_ > 0)) return core::Vector6d::Zero();
  const core::Vector6d xi = compensation_velocity_.log() / compensation_dt_;
  if (!xi.allFinite()) return core::Vector6d::Zero();
  const double rate_deg_s = core::degrees(xi.tail<3>().norm());
  return rate_deg_s > kMaxRateDegS ? core::Vector6d(xi * (kMaxRateDegS / rate_deg_s)) : xi;
}

bool KeyframeOdometry::trips_threshold(const core::SE3& T_mn, double gamma) {
  const auto& k = parameters_.keyframe;
  if (gamma < k.inner_product_ratio_threshold)
    reason_ = KeyframeReason::kGamma;
  else if (T_mn.translation().norm() > k.translation_threshold_m)
    reason_ = KeyframeReason::kTranslation;
  else if (core::degrees(T_mn.angle()) > k.rotation_threshold_deg)
    reason_ = KeyframeReason::kRotation;
  else if (graphs_[graph_].full())
    reason_ = KeyframeReason::kGraphFull;
  else
    return false;
  return true;
}

// Eq. 7 and 8: frame to frame from the constant velocity, keyframe to frame from the chain; then
// T̄_m^n, the keyframe result fused with the chain (see the header; the raw one goes to the graph).
KeyframeOdometry::Registrations KeyframeOdometry::register_frame(TrackResult& result, const FrameStart& f2f_start) {
  Registrations r;
  const auto start = Clock::now();
  r.f2f = registration_.align(clouds_[previous_], clouds_[current_], velocity_, f2f_start.ell, f2f_start.reuse);
  result.frame_registration_ms += ms_since(start);
  const bool f2f_ok = r.f2f.converged, separate = keyframe_ != previous_;
  r.kf = r.f2f;  // the keyframe is the previous frame: one registration
  r.chain = T_m_previous_ * (f2f_ok ? r.f2f.transform : velocity_);
  if (separate) {
    const auto keyframe_start = Clock::now();
    // From a converged frame-to-frame result the chain is within millimetres of the answer: no
    // wide basin is needed, so the keyframe registration starts at ℓ_min.
    r.kf = registration_.align(clouds_[keyframe_], clouds_[current_], r.chain, f2f_ok ? parameters_.cvo.ell_min : 0.0);
    result.keyframe_registration_ms = ms_since(keyframe_start);
  }
  r.T_mn = r.kf.converged && f2f_ok && separate ? fuse_with_chain(r.kf, r.f2f, r.chain, r.chain_information)
                                                : r.kf.transform;
  result.registration_ms = ms_since(start);
  result.iterations = r.f2f.iterations + (separate ? r.kf.iterations : 0);
  result.registration_status = r.kf.converged ? r.f2f.status : r.kf.status;
  return r;
}

// γ (eq. 9) after a converged keyframe registration, and the thresholds (eq. 10): whether frame
// n-1 becomes the keyframe. A trip at frame m+1 cannot move the keyframe to n-1 = m: frame n is
// then tracked against m all the same.
bool KeyframeOdometry::keyframe_trips(const Registrations& r, TrackResult& result) {
  if (!r.kf.converged) return false;
  const auto start = Clock::now();
  const double ip = gamma_inner_product(clouds_[keyframe_], r.T_mn);
  if (gamma_reference_ <= 0) gamma_reference_ = ip;  // this is frame m+1
  gamma_ = ip / gamma_reference_;
  bool trip = trips_threshold(r.T_mn, gamma_);
  result.gamma_ms = ms_since(start);
  if (trip && keyframe_ == previous_) {
    trip = false;
    reason_ = KeyframeReason::kNone;
  }
  return trip;
}

// Frame n tracked against keyframe m: a node of the open local graph, with its keyframe edge and,
// when the keyframe is not n-1, its frame-to-frame edge.
core::SE3 KeyframeOdometry::add_to_local_graph(const core::RgbdFrame& frame, const Registrations& r,
                                               TrackStep& result) {
  const core::SE3 pose = keyframe_pose_ * r.T_mn;
  result.status = TrackStatus::kOk;
  result.inner_product = r.kf.inner_product;
  auto& graph = graphs_[graph_];
  const auto f2f_covariance = fill_covariances(r, false, result);
  graph.add_node({frame.index, frame.timestamp, pose});
  graph.add_edge({keyframe_frame_, frame.index, r.kf.transform,
                  registration::information_of(result.edge_covariance, r.kf.hessian)});
  if (r.f2f.converged && keyframe_ != previous_)
    graph.add_edge(
        {previous_frame_, frame.index, r.f2f.transform, registration::information_of(f2f_covariance, r.f2f.hessian)});
  return pose;
}

// Frame n-1 becomes the keyframe (the paper's rule); T_{n-1}^n is then the keyframe-to-frame
// transform of frame n and its inner product the new γ reference.
core::SE3 KeyframeOdometry::keyframe_at_previous(const core::RgbdFrame& frame, const Registrations& r,
                                                 TrackStep& result) {
  start_keyframe(previous_, previous_frame_, previous_timestamp_, previous_pose_,
                 r.kf.converged ? reason_ : KeyframeReason::kKeyframeLost);
  const core::SE3 pose = previous_pose_ * r.f2f.transform;
  const auto reference_start = Clock::now();
  gamma_reference_ = gamma_inner_product(clouds_[keyframe_], r.f2f.transform);
  result.gamma_ms += ms_since(reference_start);
  gamma_ = 1.0;
  result.status = TrackStatus::kOk;
  result.keyframe = true;
  result.inner_product = r.f2f.inner_product;
  fill_covariances(r, true, result);  // n-1 is the keyframe: the frame-to-frame edge is its edge
  graphs_[graph_].add_node({frame.index, frame.timestamp, pose});
  graphs_[graph_].add_edge({previous_frame_, frame.index, r.f2f.transform,
                            registration::information_of(result.edge_covariance, r.f2f.hessian)});
  return pose;
}

// The edges' covariances, calibrated (registration/edge_covariance.hpp, variance_factor.hpp), and the published
// poses' (pose_covariance.hpp), from the registrations and the information the fusion used. A
// registration without a covariance (singular) leaves the relative one out and carries the
// odometry one. Returns the frame-to-frame edge's calibrated covariance when there is one.
std::optional<core::Matrix6d> KeyframeOdometry::fill_covariances(const Registrations& r, bool from_new_keyframe,
                                                                 TrackStep& result) {
  const double factor = variance_factor_.value();
  const auto calibrated = [factor](const registration::RegistrationResult& e) -> std::optional<core::Matrix6d> {
    const auto sigma = registration::edge_covariance(e);
    if (!sigma) return std::nullopt;
    return factor * *sigma;
  };
  const auto f2f = r.f2f.converged ? calibrated(r.f2f) : std::nullopt;
  result.edge_covariance = from_new_keyframe ? f2f : calibrated(r.kf);
  PoseCovariances c;
  if (!result.edge_covariance) {
    c = track_unmeasured(covariance_chain_, false, from_new_keyframe);
  } else if (from_new_keyframe) {
    c = track_from_new_keyframe(covariance_chain_, r.f2f.transform, *result.edge_covariance);
  } else {
    std::optional<ChainTerm> chain;
    if (f2f && !r.chain_information.isZero(0)) {
      chain = ChainTerm{*f2f, r.chain_information, T_m_previous_};
      const core::Matrix6d Ad = T_m_previous_.adjoint();
      const core::Matrix6d S = *result.edge_covariance + Ad * *f2f * Ad.transpose() + covariance_chain_.previous_fused;
      add_disagreement(variance_factor_, factor * disagreement_chi2((r.chain * r.kf.transform.inverse()).log(), S));
    }
    c = track_against_keyframe(covariance_chain_, r.T_mn, *result.edge_covariance, r.kf.hessian, chain);
  }
  result.relative_covariance = c.relative;
  result.odometry_covariance = c.odometry;
  return f2f;
}

// The compensations at frame n's own motion (see the header): a first frame-to-frame registration
// measures T_{n-1}^n, and the frame is selected again with it; so is frame n-1 when it was
// selected without a motion (a session's first frame, the first after a failure). Returns where
// the frame-to-frame registration of those points starts: at ℓ_min from the first one's result,
// keeping its grid and candidate pairs when frame n-1's points stand (the same pixels, moved by
// millimetres, need no new search: registration.hpp, "Reuse"); or (nothing to compensate, or the
// first registration failed: the points stand) as without.
KeyframeOdometry::FrameStart KeyframeOdometry::select_with_own_motion(const core::RgbdFrame& frame,
                                                                      TrackResult& result) {
  const double dt = frame.timestamp - previous_timestamp_;
  if (!compensates(frame)) return {f2f_ell_start(dt)};
  const auto start = Clock::now();
  const auto first = registration_.align(clouds_[previous_], clouds_[current_], velocity_, f2f_ell_start(dt));
  result.frame_registration_ms = ms_since(start);
  if (!first.converged) return {f2f_ell_start(dt)};
  const auto selection_start = Clock::now();
  compensation_velocity_ = first.transform;
  compensation_dt_ = dt;
  if (reselect(frame, current_)) current_uncompensated_ = false;
  bool previous_stands = true;
  if (previous_uncompensated_) {
    previous_stands = false;
    if (reselect(previous_images_, previous_)) previous_uncompensated_ = false;
  }
  result.selection_ms += ms_since(selection_start);
  result.points = clouds_[current_].size();
  velocity_ = first.transform;
  return {parameters_.cvo.ell_min, previous_stands ? registration::Reuse::kCandidates : registration::Reuse::kNothing};
}

// `frame` selected again into clouds_[cloud] with the compensations' velocity; where that leaves
// too few points, as it was selected before (without a velocity, or with the last interval's).
bool KeyframeOdometry::reselect(const core::RgbdFrame& frame, int cloud) {
  const auto selection = selector_.reselect(frame, clouds_[cloud], colour_T_depth(frame), twist(frame));
  if (usable(selection.status) && clouds_[cloud].size() >= 3) return true;
  const core::SE3 velocity = std::exchange(compensation_velocity_, last_compensation_velocity_);
  const double dt = std::exchange(compensation_dt_, last_compensation_dt_);
  selector_.reselect(frame, clouds_[cloud], colour_T_depth(frame), twist(frame));
  compensation_velocity_ = velocity, compensation_dt_ = dt;
  return false;
}

// Where the frame-to-frame registration starts: ℓ_init (0: align()'s own start) after a measured
// motion. Without one (a session's first pair) the camera may already turn at full speed and no
// constant-velocity guess has taken that turn out of what the kernel must span: a pair farther
// apart than r_max(ℓ) never counts, so the registration starts at the ℓ whose reach covers the
// displacement ω dt z of a point at the previous cloud's mean depth z under the fastest turn ω
// (at most θ_thres: a larger turn leaves no keyframe to track against).
double KeyframeOdometry::f2f_ell_start(double dt) const {
  if (velocity_dt_ > 0) return 0.0;
  const double turn = std::min(core::radians(parameters_.tracking.max_turn_rate_deg_s) * std::max(dt, 0.0),
                               core::radians(parameters_.keyframe.rotation_threshold_deg));
  const double unit_reach = registration::kernel_reach(parameters_.cvo, 1.0);
  const double ell = unit_reach > 0 ? turn * mean_depth(clouds_[previous_]) / unit_reach : 0.0;
  return std::max(ell, parameters_.cvo.ell_init);
}

// A frame with a previous one: registered, then tracked against the keyframe, made the start of a
// new keyframe at n-1, or (neither registration converged) predicted and a restart; the motion
// model learns from what converged.
core::SE3 KeyframeOdometry::track_registered(const core::RgbdFrame& frame, const core::SE3& predicted,
                                             TrackStep& result) {
  const Registrations r = register_frame(result, select_with_own_motion(frame, result));
  const bool trip = keyframe_trips(r, result);
  core::SE3 pose = predicted;
  if (r.kf.converged && !trip) {
    pose = add_to_local_graph(frame, r, result);
  } else if (r.f2f.converged) {
    pose = keyframe_at_previous(frame, r, result);
  } else {
    start_keyframe(current_, frame.index, frame.timestamp, pose, KeyframeReason::kRestart);
    result.odometry_covariance = track_unmeasured(covariance_chain_, false, true).odometry;
    result.status = TrackStatus::kRegistrationFailed;
    result.keyframe = true;
  }
  result.motion = previous_pose_.inverse() * pose;
  if (r.f2f.converged || result.status == TrackStatus::kOk) velocity_dt_ = frame.timestamp - previous_timestamp_;
  if (r.f2f.converged)
    velocity_ = r.f2f.transform;
  else if (result.status == TrackStatus::kOk)
    velocity_ = result.motion;
  // The compensations' velocity: the published motion when this frame was tracked (see the header).
  compensation_velocity_ = result.status == TrackStatus::kOk ? result.motion : velocity_;
  compensation_dt_ = velocity_dt_;
  return pose;
}

// What the frame closed and made, and what it was tracked against (before the clouds' roles move
// on: a keyframe made at n-1 is the previous cloud and previous_images_ now).
void KeyframeOdometry::hand_out(const core::RgbdFrame& frame, TrackStep& step) const {
  step.keyframe_id = keyframe_id_;
  step.gamma = gamma_;
  step.reason = reason_;
  step.lost = reason_ == KeyframeReason::kRestart;
  if (graph_closed_) step.closed_graph = HandedLocalGraph{keyframe_id_ - 1, &graphs_[1 - graph_]};
  if (step.keyframe)
    step.new_keyframe = NewKeyframe{keyframe_id_, keyframe_ == previous_ ? previous_images_ : frame, keyframe_pose_,
                                    &clouds_[keyframe_]};
}

TrackStep KeyframeOdometry::track(const core::RgbdFrame& frame) {
  TrackStep result;
  reason_ = KeyframeReason::kNone;
  gamma_ = 0;
  graph_closed_ = false;
  add_stamp(motion_redundancy_.jitter, frame.timestamp);
  const core::SE3 predicted = have_frame_ ? last_pose_ * velocity_ : parameters_.initial_pose;

  const auto selection_start = Clock::now();
  const auto selection = selector_.select(frame, clouds_[current_], colour_T_depth(frame), twist(frame));
  result.selection_ms = ms_since(selection_start);
  current_uncompensated_ = compensates(frame) && !(compensation_dt_ > 0);
  last_compensation_velocity_ = compensation_velocity_, last_compensation_dt_ = compensation_dt_;
  result.selection_status = selection.status;
  result.points = clouds_[current_].size();

  if (!usable(selection.status) || clouds_[current_].size() < 3) {
    // No points: the prediction stands, and the next usable frame starts a new keyframe.
    result.status = TrackStatus::kSelectionFailed;
    result.odometry_covariance = track_unmeasured(covariance_chain_, false, false).odometry;
    result.pose = last_pose_ = predicted;
    result.smooth_pose = smooth(smooth_position_, frame.timestamp, predicted, std::nullopt).pose;
    result.motion = velocity_;
    motion_redundancy_.history = 0;  // no measured increment: the third differences start again
    have_frame_ = true;
    have_previous_ = false;
    hand_out(frame, result);
    return result;
  }

  core::SE3 pose;
  if (have_previous_) {
    pose = track_registered(frame, predicted, result);
  } else {
    // The first frame, or the first usable one after a failure: it is the keyframe.
    const bool first = !have_keyframe_;
    pose = first ? parameters_.initial_pose : predicted;
    start_keyframe(current_, frame.index, frame.timestamp, pose,
                   first ? KeyframeReason::kFirst : KeyframeReason::kRestart);
    result.odometry_covariance = track_unmeasured(covariance_chain_, first, true).odometry;
    result.status = first ? TrackStatus::kFirstFrame : TrackStatus::kRegistrationFailed;
    result.keyframe = true;
    result.motion = first ? core::SE3() : velocity_;
  }
  result.relative_covariance = publish_relative(motion_redundancy_, result.motion,
                                                frame.timestamp - previous_timestamp_, result.relative_covariance);
  const SmoothStep published = smooth(smooth_position_, frame.timestamp, pose, result.relative_covariance);
  result.smooth_pose = published.pose;
  result.relative_covariance = published.relative;

  result.pose = last_pose_ = pose;
  hand_out(frame, result);
  // The current frame becomes the previous one; the free cloud takes the next frame.
  previous_images_ = frame;  // its images are the caller's: a header copy
  previous_ = current_;
  previous_frame_ = frame.index;
  previous_timestamp_ = frame.timestamp;
  previous_uncompensated_ = current_uncompensated_;
  previous_pose_ = pose;
  T_m_previous_ = keyframe_pose_.inverse() * pose;
  have_previous_ = have_frame_ = true;
  for (int c = 0; c < 3; ++c)
    if (c != keyframe_ && c != previous_) current_ = c;
  return result;
}

}  // namespace cvo::odometry
