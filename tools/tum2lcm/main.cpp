// tum2lcm: a TUM RGB-D folder to an LCM log of CVO_RGBD frames (what a camera driver would have
// published, as lcm-logger records it), and back with --to-tum.
//
// A contract that scripts rely on: the arguments below and the exit codes 0 (ok), 1 (bad input;
// the message names the file) and 2 (usage error).
#include <charconv>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <system_error>

#include "libcvo/lcm/rgbd_conversion.hpp"
#include "log_to_tum.hpp"
#include "program/cli.hpp"
#include "tum_to_log.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;

constexpr const char* kSynopsis =
    "tum2lcm TUM_DIR OUT.lcmlog [--colour png|jpeg|raw] [--depth png|raw] [--channel NAME]\n"
    "               [--max-frames N] [--jpeg-quality Q] [--key-file FILE]\n"
    "       tum2lcm --to-tum IN.lcmlog OUT_DIR [--channel NAME]";

constexpr const char* kDescription =
    R"(The first form writes the frames of a TUM RGB-D folder (rgb.txt, depth.txt, images; camera.yaml or
the preset its name implies) as an LCM log of cvo_lcm.rgbd_frame_t messages, one event per frame in
recording order, each event stamped with its frame's time: a recording like one of a camera.
The second writes the frames of such a log back as a TUM folder (PNG images, rgb.txt, depth.txt,
camera.yaml); png and raw recordings come back pixel-exact.)";

struct Arguments {
  bool to_tum = false;
  fs::path input, output;
  std::string colour = "png", depth = "png", channel = "CVO_RGBD";
  fs::path keys;  // --key-file
  int jpeg_quality = 90;
  std::size_t max_frames = 0;  // 0 = all
};

// CLI11 reads integers with strtoull/strtoll base 0 ("010" is octal, "-1" wraps for unsigned):
// whole numbers here are plain decimal, as before, and reach CLI11 in canonical form.
const CLI::Validator kDecimal(
    [](std::string& text) -> std::string {
      std::uint64_t value = 0;
      const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (ec != std::errc() || end != text.data() + text.size() || text.empty())
        return "needs a whole number, not '" + text + "'";
      text = std::to_string(value);
      return {};
    },
    "", "decimal");

void add_options(CLI::App& app, Arguments& args) {
  app.add_option("INPUT", args.input, "TUM_DIR, or IN.lcmlog with --to-tum")->required();
  app.add_option("OUTPUT", args.output, "OUT.lcmlog, or OUT_DIR with --to-tum")->required();
  app.add_flag("--to-tum", args.to_tum, "the second form: an LCM log back to a TUM folder");
  app.add_option("--colour,--color", args.colour, "colour encoding: png (lossless), jpeg, raw (BGR8)")
      ->check(CLI::IsMember({"png", "jpeg", "raw"}));
  app.add_option("--depth", args.depth, "depth encoding: png (lossless), raw (uint16 little-endian)")
      ->check(CLI::IsMember({"png", "raw"}));
  app.add_option("--jpeg-quality", args.jpeg_quality, "JPEG quality of --colour jpeg")
      ->transform(kDecimal)
      ->check(CLI::Range(0, 100));
  app.add_option("--channel", args.channel, "LCM channel")->check([](const std::string& name) {
    return name.empty() ? std::string("needs a non-empty name") : std::string();
  });
  app.add_option("--key-file", args.keys,
                 "sign every event with this deployment key file (auth.key_file; cvo-keygen), as a driver on an "
                 "authenticated bus does")
      ->default_str("none (unsigned)");
  app.add_option("--max-frames", args.max_frames, "only the first N frames")
      ->transform(kDecimal)
      ->check(CLI::Range(1, 1'000'000'000))
      ->default_str("all");
}

int run(const Arguments& args) {
  if (args.to_tum) {
    const auto s = tools::log_to_tum(args.input, args.output, args.channel);
    std::cout << "tum2lcm: wrote " << s.frames << " frames to " << args.output.string();
    if (s.other_events > 0) std::cout << " (skipped " << s.other_events << " events on other channels)";
    std::cout << "\n";
    return 0;
  }
  tools::TumToLogOptions options;
  // The names were checked by IsMember.
  options.encoding.colour = lcm::parse_colour_encoding(args.colour).value();
  options.encoding.depth = lcm::parse_depth_encoding(args.depth).value();
  options.encoding.jpeg_quality = args.jpeg_quality;
  options.channel = args.channel;
  options.max_frames = args.max_frames;
  if (!args.keys.empty()) options.keys = std::make_shared<const auth::KeyRing>(auth::read_key_file(args.keys));
  const auto s = tools::tum_to_log(args.input, args.output, options);
  std::cout << "tum2lcm: wrote " << s.frames << " frames to " << args.output.string() << " on " << options.channel
            << ", colour " << lcm::to_string(options.encoding.colour) << ", depth "
            << lcm::to_string(options.encoding.depth) << ", " << s.bytes << " bytes ("
            << (s.frames > 0 ? s.bytes / s.frames : 0) << " per frame)\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  CLI::App app(kDescription, "tum2lcm");
  program::describe(app, kSynopsis);
  add_options(app, args);
  return program::cli_main(app, argc, argv, [&] { return run(args); });
}
