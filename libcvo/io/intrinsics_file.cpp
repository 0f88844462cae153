#include "libcvo/io/intrinsics_file.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <yaml-cpp/yaml.h>

#include "libcvo/io/input_error.hpp"
#include "libcvo/io/numbers.hpp"
#include "libcvo/io/text_lines.hpp"

namespace cvo::io {
namespace {

constexpr std::array<std::string_view, 13> kKeys{"fx", "fy", "cx", "cy", "width", "height",   "depth_scale",
                                                 "k1", "k2", "p1", "p2", "k3",    "readout_s"};
constexpr std::size_t kRequiredKeys = 6;  // fx .. height; the rest default
constexpr std::string_view kExpected = "fx, fy, cx, cy, width, height, depth_scale, k1, k2, p1, p2, k3, readout_s";
constexpr std::array<std::string_view, 5> kDistortionKeys{"k1", "k2", "p1", "p2", "k3"};  // OpenCV's order
constexpr std::string_view kDepthSensorKey = "depth_sensor";
constexpr std::string_view kExtrinsicKey = "T_colour_depth";

// Shortest text that reads back as the same double.
std::string exact(double v) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
  return {buffer, result.ptr};
}

std::size_t line_of(const YAML::Node& node) {
  const int line = node.Mark().line;
  return line >= 0 ? static_cast<std::size_t>(line) + 1 : 0;
}

// The key of a field named in Intrinsics::validate()'s message ("fx must be ..."), to find its line.
std::string_view key_in(const std::string& message) {
  for (const auto key : kKeys)
    if (message.starts_with(key) && message.size() > key.size() && message[key.size()] == ' ') return key;
  return {};
}

core::Intrinsics parse_eth3d(std::string_view text, const std::filesystem::path& name) {
  std::istringstream in{std::string(text)};
  core::Intrinsics k;
  k.width = k.height = 0;  // not in the file: from the images
  std::size_t lines = 0;
  for_each_data_line(in, name, [&](std::size_t line_no, const std::vector<std::string>& fields) {
    if (++lines > 1) throw InputError(name, line_no, "an ETH3D calibration has one line 'fx fy cx cy'");
    if (fields.size() != 4)
      throw InputError(name, line_no, "expected 4 fields 'fx fy cx cy', got " + std::to_string(fields.size()));
    k.fx = parse_finite(fields[0], name, line_no);
    k.fy = parse_finite(fields[1], name, line_no);
    k.cx = parse_finite(fields[2], name, line_no);
    k.cy = parse_finite(fields[3], name, line_no);
  });
  if (lines == 0) throw InputError(name, "empty intrinsics file");
  if (const auto error = validate_allowing_unknown_size(k); !error.empty()) throw InputError(name, 1, error);
  return k;
}

YAML::Node load_yaml(std::string_view text, const std::filesystem::path& name) {
  try {
    return YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    throw InputError(name, e.mark.line >= 0 ? static_cast<std::size_t>(e.mark.line) + 1 : 0, "YAML: " + e.msg);
  }
}

// One intrinsics key's value into k.
void set_key(core::Intrinsics& k, const std::string& key, const YAML::Node& value, const std::filesystem::path& name,
             std::size_t line) {
  if (!value.IsScalar()) throw InputError(name, line, key + ": expected a number");
  const auto& text_value = value.Scalar();
  if (key == "width" || key == "height") {
    const auto v = to_integer(text_value);
    if (!v || *v <= 0 || *v > 16384)
      throw InputError(name, line, key + ": expected an integer in 1..16384, got '" + text_value + "'");
    (key == "width" ? k.width : k.height) = static_cast<int>(*v);
    return;
  }
  const auto v = to_finite(text_value);
  if (!v) throw InputError(name, line, key + ": not a finite number: '" + text_value + "'");
  if (key == "fx") k.fx = *v;
  if (key == "fy") k.fy = *v;
  if (key == "cx") k.cx = *v;
  if (key == "cy") k.cy = *v;
  if (key == "depth_scale") k.depth_scale = *v;
  if (key == "readout_s") k.readout_s = *v;
  for (std::size_t i = 0; i < kDistortionKeys.size(); ++i)
    if (key == kDistortionKeys[i]) k.distortion[i] = *v;
}

// T_colour_depth: [tx, ty, tz, qx, qy, qz, qw], the TUM order; the quaternion is normalised.
core::SE3 parse_extrinsic(const YAML::Node& value, const std::filesystem::path& name, std::size_t line) {
  const std::string what = std::string(kExtrinsicKey) + ": expected [tx, ty, tz, qx, qy, qz, qw]";
  if (!value.IsSequence() || value.size() != 7) throw InputError(name, line, what);
  double x[7];
  for (std::size_t i = 0; i < 7; ++i) {
    const auto v = value[i].IsScalar() ? to_finite(value[i].Scalar()) : std::nullopt;
    if (!v) throw InputError(name, line, what + ", element " + std::to_string(i + 1) + " is not a finite number");
    x[i] = *v;
  }
  const Eigen::Quaterniond q(x[6], x[3], x[4], x[5]);
  if (!(q.norm() > 0.5 && q.norm() < 2)) throw InputError(name, line, what + " with a unit quaternion");
  return {q.normalized(), Eigen::Vector3d(x[0], x[1], x[2])};
}

// The intrinsics keys of `map` (the file's root, or its depth_sensor section starting on `line`,
// 0 for the root); `nested` is what else the mapping may hold (the depth_sensor section, or
// T_colour_depth in it).
core::Intrinsics parse_map(const YAML::Node& map, const std::filesystem::path& name, std::size_t line_of_map,
                           std::string_view nested, std::map<std::string, std::size_t, std::less<>>& seen) {
  core::Intrinsics k;
  for (const auto& entry : map) {
    const auto key = entry.first.Scalar();
    const auto line = line_of(entry.first);
    if (key != nested && std::find(kKeys.begin(), kKeys.end(), key) == kKeys.end())
      throw InputError(
          name, line,
          "unknown key '" + key + "' (expected " + std::string(kExpected) + ", " + std::string(nested) + ")");
    if (const auto [it, fresh] = seen.emplace(key, line); !fresh)
      throw InputError(name, line, "duplicate key '" + key + "' (first on line " + std::to_string(it->second) + ")");
    if (key != nested) set_key(k, key, entry.second, name, line);
  }
  for (std::size_t i = 0; i < kRequiredKeys; ++i)
    if (!seen.contains(kKeys[i])) throw InputError(name, line_of_map, "missing key '" + std::string(kKeys[i]) + "'");
  if (const auto error = k.validate(); !error.empty()) {
    const auto it = seen.find(key_in(error));
    throw InputError(name, it != seen.end() ? it->second : 0, error);
  }
  return k;
}

CameraFile parse_yaml(std::string_view text, const std::filesystem::path& name) {
  const YAML::Node root = load_yaml(text, name);
  if (!root.IsMap())
    throw InputError(
        name, std::string("expected a YAML mapping with keys ").append(kExpected) + ", or an ETH3D line 'fx fy cx cy'");
  std::map<std::string, std::size_t, std::less<>> seen;  // key -> line
  CameraFile camera{parse_map(root, name, 0, kDepthSensorKey, seen), std::nullopt};
  if (const YAML::Node section = root[std::string(kDepthSensorKey)]) {
    const auto line = seen.at(std::string(kDepthSensorKey));
    if (!section.IsMap()) throw InputError(name, line, std::string(kDepthSensorKey) + ": expected a mapping");
    std::map<std::string, std::size_t, std::less<>> inner;
    core::DepthSensor depth{parse_map(section, name, line, kExtrinsicKey, inner), {}};
    if (!inner.contains(std::string(kExtrinsicKey)))
      throw InputError(name, line, std::string(kDepthSensorKey) + ": missing key '" + std::string(kExtrinsicKey) + "'");
    depth.T_colour_depth =
        parse_extrinsic(section[std::string(kExtrinsicKey)], name, inner.at(std::string(kExtrinsicKey)));
    camera.depth_sensor = depth;
  }
  return camera;
}

}  // namespace

