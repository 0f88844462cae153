#pragma once
// Intrinsics of an RGB-D camera whose depth is registered to colour: a pinhole with Brown–Conrady
// lens distortion, as OpenCV models it (cv::projectPoints, cv::undistortPoints):
//   x' = x / z,  y' = y / z,  r² = x'² + y'²
//   x'' = x' (1 + k1 r² + k2 r⁴ + k3 r⁶) + 2 p1 x'y' + p2 (r² + 2 x'²)
//   y'' = y' (1 + k1 r² + k2 r⁴ + k3 r⁶) + p1 (r² + 2 y'²) + 2 p2 x'y'
//   u = fx x'' + cx,  v = fy y'' + cy,  depth_metres = raw_depth / depth_scale.
// All coefficients zero is the plain pinhole u = fx x / z + cx. Depth is registered in the same
// (distorted) colour image, and its value is z, the distance along the optical axis.
//
// Rolling shutter: a sensor that reads its rows one after another sees row v at
//   t(v) = t_frame + readout_s (v / (height - 1) - 1/2),
// the frame's stamp being its middle row's time; readout_s = 0 is a global shutter. A camera
// turning at ω rad/s shears and stretches its image by about ω · readout_s between the first row and
// the last (the trackers undo it with their motion model: point_selection.hpp).
#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cvo::core {

struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
  double depth_scale = 5000.0;  // raw 16-bit depth units per metre (TUM: 5000)
  // k1, k2, p1, p2, k3 in OpenCV's order (its distCoeffs for 5 coefficients); zeros: none.
  std::array<double, 5> distortion{};
  double readout_s = 0;  // rolling shutter: first row to last row (s); 0 = global shutter

  /// The same camera: every field equal. Whoever carries an Intrinsics (a message, a file) carries
  /// every field, so that this holds after the trip (tests/lcm/intrinsics_round_trip_test.cpp).
  bool operator==(const Intrinsics&) const = default;

  [[nodiscard]] bool rolling_shutter() const { return readout_s > 0; }

  [[nodiscard]] bool has_distortion() const {
    for (const double c : distortion)
      if (c != 0) return true;
    return false;
  }

  /// Empty when valid, else a message naming the bad field.
  [[nodiscard]] std::string validate() const;
};

/// The lens model above on a normalised point: (x', y') -> (x'', y''), coefficients k1 k2 p1 p2 k3
/// (Intrinsics::distortion). T = float in per-pixel loops.
template <typename T>
std::array<T, 2> distort(const std::array<double, 5>& d, T x, T y) {
  const T k1 = static_cast<T>(d[0]), k2 = static_cast<T>(d[1]), p1 = static_cast<T>(d[2]), p2 = static_cast<T>(d[3]),
          k3 = static_cast<T>(d[4]);
  const T r2 = x * x + y * y, radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
  return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x), y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
}

/// Named presets: "tum_fr1", "tum_fr2", "tum_fr3" (TUM RGB-D benchmark calibrations, 640x480,
/// 5000 units/m, with the published distortion of fr1 and fr2, whose images are distorted; fr3's
/// images were undistorted before release, so its coefficients are zero) and "synthetic" (the
/// renderer's default camera, distortion-free, global shutter). fr1 and fr2 are Kinects (v1)
/// with rolling shutters; their readout (not published by TUM) is measured here, chosen on one half
/// of fr1/rpy and confirmed on the other, within a 30 Hz frame's 33 ms (bench/odometry-tuning.md).
std::optional<Intrinsics> camera_preset(std::string_view name);
std::vector<std::string> camera_preset_names();

}  // namespace cvo::core
