#pragma once
// Keyframe-based CVO odometry, KF-CVO (paper section 4). For each new frame n, with keyframe m:
//
//   frame-to-frame     T_{n-1}^n = argmax <f_X(n-1), h.f_Xn>   from h_0 = T_{n-2}^{n-1}   (eq. 7)
//   keyframe-to-frame  T_m^n     = argmax <f_Xm,     h.f_Xn>   from h_0 = T_m^{n-1} T_{n-1}^n (eq. 8)
//   pose               P_n = P_m T̄_m^n, T̄_m^n the keyframe result fused with the chain (below)
//   keyframe test      γ = <f_Xm, T_m^n.f_Xn> / <f_Xm, T_m^{m+1}.f_X(m+1)>                  (eq. 9)
//                      with θ_mn = arccos((tr R_mn - 1)/2) and |t_mn|                       (eq. 10)
//
// (T_a^b is frame b's camera in frame a's camera frame.) When γ < γ_thres, |t_mn| > t_thres or
// θ_mn > θ_thres, frame n-1 becomes the new keyframe, as in the paper: its local graph is closed
// and handed out, and frame n is then re-expressed against it with the frame-to-frame result
// (T_{n-1}^n is exactly its keyframe-to-frame transform), which also gives the new γ reference.
//
// Fusion with the chain. The published T̄_m^n is the keyframe result T_m^n pulled toward the
// chained estimate C = T_m^{n-1} T_{n-1}^n: the one-node pose graph of the paper's local graph
// (keyframe and frame n-1 held fixed, the keyframe→n and (n-1)→n edges weighted by their CVO
// Hessians), solved in closed form in the tangent space at T_m^n. The chain edge's weight is
// chain_weight, or, with chain_full_weight_deg > 0, ramps as (θ / chain_full_weight_deg)² up to
// it, θ the rotation from the keyframe: keyframe-to-frame registrations across large rotations
// err by more than their Hessians show, while on rendered data the keyframe edge alone is the more
// accurate near the keyframe. A short ramp serves real sensors, where a keyframe registration of a
// few dozen kernel pairs left alone jitters by centimetres; the chain's drift then enters sooner
// on exact rendered data (the values tried and their figures: bench/odometry-tuning.md). Local
// graph edges keep the raw measurements; γ and the thresholds use the fused T̄_m^n.
//
// Depth-time compensation: the colour and depth images of a Kinect are not taken together (TUM
// stamps differ by up to ±17 ms, plus SelectionParameters::depth_time_offset_s). Each frame's
// points are selected with colour_T_depth, the velocity (below) scaled to that interval
// (PointSelector::select explains the rest); what it gains on fr1/rpy: bench/odometry-tuning.md.
// The velocity of both compensations (depth time, rolling shutter) is frame n's own motion. The
// frame is first selected with the published motion of the last interval, P_{n-2}^{-1} P_{n-1}
// (not the last frame-to-frame registration alone, whose error would move the next frame's points
// and through them the next velocity: the increments would jitter); a frame-to-frame registration
// from the last frame-to-frame result measures T_{n-1}^n on those points; and the frame is selected
// again with that (its pixels back-projected anew, PointSelector::reselect). A camera that turns
// faster or slower than in the last interval (a hand-held camera's shaking) is compensated for the
// motion it has, not the one it had 1.5 frames before. Both registrations then run on the second
// selection, the frame-to-frame one from the first's result at ℓ_min. A frame with nothing to
// compensate (a global shutter, depth stamped with the colour) is selected and registered once.
//
// A session's first pair has no constant-velocity guess: the camera may already turn at full speed,
// and a kernel at ℓ_init reaches only pairs 6 cm apart (registration::kernel_reach), a 2-degree turn
// at 2 m. That pair starts at the ℓ whose reach covers the fastest turn over the frame interval at
// the scene's mean depth (KeyframeTrackingParameters::max_turn_rate_deg_s); the pair budget keeps
// the wide kernel's cost that of a frame. Later frames start at ℓ_init from the prediction.
//
// Failures never crash and never jump: a frame whose points cannot be selected, or whose two
// registrations both fail, keeps the constant-velocity prediction, is marked, and the next usable
// frame starts a new keyframe at its predicted pose. When only the keyframe registration fails
// (the keyframe has left the view), frame n-1 becomes the keyframe as above.
//
// Fixed memory: three clouds (keyframe, previous, current) whose roles rotate by index, one
// solver, a local graph with a capacity; after the first frames track() does not allocate.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/odometry/local_graph.hpp"
#include "libcvo/odometry/motion_redundancy.hpp"
#include "libcvo/odometry/pose_covariance.hpp"
#include "libcvo/odometry/smooth_position.hpp"
#include "libcvo/odometry/track_result.hpp"
#include "libcvo/odometry/variance_factor.hpp"
#include "libcvo/registration/point_cloud.hpp"
#include "libcvo/registration/point_selection.hpp"
#include "libcvo/registration/registration.hpp"

