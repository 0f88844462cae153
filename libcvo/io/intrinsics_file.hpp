#pragma once
// Camera intrinsics from a file, or by preset name.
//
// Two file formats are accepted, told apart by their content:
//   - YAML, a mapping with keys fx, fy, cx, cy, width, height (required), depth_scale
//     (optional, raw depth units per metre, default 5000 as TUM) and k1, k2, p1, p2, k3
//     (optional, each absent one 0: OpenCV's Brown–Conrady lens distortion, core/camera.hpp):
//         fx: 517.3
//         fy: 516.5
//         ...
//         k1: 0.2624
//     A camera whose depth is a separate sensor (RealSense, most UVC depth cameras) adds a
//     depth_sensor mapping: the depth sensor's own intrinsics (the same keys) and its pose in the
//     colour camera's frame, T_colour_depth: [tx, ty, tz, qx, qy, qz, qw] (TUM's order):
//         depth_sensor:
//           fx: 425.0
//           ...
//           T_colour_depth: [-0.015, 0, 0, 0, 0, 0, 1]
//   - ETH3D's calibration.txt: a single line "fx fy cx cy". It gives no image size, so width and
//     height are returned as 0, meaning "take them from the images" (TumSequence does).
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "libcvo/core/camera.hpp"
#include "libcvo/core/depth_sensor.hpp"

namespace cvo::io {

/// A camera file: the colour camera (to which depth is registered), and the depth sensor when the
/// camera's depth is a separate sensor whose depth the driver registers.
struct CameraFile {
  core::Intrinsics colour;
  std::optional<core::DepthSensor> depth_sensor;
};

/// The whole camera file, depth_sensor included. Throws InputError as read_intrinsics_file.
CameraFile read_camera_file(const std::filesystem::path& file);
CameraFile parse_camera(std::string_view text, const std::filesystem::path& name_for_errors);

/// Reads and validates an intrinsics file (its colour camera). Throws InputError naming the file, the line where
/// known, and the offending key (unknown key, missing key, duplicate key, bad value).
core::Intrinsics read_intrinsics_file(const std::filesystem::path& file);
core::Intrinsics parse_intrinsics(std::string_view text, const std::filesystem::path& name_for_errors);

/// The YAML form of `intrinsics`, each number in its shortest exact text, after a "# comment"
/// line. The distortion keys are written only for a distorted camera, so files of distortion-free
/// cameras read the same by older versions.
std::string format_intrinsics_yaml(const core::Intrinsics& intrinsics, std::string_view comment);

/// A camera given as a preset name (core::camera_preset_names()) or else a path to an intrinsics
/// file; throws InputError when it is neither.
core::Intrinsics load_camera(std::string_view preset_or_file);
CameraFile load_camera_file(std::string_view preset_or_file);

/// Intrinsics::validate(), except that width = height = 0 ("from the images") is allowed.
[[nodiscard]] std::string validate_allowing_unknown_size(const core::Intrinsics& intrinsics);

}  // namespace cvo::io