std::string validate_allowing_unknown_size(const core::Intrinsics& intrinsics) {
  if (intrinsics.width != 0 || intrinsics.height != 0) return intrinsics.validate();
  auto sized = intrinsics;
  sized.width = sized.height = 1;
  return sized.validate();
}

std::string format_intrinsics_yaml(const core::Intrinsics& k, std::string_view comment) {
  std::string text = "# " + std::string(comment) + "\n";
  text += "fx: " + exact(k.fx) + "\nfy: " + exact(k.fy) + "\ncx: " + exact(k.cx) + "\ncy: " + exact(k.cy) +
          "\nwidth: " + std::to_string(k.width) + "\nheight: " + std::to_string(k.height) +
          "\ndepth_scale: " + exact(k.depth_scale) + "\n";
  if (k.has_distortion())
    for (std::size_t i = 0; i < kDistortionKeys.size(); ++i)
      text.append(kDistortionKeys[i]).append(": ").append(exact(k.distortion[i])).append("\n");
  if (k.rolling_shutter()) text += "readout_s: " + exact(k.readout_s) + "\n";
  return text;
}

CameraFile parse_camera(std::string_view text, const std::filesystem::path& name) {
  // A YAML mapping always has a ':' outside comments; ETH3D's line of four numbers never does.
  std::istringstream in{std::string(text)};
  for (std::string line; std::getline(in, line);)
    if (line.substr(0, line.find('#')).find(':') != std::string::npos) return parse_yaml(text, name);
  return {parse_eth3d(text, name), std::nullopt};
}

core::Intrinsics parse_intrinsics(std::string_view text, const std::filesystem::path& name) {
  return parse_camera(text, name).colour;
}

CameraFile read_camera_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file, "cannot open intrinsics file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(file, "read error");
  return parse_camera(text.str(), file);
}

core::Intrinsics read_intrinsics_file(const std::filesystem::path& file) { return read_camera_file(file).colour; }

CameraFile load_camera_file(std::string_view preset_or_file) {
  if (const auto preset = core::camera_preset(preset_or_file)) return {*preset, std::nullopt};
  const std::filesystem::path file(preset_or_file);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    std::string presets;
    for (const auto& n : core::camera_preset_names()) presets.append(presets.empty() ? "" : ", ").append(n);
    throw InputError(file, "not a camera preset (" + presets + ") nor an intrinsics file");
  }
  return read_camera_file(file);
}

core::Intrinsics load_camera(std::string_view preset_or_file) { return load_camera_file(preset_or_file).colour; }

}  // namespace cvo::io