namespace cvo::odometry {

/// The core structs whole (libcvo/core/parameters.hpp has the defaults and the why of each
/// value). From the configuration: config::keyframe_odometry_parameters
/// (libcvo/config/module_parameters.hpp).
struct KeyframeOdometryParameters {
  core::SelectionParameters selection;
  core::CvoParameters cvo;
  core::KeyframeParameters keyframe;          // the paper's thresholds
  core::KeyframeTrackingParameters tracking;  // γ's kernel, the local graph's capacity, the fusion
  core::OdometryParameters odometry;          // max_points: capacity of each cloud
  core::SE3 initial_pose;                     // P of the first usable frame
};

/// Why a frame made a new keyframe.
enum class KeyframeReason { kNone, kFirst, kGamma, kTranslation, kRotation, kKeyframeLost, kRestart, kGraphFull };
const char* to_string(KeyframeReason reason);

/// A local graph handed out, named by its keyframe's id in the session. The graph is the
/// tracker's: it stays valid until the tracker's next track() or reset().
struct HandedLocalGraph {
  std::int64_t keyframe_id = -1;
  const LocalGraph* graph = nullptr;
};

/// A keyframe a frame made: frame n itself (the first frame, a restart) or frame n-1 (the paper's
/// rule). `frame` shares the caller's images (a cv::Mat header, no pixel copy): the caller keeps
/// frame n-1's images unchanged until the track() of frame n has returned and its step was used
/// (cvo-trackerd releases a ring slot one frame late for that). `cloud` is the tracker's, valid
/// until its next track().
struct NewKeyframe {
  std::int64_t id = -1;  // from 0 in every session
  core::RgbdFrame frame;
  core::SE3 pose;                                   // T_odom_keyframe: the anchor of the local graph it opens
  const registration::PointCloud* cloud = nullptr;  // its CVO points, in its camera frame
};

/// Everything one track() gives its caller, so that nobody asks the tracker a second time.
struct TrackStep : TrackResult {
  std::int64_t keyframe_id = -1;                  // the keyframe this frame is tracked against (-1 before the first)
  double gamma = 0;                               // γ of this frame (eq. 9); 0 when no keyframe registration ran
  KeyframeReason reason = KeyframeReason::kNone;  // why this frame made a keyframe
  // Covariance of this frame's keyframe→frame edge T_m^n (edge_covariance.hpp: the sandwich of
  // its registration, left perturbation in the keyframe's frame, [translation, rotation]); none
  // for a frame without one (a first frame, a restart, a failure).
  std::optional<core::Matrix6d> edge_covariance;
  // The odometry failed: this frame could not be registered (or is the first usable one after
  // frames without points), so its pose is a guess and the session's odometry frame is broken here
  // (a camera carried elsewhere, covered, shaken). The caller ends the session (finish(), reset())
  // and tracks the next frame as the first of a new one, which the back end localizes afresh.
  bool lost = false;
  // Covariance of the published relative pose T_{n-1}^n = S_{n-1}⁻¹ S_n, S the smooth pose,
  // right perturbation (T = T̄ exp(ξ)), [rho; phi] as core::SE3: the tracked relative pose's
  // (pose_covariance.hpp has the maths), completed with what the smooth motion and the stamps
  // reveal (motion_redundancy.hpp), its translation block the filter's (smooth_position.hpp);
  // none for a frame without a measured motion (the first frame, a restart, a failure).
  std::optional<core::Matrix6d> relative_covariance;
  // Covariance of the published odometry pose P_n, right perturbation, accumulated along the
  // keyframe chain since the session's first frame (zero there); carried unchanged by a failure.
  core::Matrix6d odometry_covariance = core::Matrix6d::Zero();
  std::optional<HandedLocalGraph> closed_graph;  // the local graph this frame closed
  std::optional<NewKeyframe> new_keyframe;       // the keyframe this frame made
};

class KeyframeOdometry {
 public:
  KeyframeOdometry(int width, int height, const KeyframeOdometryParameters& parameters);

  /// Tracks the next frame. Never throws on bad frames: see TrackResult::status. Its images must
  /// stay unchanged until the next track() has returned (NewKeyframe says why).
  TrackStep track(const core::RgbdFrame& frame);

  /// Ends the session: hands out the open local graph (its keyframe and the frames tracked
  /// against it, so the back end has every tracked frame; nullopt when none is open), valid until
  /// the next track() or reset(), and the next frame starts a new session as after reset().
  std::optional<HandedLocalGraph> finish();

  /// Back to the state of a new tracker: the next frame is the first (at
  /// parameters().initial_pose, a new keyframe, id 0), no graph is open or closed. For a camera
  /// that was re-initialised (a new session); every buffer is kept, so it does not allocate.
  void reset();

