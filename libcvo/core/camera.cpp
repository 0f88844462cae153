#include "libcvo/core/camera.hpp"

#include <array>
#include <cmath>

namespace cvo::core {
namespace {

struct Preset {
  std::string_view name;
  Intrinsics intrinsics;
};

// The Kinect (v1)'s rolling-shutter readout, not published: measured on TUM fr1/rpy (see camera.hpp).
constexpr double kKinectReadout = 0.02;

// TUM values from the benchmark's "file formats / intrinsic camera calibration" page (d0 d1 d2 d3
// d4 there are OpenCV's k1 k2 p1 p2 k3).
constexpr std::array kPresets{
    Preset{"tum_fr1",
           {517.3, 516.5, 318.6, 255.3, 640, 480, 5000.0, {0.2624, -0.9531, -0.0054, 0.0026, 1.1633}, kKinectReadout}},
    Preset{"tum_fr2",
           {520.9, 521.0, 325.1, 249.7, 640, 480, 5000.0, {0.2312, -0.7849, -0.0033, -0.0001, 0.9172}, kKinectReadout}},
    Preset{"tum_fr3", {535.4, 539.2, 320.1, 247.6, 640, 480, 5000.0}},
    Preset{"synthetic", {525.0, 525.0, 319.5, 239.5, 640, 480, 5000.0}},
};

bool positive_finite(double v) { return std::isfinite(v) && v > 0; }

}  // namespace

std::string Intrinsics::validate() const {
  if (!positive_finite(fx)) return "fx must be a positive number";
  if (!positive_finite(fy)) return "fy must be a positive number";
  if (!std::isfinite(cx)) return "cx must be a finite number";
  if (!std::isfinite(cy)) return "cy must be a finite number";
  if (width <= 0 || width > 16384) return "width must be in 1..16384";
  if (height <= 0 || height > 16384) return "height must be in 1..16384";
  if (!positive_finite(depth_scale)) return "depth_scale must be a positive number";
  if (!(std::isfinite(readout_s) && readout_s >= 0 && readout_s < 1))
    return "readout_s must be a number of seconds in [0, 1)";
  for (const double c : distortion)
    if (!std::isfinite(c)) return "distortion must be finite numbers (k1 k2 p1 p2 k3)";
  return {};
}

std::optional<Intrinsics> camera_preset(std::string_view name) {
  for (const auto& p : kPresets)
    if (p.name == name) return p.intrinsics;
  return std::nullopt;
}

std::vector<std::string> camera_preset_names() {
  std::vector<std::string> names;
  for (const auto& p : kPresets) names.emplace_back(p.name);
  return names;
}

}  // namespace cvo::core
