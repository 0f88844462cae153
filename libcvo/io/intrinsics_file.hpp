#pragma once
// Camera intrinsics from a file, or by preset name.
//
// Two file formats are accepted, told apart by their content:
//   - YAML, a mapping with keys fx, fy, cx, cy, width, height (required) and depth_scale
//     (optional, raw depth units per metre, default 5000 as TUM):
//         fx: 517.3
//         fy: 516.5
//         ...
//   - ETH3D's calibration.txt: a single line "fx fy cx cy". It gives no image size, so width and
//     height are returned as 0, meaning "take them from the images" (TumSequence does).
#include <filesystem>
#include <string_view>

#include "libcvo/core/camera.hpp"

namespace cvo::io {

/// Reads and validates an intrinsics file. Throws InputError naming the file, the line where
/// known, and the offending key (unknown key, missing key, duplicate key, bad value).
core::Intrinsics read_intrinsics_file(const std::filesystem::path& file);
core::Intrinsics parse_intrinsics(std::string_view text, const std::filesystem::path& name_for_errors);

/// A camera given as a preset name (core::camera_preset_names()) or else a path to an intrinsics
/// file; throws InputError when it is neither.
core::Intrinsics load_camera(std::string_view preset_or_file);

/// Intrinsics::validate(), except that width = height = 0 ("from the images") is allowed.
[[nodiscard]] std::string validate_allowing_unknown_size(const core::Intrinsics& intrinsics);

}  // namespace cvo::io