  [[nodiscard]] const KeyframeOdometryParameters& parameters() const { return parameters_; }

 private:
  // Frame n's two registrations (eq. 7, 8) and T̄_m^n, the keyframe result fused with the chain.
  struct Registrations {
    registration::RegistrationResult f2f, kf;
    core::SE3 chain, T_mn;
    core::Matrix6d chain_information = core::Matrix6d::Zero();  // what the fusion gave the chain (0: not fused)
  };
  // Where the frame-to-frame registration starts: its first length-scale (0: ℓ_init) and what it
  // keeps of the registration before it.
  struct FrameStart {
    double ell = 0;
    registration::Reuse reuse = registration::Reuse::kNothing;
  };
  Registrations register_frame(TrackResult& result, const FrameStart& f2f_start);
  FrameStart select_with_own_motion(const core::RgbdFrame& frame, TrackResult& result);
  bool reselect(const core::RgbdFrame& frame, int cloud);
  [[nodiscard]] double f2f_ell_start(double dt) const;
  bool keyframe_trips(const Registrations& r, TrackResult& result);
  core::SE3 track_registered(const core::RgbdFrame& frame, const core::SE3& predicted, TrackStep& result);
  core::SE3 add_to_local_graph(const core::RgbdFrame& frame, const Registrations& r, TrackStep& result);
  core::SE3 keyframe_at_previous(const core::RgbdFrame& frame, const Registrations& r, TrackStep& result);
  void start_keyframe(int cloud, std::uint64_t index, double timestamp, const core::SE3& pose, KeyframeReason why);
  void hand_out(const core::RgbdFrame& frame, TrackStep& step) const;
  void start_over();
  bool trips_threshold(const core::SE3& T_mn, double gamma);
  double gamma_inner_product(const registration::PointCloud& keyframe, const core::SE3& T_mn);
  [[nodiscard]] core::SE3 colour_T_depth(const core::RgbdFrame& frame) const;
  [[nodiscard]] core::Vector6d twist(const core::RgbdFrame& frame) const;
  core::SE3 fuse_with_chain(const registration::RegistrationResult& kf, const registration::RegistrationResult& f2f,
                            const core::SE3& chain, core::Matrix6d& chain_information) const;
  std::optional<core::Matrix6d> fill_covariances(const Registrations& r, bool from_new_keyframe, TrackStep& result);

  KeyframeOdometryParameters parameters_;
  registration::PointSelector selector_;
  registration::Registration registration_;
  registration::Registration gamma_registration_;  // the same kernel, looser sparsification (γ only)
  std::array<registration::PointCloud, 3> clouds_;
  int keyframe_ = 0, previous_ = 1, current_ = 2;  // roles of clouds_
  bool have_keyframe_ = false, have_previous_ = false, have_frame_ = false;

  std::uint64_t keyframe_frame_ = 0;
  core::SE3 keyframe_pose_;
  double gamma_reference_ = 0;  // <f_Xm, T_m^{m+1}.f_X(m+1)>; 0 until frame m+1 is tracked
  double gamma_ = 0;
  KeyframeReason reason_ = KeyframeReason::kNone;

  std::uint64_t previous_frame_ = 0;
  double previous_timestamp_ = 0;
  core::SE3 previous_pose_;               // P_{n-1}
  core::SE3 T_m_previous_;                // T_m^{n-1}
  core::SE3 velocity_;                    // T_{n-2}^{n-1}
  double velocity_dt_ = 0;                // colour-stamp seconds velocity_ spans; 0: none yet
  core::SE3 compensation_velocity_;       // the compensations' velocity (see the header)
  double compensation_dt_ = 0;            // colour-stamp seconds it spans; 0: none yet
  core::SE3 last_compensation_velocity_;  // what the current frame was first selected with
  double last_compensation_dt_ = 0;
  bool current_uncompensated_ = false;   // the current frame needs compensation and had no velocity
  bool previous_uncompensated_ = false;  // ... the previous frame (see select_with_own_motion)
  core::SE3 last_pose_;                  // the last published pose (tracked or predicted)
  PoseCovarianceChain covariance_chain_;
  VarianceFactor variance_factor_;      // of this session's registrations (variance_factor.hpp)
  MotionRedundancy motion_redundancy_;  // of its tracked increments (motion_redundancy.hpp)
  SmoothPosition smooth_position_;      // the published pose's filter (smooth_position.hpp)

  // The previous frame (n-1), sharing the caller's images: the keyframe when one is made at n-1.
  core::RgbdFrame previous_images_;

  std::array<LocalGraph, 2> graphs_;  // [graph_] is open, the other the last closed one
  int graph_ = 0;
  bool graph_closed_ = false;      // by the last track()
  std::int64_t keyframe_id_ = -1;  // of the current keyframe, from 0 in the session
};

}  // namespace cvo::odometry
