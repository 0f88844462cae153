// cvo-render: writes a synthetic RGB-D sequence with exact ground truth in TUM layout.
// Exit status: 0 done, 1 I/O error, 2 bad arguments.
#include <charconv>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <iostream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "libcvo/sim/sequence.hpp"

namespace {

constexpr std::string_view kUsage =
    "usage: cvo-render OUTDIR [--scene textured_room|textureless_room|textured_wall]\n"
    "                         [--path orbit|sweep|wall] [--frames N] [--seed S] [--noise]\n"
    "\n"
    "Renders a synthetic RGB-D sequence with exact ground truth into OUTDIR in TUM layout:\n"
    "rgb/, depth/ (16-bit, 5000 units per metre), rgb.txt, depth.txt, groundtruth.txt, camera.yaml.\n"
    "Camera: the 'synthetic' preset (640x480, fx = fy = 525); 30 Hz from t = 1000 s.\n"
    "\n"
    "  --scene NAME  textured_room (default), textureless_room or textured_wall\n"
    "  --path NAME   orbit (12 s loop; default), sweep (12 s) or wall (10 s; default for textured_wall)\n"
    "  --frames N    number of frames, 1..100000 (default: one period of the path)\n"
    "  --seed S      texture and noise seed, unsigned 64-bit (default 0)\n"
    "  --noise       Kinect-like depth noise and dropouts (default: exact depth)\n"
    "  -h, --help    this text\n"
    "\n"
    "The same arguments always give byte-identical files.\n";

struct UsageError {
  std::string message;
};

template <typename T>
T parse_unsigned(std::string_view text, std::string_view option) {
  T value{};
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size())
    throw UsageError{std::string(option) + " needs an unsigned integer, got '" + std::string(text) + "'"};
  return value;
}

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

struct Arguments {
  std::string out_dir;
  cvo::sim::SequenceOptions options;
};

// Returns nothing when help was asked for.
std::optional<Arguments> parse(const std::vector<std::string_view>& args) {
  Arguments parsed;
  std::optional<cvo::sim::PathKind> path;
  std::optional<std::size_t> frames;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string_view arg = args[i];
    auto value = [&]() -> std::string_view {
      if (i + 1 >= args.size()) throw UsageError{std::string(arg) + " needs a value"};
      return args[++i];
    };
    if (arg == "-h" || arg == "--help") return std::nullopt;
    if (arg == "--scene") {
      const std::string_view name = value();
      const auto kind = cvo::sim::parse_scene_kind(name);
      if (!kind) throw UsageError{"unknown scene '" + std::string(name) + "' (one of " + join(cvo::sim::scene_names()) + ")"};
      parsed.options.scene = *kind;
    } else if (arg == "--path") {
      const std::string_view name = value();
      path = cvo::sim::parse_path_kind(name);
      if (!path) throw UsageError{"unknown path '" + std::string(name) + "' (one of " + join(cvo::sim::path_names()) + ")"};
    } else if (arg == "--frames") {
      frames = parse_unsigned<std::size_t>(value(), arg);
      if (*frames < 1 || *frames > 100000) throw UsageError{"--frames must be in 1..100000"};
    } else if (arg == "--seed") {
      parsed.options.seed = parse_unsigned<std::uint64_t>(value(), arg);
    } else if (arg == "--noise") {
      parsed.options.noise.enabled = true;
    } else if (arg.starts_with("-")) {
      throw UsageError{"unknown option '" + std::string(arg) + "'"};
    } else if (parsed.out_dir.empty()) {
      parsed.out_dir = arg;
    } else {
      throw UsageError{"more than one OUTDIR given ('" + parsed.out_dir + "', '" + std::string(arg) + "')"};
    }
  }
  if (parsed.out_dir.empty()) throw UsageError{"OUTDIR is missing"};
  parsed.options.path = path.value_or(parsed.options.scene == cvo::sim::SceneKind::textured_wall ? cvo::sim::PathKind::wall
                                                                                                  : cvo::sim::PathKind::orbit);
  parsed.options.frames =
      frames.value_or(static_cast<std::size_t>(cvo::sim::path_period(parsed.options.path) * parsed.options.rate_hz));
  return parsed;
}

}  // namespace

int main(int argc, char** argv) {
  std::optional<Arguments> arguments;
  try {
    arguments = parse(std::vector<std::string_view>(argv + 1, argv + argc));
  } catch (const UsageError& e) {
    std::cerr << "cvo-render: " << e.message << '\n' << kUsage.substr(0, kUsage.find("\n\n") + 1)
              << "(cvo-render --help for details)\n";
    return 2;
  }
  if (!arguments) {
    std::cout << kUsage;
    return 0;
  }
  const auto& [out_dir, options] = *arguments;
  try {
    const auto start = std::chrono::steady_clock::now();
    const cvo::sim::SequenceSummary summary = cvo::sim::write_sequence(out_dir, options);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("cvo-render: %zu frames (%s, %s, seed %llu, noise %s; %.1f s of motion, %.2f m, %.1f%% valid depth) "
                "-> %s in %.1f s\n",
                summary.frames, std::string(cvo::sim::scene_name(options.scene)).c_str(),
                std::string(cvo::sim::path_name(options.path)).c_str(), static_cast<unsigned long long>(options.seed),
                options.noise.enabled ? "on" : "off", summary.duration_s, summary.path_length_m,
                100.0 * summary.valid_depth_fraction, out_dir.c_str(), seconds);
  } catch (const std::exception& e) {
    std::cerr << "cvo-render: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
