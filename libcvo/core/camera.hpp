#pragma once
// Pinhole intrinsics of an RGB-D camera whose depth is registered to colour.
//   u = fx * x / z + cx,  v = fy * y / z + cy,  depth_metres = raw_depth / depth_scale.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cvo::core {

struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
  double depth_scale = 5000.0;  // raw 16-bit depth units per metre (TUM: 5000)

  /// Empty when valid, else a message naming the bad field.
  [[nodiscard]] std::string validate() const;
};

/// Named presets: "tum_fr1", "tum_fr2", "tum_fr3" (TUM RGB-D benchmark calibrations, 640x480,
/// 5000 units/m; distortion is ignored as the benchmark's own tools do) and "synthetic" (the
/// renderer's default camera).
std::optional<Intrinsics> camera_preset(std::string_view name);
std::vector<std::string> camera_preset_names();

}  // namespace cvo::core
