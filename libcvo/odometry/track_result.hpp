#pragma once
// What a tracker reports for one frame. Every odometry mode (frame-to-frame CVO now; keyframe CVO
// and the OpenCV baselines later) fills the same value, so tools and tests handle them alike.
//
// A frame that could not be tracked still gets a pose: the constant-velocity prediction. It is
// marked by its status, so the caller can tell a measured pose from a guessed one; the pose never
// jumps silently.
#include <cstddef>
#include <optional>

#include "libcvo/core/se3.hpp"
#include "libcvo/registration/point_selection.hpp"
#include "libcvo/registration/registration.hpp"

namespace cvo::odometry {

enum class TrackStatus {
  kOk,                  // registered against the previous frame
  kFirstFrame,          // the first usable frame: it defines the world frame (or the initial pose)
  kSelectionFailed,     // no usable points (no image, no valid depth): pose predicted
  kRegistrationFailed,  // registration did not converge or failed: pose predicted
};
const char* to_string(TrackStatus status);

struct TrackResult {
  TrackStatus status = TrackStatus::kFirstFrame;
  core::SE3 pose;  // T_world_camera of this frame, as tracked
  // The pose a controller reads, where a tracker smooths it (KF-CVO: the tracked rotation, the
  // position through smooth_position.hpp's filter); none: `pose` is published as it is.
  std::optional<core::SE3> smooth_pose;
  core::SE3 motion;       // T_previous_current: this camera in the frame of the previous frame's camera
  bool keyframe = false;  // a new keyframe was made (never in frame-to-frame mode: it has none)
  registration::SelectionStatus selection_status = registration::SelectionStatus::kOk;
  registration::RegistrationStatus registration_status = registration::RegistrationStatus::kOk;
  std::size_t points = 0;      // points selected in this frame
  int iterations = 0;          // solver iterations (0 when no registration ran)
  double inner_product = 0;    // F(T) of the registration at ℓ_min (0 when none ran)
  double selection_ms = 0;     // wall time of point selection
  double registration_ms = 0;  // wall time of registration (every align() of the frame, and fusion)
  // KF-CVO's stages (0 where a mode has none; bench/odometry_stages tabulates them):
  double frame_registration_ms = 0;     // the frame-to-frame align() (eq. 7)
  double keyframe_registration_ms = 0;  // the keyframe-to-frame align() (eq. 8)
  double gamma_ms = 0;                  // the inner products of γ (eq. 9)

  /// What the tracker publishes for this frame (cvo-run --out, CVO_POSE's odom_pose).
  [[nodiscard]] const core::SE3& published_pose() const { return smooth_pose ? *smooth_pose : pose; }

  /// The pose was measured (or is the first frame's), not predicted.
  [[nodiscard]] bool tracked() const { return status == TrackStatus::kOk || status == TrackStatus::kFirstFrame; }
};

}  // namespace cvo::odometry
