#pragma once
// The peer a user would pick instead of CVO: OpenCV contrib's dense RGB-D odometry (module rgbd),
// run frame to frame on the same frames and reported through the same TrackResult, so cvo-run
// measures every mode side by side.
//
//   rgbd      cv::rgbd::RgbdOdometry: photometric (Steinbruecker, Sturm, Cremers, ICCV 2011)
//   rgbd_icp  cv::rgbd::RgbdICPOdometry: the photometric and the point-to-plane ICP energies summed
//
// Each frame is converted once (grey CV_8UC1 from BGR; depth CV_32FC1 in metres, no measurement =
// NaN as OpenCV's own TUM sample does) and its OpenCV cache (pyramids, gradients, normals) is
// prepared for both roles; the reference frame's cache is then reused as the source of the next
// registration (two frames, swapped by index). The camera matrix comes from the intrinsics.
//
// Convention: OpenCV's compute(src, dst, Rt, initRt) returns Rt with p_dst = Rt p_src. With
// src = the reference r and dst = the current frame k, Rt = T_k_r; the motion is T_r_k = Rt⁻¹.
// The motion model, the prediction and the failure policy are those of FrameToFrameOdometry
// (frame_to_frame.hpp): the guess is T_0 = P_r⁻¹ P̂_k with P̂_k = P_{k-1} V^n, so initRt = T_0⁻¹;
// a failed frame keeps P̂_k, is marked, and the reference stays until `restart_after_failures`
// failures in a row. compute() returning false (too few correspondences, a singular system, or a
// step from the guess beyond OpenCV's limits of 0.15 m / 15 degrees) is kRegistrationFailed with
// registration_status kNoOverlap when no step was taken and kNotConverged when a step was
// rejected. OpenCV reports no iteration count: iterations stays 0.
//
// Not allocation-free (OpenCV allocates its pyramids per frame); it is a reference, not the product.
#include <cstdint>
#include <memory>

#include "libcvo/core/camera.hpp"
#include "libcvo/core/parameters.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/odometry/track_result.hpp"

namespace cvo::odometry {

enum class OpenCvVariant { rgbd, rgbd_icp };
const char* to_string(OpenCvVariant variant);

struct OpenCvOdometryParameters {
  OpenCvVariant variant = OpenCvVariant::rgbd;
  // Of the core structs (libcvo/core/parameters.hpp) only selection's min_depth_m and max_depth_m,
  // the valid depth range (OpenCV's own defaults: 0 and 4), and odometry's restart_after_failures
  // (as FrameToFrameParameters) apply. From the configuration: config::opencv_odometry_parameters.
  core::SelectionParameters selection;
  core::OdometryParameters odometry;
  core::SE3 initial_pose;  // P of the first usable frame
  // Everything else is OpenCV's default: 4 pyramid levels with 7/7/7/10 iterations, gradient
  // magnitude >= 10, max depth difference 0.07 m, 7% of the pixels, max step 0.15 m and 15 deg.
};

class OpenCvOdometry {
 public:
  /// Frames must be camera.width x camera.height; their depth is in camera.depth_scale units.
  OpenCvOdometry(const core::Intrinsics& camera, const OpenCvOdometryParameters& parameters);
  ~OpenCvOdometry();
  OpenCvOdometry(OpenCvOdometry&&) noexcept;
  OpenCvOdometry& operator=(OpenCvOdometry&&) noexcept;

  /// Tracks the next frame of the stream. Never throws on bad frames: see TrackResult::status.
  /// `points` is the number of pixels OpenCV samples in this frame (its textured pixels, plus for
  /// rgbd_icp its pixels with a normal, at full resolution); selection_ms is the conversion and
  /// the cache, registration_ms the compute() call.
  TrackResult track(const core::RgbdFrame& frame);

  [[nodiscard]] const OpenCvOdometryParameters& parameters() const;

 private:
  struct State;  // OpenCV's types stay out of this header (opencv_rgbd is linked privately)
  std::unique_ptr<State> state_;
};

}  // namespace cvo::odometry
