// tum2lcm: a TUM RGB-D folder to an LCM log of CVO_RGBD frames (what a camera driver would have
// published, as lcm-logger records it), and back with --to-tum.
//
// A contract that scripts rely on: the arguments below and the exit codes 0 (ok), 1 (bad input;
// the message names the file) and 2 (usage error).
#include <charconv>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "libcvo/io/input_error.hpp"
#include "log_to_tum.hpp"
#include "tum_to_log.hpp"
#include "tools/common/cli.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;

constexpr std::string_view kUsage =
    R"(usage: tum2lcm TUM_DIR OUT.lcmlog [--colour png|jpeg|raw] [--depth png|raw] [--channel NAME]
               [--max-frames N] [--jpeg-quality Q]
       tum2lcm --to-tum IN.lcmlog OUT_DIR [--channel NAME]

The first form writes the frames of a TUM RGB-D folder (rgb.txt, depth.txt, images; camera.yaml or
the preset its name implies) as an LCM log of cvo_lcm.rgbd_frame_t messages, one event per frame in
recording order, each event stamped with its frame's time: a recording like one of a camera.
The second writes the frames of such a log back as a TUM folder (PNG images, rgb.txt, depth.txt,
camera.yaml); png and raw recordings come back pixel-exact.

options:
  --colour E        colour encoding: png (default, lossless), jpeg, raw (BGR8)
  --depth E         depth encoding: png (default, lossless), raw (uint16 little-endian)
  --jpeg-quality Q  0..100 (default 90)
  --channel NAME    LCM channel (default CVO_RGBD)
  --max-frames N    only the first N frames (default: all)
  --help            this text

exit status: 0 ok, 1 bad input, 2 usage error
)";

using tools::UsageError;

struct Arguments {
  bool help = false;
  bool to_tum = false;
  fs::path input, output;
  tools::TumToLogOptions options;
};

int parse_int(std::string_view option, std::string_view text, int min, int max) {
  int v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || v < min || v > max)
    throw UsageError(std::string(option) + " needs an integer in " + std::to_string(min) + ".." + std::to_string(max) +
                     ", not '" + std::string(text) + "'");
  return v;
}

Arguments parse_arguments(int argc, char** argv) {
  Arguments args;
  std::vector<std::string> positional;
  for (int k = 1; k < argc; ++k) {
    const std::string_view arg = argv[k];
    const auto value = [&]() -> std::string {
      if (k + 1 >= argc) throw UsageError(std::string(arg) + " needs a value");
      return argv[++k];
    };
    if (arg == "--help" || arg == "-h") {
      args.help = true;
    } else if (arg == "--to-tum") {
      args.to_tum = true;
    } else if (arg == "--colour" || arg == "--color") {
      const std::string v = value();
      const auto e = lcm::parse_colour_encoding(v);
      if (!e) throw UsageError("--colour must be png, jpeg or raw, not '" + v + "'");
      args.options.encoding.colour = *e;
    } else if (arg == "--depth") {
      const std::string v = value();
      const auto e = lcm::parse_depth_encoding(v);
      if (!e) throw UsageError("--depth must be png or raw, not '" + v + "'");
      args.options.encoding.depth = *e;
    } else if (arg == "--jpeg-quality") {
      args.options.encoding.jpeg_quality = parse_int(arg, value(), 0, 100);
    } else if (arg == "--channel") {
      args.options.channel = value();
      if (args.options.channel.empty()) throw UsageError("--channel needs a non-empty name");
    } else if (arg == "--max-frames") {
      args.options.max_frames = static_cast<std::size_t>(parse_int(arg, value(), 1, 1'000'000'000));
    } else if (arg.size() > 1 && arg[0] == '-') {
      throw UsageError("unknown option " + std::string(arg));
    } else {
      positional.emplace_back(arg);
    }
  }
  if (args.help) return args;
  if (positional.size() != 2)
    throw UsageError("expected 2 paths (" + std::string(args.to_tum ? "IN.lcmlog OUT_DIR" : "TUM_DIR OUT.lcmlog") +
                     "), got " + std::to_string(positional.size()));
  args.input = positional[0];
  args.output = positional[1];
  return args;
}

int run(const Arguments& args) {
  if (args.to_tum) {
    const auto s = tools::log_to_tum(args.input, args.output, args.options.channel);
    std::cout << "tum2lcm: wrote " << s.frames << " frames to " << args.output.string();
    if (s.other_events > 0) std::cout << " (skipped " << s.other_events << " events on other channels)";
    std::cout << "\n";
  } else {
    const auto s = tools::tum_to_log(args.input, args.output, args.options);
    std::cout << "tum2lcm: wrote " << s.frames << " frames to " << args.output.string() << " on "
              << args.options.channel << ", colour " << lcm::to_string(args.options.encoding.colour) << ", depth "
              << lcm::to_string(args.options.encoding.depth) << ", " << s.bytes << " bytes ("
              << (s.frames > 0 ? s.bytes / s.frames : 0) << " per frame)\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return tools::cli_main("tum2lcm", kUsage, argc, argv, parse_arguments, run);
}
