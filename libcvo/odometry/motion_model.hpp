#pragma once
// The constant-velocity motion model and reference policy of the frame-to-frame trackers (CVO and
// the OpenCV peers; see frame_to_frame.hpp for the equations). With P_k = T_world_camera of
// frame k, V the last measured per-frame motion and r the reference frame:
//
//   prediction  P̂_k = P_{k-1} V^n        n = index gap to the previous frame (1 normally)
//   guess       T_0 = P_r⁻¹ P̂_k          handed to the registration
//   measured    P_k = P_r T,  V = T^(1/m), m = frames from r to k; k becomes the reference
//   failed      P_k = P̂_k, V kept; after `restart_after_failures` failures in a row against the
//               same reference, the failed frame becomes the reference
//
// V^s = exp(s log V). The trackers own the images or clouds in two slots; this class says which
// slot is the reference and which takes the next frame.
#include <cstdint>

#include "libcvo/core/se3.hpp"
#include "libcvo/odometry/track_result.hpp"

namespace cvo::odometry {

class MotionModel {
 public:
  MotionModel(const core::SE3& initial_pose, int restart_after_failures)
      : last_pose_(initial_pose), restart_after_failures_(restart_after_failures) {}

  /// P̂ for the frame with stream index `index`.
  [[nodiscard]] core::SE3 predict(std::uint64_t index) const;
  /// The guess of T_r_k for a frame predicted at `predicted`.
  [[nodiscard]] core::SE3 guess(const core::SE3& predicted) const { return reference_pose_.inverse() * predicted; }

  [[nodiscard]] bool has_reference() const { return have_reference_; }
  [[nodiscard]] int reference_slot() const { return reference_; }
  /// Where the new frame's data goes: the slot that is not the reference.
  [[nodiscard]] int current_slot() const { return have_reference_ ? 1 - reference_ : reference_; }

  /// Completes result.pose and result.motion from result.status (kOk needs `measured` = T_r_k)
  /// and advances the model to frame `index`.
  void update(std::uint64_t index, const core::SE3& predicted, const core::SE3& measured, TrackResult& result);

 private:
  core::SE3 last_pose_;
  std::uint64_t last_index_ = 0;
  bool have_frame_ = false;
  core::SE3 velocity_;  // V, per frame
  int reference_ = 0;
  bool have_reference_ = false;
  core::SE3 reference_pose_;
  std::uint64_t reference_index_ = 0;
  int failures_on_reference_ = 0;
  int restart_after_failures_;
};

}  // namespace cvo::odometry
