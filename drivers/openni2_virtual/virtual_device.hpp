#pragma once
// What the cvo-virtual OpenNI2 driver (cvo_virtual_driver.cpp) and its users agree on: the device
// URI and two properties of its own. Header-only, no OpenNI2 types, so that the driver plug-in and
// drivers/openni2_source.cpp can both include it.
//
// URI: "cvo-virtual:DIR" plays the TUM folder DIR; options follow a '?', '&'-separated:
//   unplug_after=N     the device disconnects after N frames (once)
//   replug_after_s=S   ... and is connected again S seconds later (without it: never)
// and, to stand for real cameras' recordings (drivers/README.md, "Real cameras' recordings"):
//   fov=0              no field of view and no kIntrinsicsProperty (as OpenNI 1 / Kinect files)
//   zpd=MM&zpps=MM     the depth stream's PS1080 zero-plane distance and pixel size (SXGA), which
//                      OpenNI's Recorder records ("ZPD", "ZPPS")
//   colour_size=WxH    colour at this size (scaled from the folder's); depth stays at the folder's
//   mirrored=1         both streams mirrored, and mirroring cannot be turned off
// The whole URI, options included, is the device's OpenNI URI (at most 255 characters).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace cvo::drivers::virtual_device {

inline constexpr std::string_view kScheme = "cvo-virtual:";

/// Stream property (read only): the colour camera's intrinsics, which OpenNI's fields of view
/// cannot carry (the principal point, the lens distortion, a rolling shutter's readout). Its value
/// is `StreamIntrinsics`. The
/// depth stream answers it too: depth is registered to colour.
inline constexpr int kIntrinsicsProperty = 0x43564F01;  // "CVO" 1, clear of OpenNI's and PS1080's ids
struct StreamIntrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double distortion[5] = {0, 0, 0, 0, 0};  // k1, k2, p1, p2, k3 as core::Intrinsics
  double readout_s = 0;                    // as core::Intrinsics
};

/// Device property (int, 1 or 0): 1 (the default) plays at the recorded rate, as a camera would;
/// 0 produces the next frame only when the application waits for one with none pending
/// (OpenNI's "manual trigger", as a recording played at speed -1), so that a slow consumer loses
/// no frame.
inline constexpr int kPacedProperty = 0x43564F02;

struct Uri {
  std::string dir;
  std::optional<std::uint64_t> unplug_after;
  std::optional<double> replug_after_s;
  bool fov = true;
  std::optional<double> zpd_mm, zpps_mm;
  std::optional<std::pair<int, int>> colour_size;
  bool mirrored = false;
};

/// "WxH" with both positive; nullopt otherwise.
inline std::optional<std::pair<int, int>> parse_size(const std::string& text) {
  const auto x = text.find('x');
  if (x == std::string::npos) return std::nullopt;
  try {
    std::size_t a = 0, b = 0;
    const int w = std::stoi(text.substr(0, x), &a), h = std::stoi(text.substr(x + 1), &b);
    if (a != x || b != text.size() - x - 1 || w <= 0 || h <= 0) return std::nullopt;
    return std::pair{w, h};
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

/// Parses a "cvo-virtual:" URI; nullopt, with the reason in `error`, when it is not one or an
/// option is unknown or malformed.
inline std::optional<Uri> parse_uri(std::string_view uri, std::string* error) {
  const auto fail = [&](const std::string& why) -> std::optional<Uri> {
    if (error != nullptr) *error = why;
    return std::nullopt;
  };
  if (!uri.starts_with(kScheme)) return fail("not a " + std::string(kScheme) + " URI");
  uri.remove_prefix(kScheme.size());
  Uri out;
  const auto q = uri.find('?');
  out.dir = std::string(uri.substr(0, q));
  if (out.dir.empty()) return fail("no folder after " + std::string(kScheme));
  std::string_view options = q == std::string_view::npos ? std::string_view{} : uri.substr(q + 1);
  while (!options.empty()) {
    const auto amp = options.find('&');
    const auto option = options.substr(0, amp);
    options = amp == std::string_view::npos ? std::string_view{} : options.substr(amp + 1);
    const auto eq = option.find('=');
    const std::string key(option.substr(0, eq)), value(eq == std::string_view::npos ? "" : option.substr(eq + 1));
    std::size_t used = 0;
    try {
      if (key == "unplug_after") {
        out.unplug_after = std::stoull(value, &used);
      } else if (key == "replug_after_s") {
        out.replug_after_s = std::stod(value, &used);
        if (*out.replug_after_s < 0) used = 0;
      } else if (key == "fov" || key == "mirrored") {
        if (value != "0" && value != "1") return fail("bad value '" + value + "' of " + key + " (0 or 1)");
        (key == "fov" ? out.fov : out.mirrored) = value == "1";
        used = value.size();
      } else if (key == "zpd" || key == "zpps") {
        auto& v = key == "zpd" ? out.zpd_mm : out.zpps_mm;
        v = std::stod(value, &used);
        if (!(*v > 0)) used = 0;
      } else if (key == "colour_size") {
        out.colour_size = parse_size(value);
        used = out.colour_size ? value.size() : 0;
      } else {
        return fail("unknown option '" + key +
                    "' (known: unplug_after, replug_after_s, fov, zpd, zpps, colour_size, mirrored)");
      }
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != value.size()) return fail("bad value '" + value + "' of " + key);
  }
  if (out.zpd_mm.has_value() != out.zpps_mm.has_value()) return fail("zpd and zpps go together");
  return out;
}

}  // namespace cvo::drivers::virtual_device
