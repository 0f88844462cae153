#include "tests/support/v4l2_emulator/config.hpp"

#include <linux/videodev2.h>

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <stdexcept>

namespace cvo::drivers::v4l2_emulator {
namespace {

std::vector<std::string_view> split(std::string_view text, char separator) {
  std::vector<std::string_view> parts;
  for (std::size_t start = 0;;) {
    const auto end = text.find(separator, start);
    parts.push_back(text.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start));
    if (end == std::string_view::npos) return parts;
    start = end + 1;
  }
}

template <class T>
T number(std::string_view key, std::string_view text) {
  T value{};
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc{} || end != text.data() + text.size())
    throw std::invalid_argument(std::string(key) + ": '" + std::string(text) + "' is not a number");
  return value;
}

std::vector<std::uint32_t> formats(std::string_view key, std::string_view text) {
  std::vector<std::uint32_t> out;
  for (const auto name : split(text, '+')) {
    if (name == "yuyv")
      out.push_back(V4L2_PIX_FMT_YUYV);
    else if (name == "mjpeg")
      out.push_back(V4L2_PIX_FMT_MJPEG);
    else
      throw std::invalid_argument(std::string(key) + ": '" + std::string(name) + "' (yuyv, mjpeg)");
  }
  return out;
}

std::vector<FrameSize> sizes(std::string_view key, std::string_view text) {
  std::vector<FrameSize> out;
  for (const auto size : split(text, '+')) {
    const auto x = size.find('x');
    if (x == std::string_view::npos)
      throw std::invalid_argument(std::string(key) + ": '" + std::string(size) + "' is not WxH");
    const FrameSize s{number<std::uint32_t>(key, size.substr(0, x)), number<std::uint32_t>(key, size.substr(x + 1))};
    // Even widths: YUYV carries two pixels per four bytes.
    if (s.width < 2 || s.height < 1 || s.width % 2 != 0 || s.width > 8192 || s.height > 8192)
      throw std::invalid_argument(std::string(key) + ": " + std::string(size) + " (an even width, up to 8192x8192)");
    out.push_back(s);
  }
  return out;
}

std::vector<std::uint32_t> rates(std::string_view key, std::string_view text) {
  std::vector<std::uint32_t> out;
  for (const auto rate : split(text, '+')) {
    out.push_back(number<std::uint32_t>(key, rate));
    if (out.back() < 1 || out.back() > 1000)
      throw std::invalid_argument(std::string(key) + ": 1 to 1000 frames per second");
  }
  return out;
}

// The setter of each key.
using Setter = std::function<void(CameraConfig&, std::string_view key, std::string_view value)>;

const std::map<std::string_view, Setter>& setters() {
  static const std::map<std::string_view, Setter> table{
      {"colour", [](CameraConfig& c, auto, auto v) { c.colour.path = v; }},
      {"depth", [](CameraConfig& c, auto, auto v) { c.depth.path = v; }},
      {"tum", [](CameraConfig& c, auto, auto v) { c.tum = std::string(v); }},
      {"colour_format", [](CameraConfig& c, auto k, auto v) { c.colour.formats = formats(k, v); }},
      {"colour_size", [](CameraConfig& c, auto k, auto v) { c.colour.sizes = sizes(k, v); }},
      {"colour_fps", [](CameraConfig& c, auto k, auto v) { c.colour.rates = rates(k, v); }},
      {"depth_size", [](CameraConfig& c, auto k, auto v) { c.depth.sizes = sizes(k, v); }},
      {"depth_fps", [](CameraConfig& c, auto k, auto v) { c.depth.rates = rates(k, v); }},
      {"depth_units_per_m", [](CameraConfig& c, auto k, auto v) { c.depth_units_per_metre = number<double>(k, v); }},
      {"play_fps", [](CameraConfig& c, auto k, auto v) { c.play_fps = number<double>(k, v); }},
      {"unplug_after", [](CameraConfig& c, auto k, auto v) { c.unplug_after = number<std::uint64_t>(k, v); }},
      {"replug_after_s", [](CameraConfig& c, auto k, auto v) { c.replug_after_s = number<double>(k, v); }},
      {"lossless", [](CameraConfig& c, auto k, auto v) { c.lossless = number<int>(k, v) != 0; }},
      {"error_every", [](CameraConfig& c, auto k, auto v) { c.error_every = number<std::uint64_t>(k, v); }},
      {"card", [](CameraConfig& c, auto, auto v) { c.card = std::string(v.substr(0, 31)); }},
      {"at_end",
       [](CameraConfig& c, auto k, auto v) {
         if (v != "loop" && v != "unplug") throw std::invalid_argument(std::string(k) + ": loop or unplug");
         c.at_end = v == "loop" ? AtEnd::kLoop : AtEnd::kUnplug;
       }},
  };
  return table;
}

}  // namespace

CameraConfig parse_camera_config(std::string_view text) {
  CameraConfig c;
  c.colour.formats = {V4L2_PIX_FMT_YUYV};
  c.colour.sizes = {{640, 480}};
  c.colour.rates = {30};
  c.depth.formats = {V4L2_PIX_FMT_Z16};
  c.depth.sizes = {{848, 480}};
  c.depth.rates = {30};
  for (const auto item : split(text, ',')) {
    const auto eq = item.find('=');
    const auto key = item.substr(0, eq);
    const auto it = setters().find(key);
    if (eq == std::string_view::npos || it == setters().end())
      throw std::invalid_argument("'" + std::string(item) + "': expected key=value with a known key");
    it->second(c, key, item.substr(eq + 1));
  }
  if (c.colour.path.empty() || c.depth.path.empty() || c.tum.empty())
    throw std::invalid_argument("colour=, depth= and tum= are required");
  if (c.colour.path == c.depth.path) throw std::invalid_argument("colour and depth must be two nodes");
  if (!(c.depth_units_per_metre > 0)) throw std::invalid_argument("depth_units_per_m must be positive");
  if (c.play_fps < 0) throw std::invalid_argument("play_fps must not be negative");
  if (c.play_fps == 0) c.play_fps = c.colour.rates.front();
  return c;
}

std::vector<CameraConfig> cameras_from_environment() {
  std::vector<CameraConfig> cameras;
  for (int i = 1; i <= 9; ++i) {
    const std::string name = i == 1 ? "CVO_V4L2_EMULATOR" : "CVO_V4L2_EMULATOR_" + std::to_string(i);
    const char* value = std::getenv(name.c_str());
    if (value == nullptr || *value == '\0') continue;
    try {
      cameras.push_back(parse_camera_config(value));
    } catch (const std::invalid_argument& e) {
      std::fprintf(stderr, "cvo-v4l2-emulator: %s ignored: %s\n", name.c_str(), e.what());
    }
  }
  return cameras;
}

}  // namespace cvo::drivers::v4l2_emulator
