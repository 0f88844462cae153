#pragma once
// Frame-to-frame CVO odometry, the paper's baseline (section 4, eq. 7): each frame is registered
// against the previous one, starting from the previous relative motion (constant velocity).
//
// With P_k = T_world_camera of frame k, V the last measured per-frame motion and X the point cloud
// of the reference frame r (the last frame whose points could be selected, normally k - 1):
//
//   prediction    P̂_k = P_{k-1} V^n                 n = index gap to the previous frame (1 normally)
//   registration  T   = argmax_T <f_X, T.f_Z_k>      from T_0 = P_r⁻¹ P̂_k  (= V when r = k - 1)
//   pose          P_k = P_r T
//   velocity      V   = T^(1/m)                      m = frames from r to k (1 normally)
//
// V^s = exp(s log V). With no gaps this is exactly eq. 7: T_0 = T_{k-2,k-1}. Gaps in the frame
// index (frames the reader dropped) scale the guess so it still predicts a constant velocity.
// When selection or registration fails the frame keeps the prediction P̂_k, is marked, and V is
// kept. The reference stays: a measured cloud at a measured pose is a better target than a
// failed frame's cloud at a guessed one, and the next frame's guess is the same either way
// (P_r V^2 = P̂_k V). Only after `restart_after_failures` registrations in a row have failed
// against it does the failed frame become the reference, at P̂_k, so tracking can restart once
// the old reference is out of view.
//
// Fixed memory: the selector, the solver and two clouds are allocated at construction; after the
// first frames track() performs no heap allocation.
#include <array>
#include <cstddef>
#include <cstdint>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/odometry/motion_model.hpp"
#include "libcvo/odometry/track_result.hpp"
#include "libcvo/registration/point_cloud.hpp"
#include "libcvo/registration/point_selection.hpp"
#include "libcvo/registration/registration.hpp"

namespace cvo::odometry {

/// The core structs whole (libcvo/core/parameters.hpp). From the configuration:
/// config::frame_to_frame_parameters (libcvo/config/module_parameters.hpp).
struct FrameToFrameParameters {
  core::SelectionParameters selection;
  core::CvoParameters cvo;
  core::OdometryParameters odometry;  // max_points (each cloud's capacity), restart_after_failures (above)
  core::SE3 initial_pose;             // P of the first usable frame
};

class FrameToFrameOdometry {
 public:
  /// Frames must be width x height (the camera's image size).
  FrameToFrameOdometry(int width, int height, const FrameToFrameParameters& parameters);

  /// Tracks the next frame of the stream. Never throws on bad frames: see TrackResult::status.
  TrackResult track(const core::RgbdFrame& frame);

  [[nodiscard]] const FrameToFrameParameters& parameters() const { return parameters_; }

 private:
  FrameToFrameParameters parameters_;
  registration::PointSelector selector_;
  registration::Registration registration_;
  std::array<registration::PointCloud, 2> clouds_;  // slots of MotionModel: reference and current
  MotionModel motion_;
};

}  // namespace cvo::odometry
