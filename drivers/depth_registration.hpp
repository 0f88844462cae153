#pragma once
// Depth registration for cameras whose depth is a separate sensor (RealSense and most UVC depth
// cameras): each depth pixel is moved into the colour camera, so that the frame leaving the
// driver holds depth registered to colour as every consumer expects (core/camera.hpp).
//
// For a depth pixel (u, v) with raw value r of the depth sensor D (intrinsics K_d with lens
// distortion, raw units s_d per metre), and each corner c of the pixel's footprint, the
// corners (u - 1/2, v - 1/2) and (u + 1/2, v + 1/2):
//     (x, y) = undistort(K_d^-1 c)               the corner's normalised ray, computed once
//     X_d    = (r / s_d) (x, y, 1)               its point at the pixel's depth, in D's frame
//     X_c    = T_colour_depth X_d                the point in the colour camera's frame
//     c'     = K_c distort(X_c / z_c)            where the corner lands in the colour image
// and every colour pixel whose centre lies between the two corners' landing points (the first
// included, the second not, so that footprints tiling the depth image cover each colour pixel
// once) takes z_c of the pixel's centre,
// round(z_c s_c), unless a nearer point already landed there (a z-buffer: the nearer surface
// occludes). This is librealsense's align: a depth pixel covers the colour pixels its footprint
// covers, so a depth sensor with coarser angular resolution than the colour camera leaves no
// hole grid. Colour pixels that no depth pixel covers stay 0 ("no measurement"): occluded or
// unmeasured parts are left empty, never filled by interpolation. Points behind the colour camera
// are dropped, footprints are clipped to the colour image.
//
// All memory is taken at construction (the corner rays); apply() allocates nothing once its
// output has the colour camera's size, so it runs in the tracker's acquisition thread.
#include <optional>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "libcvo/core/camera.hpp"
#include "libcvo/core/depth_sensor.hpp"

namespace cvo::drivers {

class DepthRegistration {
 public:
  /// Throws std::invalid_argument when either camera's intrinsics do not validate.
  DepthRegistration(const core::DepthSensor& depth, const core::Intrinsics& colour);

  /// depth: CV_16UC1 of the depth sensor's size (std::invalid_argument otherwise); registered:
  /// CV_16UC1 of the colour camera's size ((re)allocated only when it is not).
  void apply(const cv::Mat& depth, cv::Mat& registered) const;

 private:
  std::optional<Eigen::Vector3f> land(const float* ray, float z) const;

  core::DepthSensor depth_;
  core::Intrinsics colour_;
  // R_colour_depth (x, y, 1) of the (width + 1) x (height + 1) pixel corners of the depth sensor
  std::vector<float> corners_;
  Eigen::Vector3f t_;
};

}  // namespace cvo::drivers
