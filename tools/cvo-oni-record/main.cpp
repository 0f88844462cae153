// cvo-oni-record: records an OpenNI2 device (a camera, or the virtual device playing a TUM folder)
// into an .oni file with OpenNI2's own Recorder, so that `--source openni2:OUT.oni` replays it.
//
// A contract that scripts rely on: the positional arguments URI and OUT.oni, --frames, and the exit
// codes 0 (recorded), 1 (the device or the file does not open; the message names it) and 2 (usage).
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "drivers/openni2_source.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "program/cli.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;

constexpr const char* kDescription =
    R"(Records the depth and colour streams of the OpenNI2 device URI into OUT.oni with OpenNI2's own
Recorder (depth lossless, colour uncompressed), in the modes cvo-trackerd's openni2: source asks for.
It stops after --frames frames, at the device's end (the virtual device at the end of its folder),
when the device is unplugged, or on SIGINT/SIGTERM.
  URI  as after openni2: in --source: "any" (the first camera), a device URI as OpenNI lists it, or
       cvo-virtual:DIR (the TUM folder DIR through the project's virtual device, every frame).
)";

struct Arguments {
  std::string uri;
  fs::path out;
  std::uint64_t frames = 0;
};

volatile std::sig_atomic_t g_stop = 0;  // a signal handler can only set a flag
extern "C" void on_signal(int) { g_stop = 1; }

int run(const Arguments& args) {
  drivers::SourceOptions options;
  options.realtime = false;  // the virtual device then sends one frame per read: none is missed
  const auto source = drivers::open_openni2_recording(args.uri, args.out, options);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  core::RgbdFrame frame;
  std::uint64_t recorded = 0;
  std::string why = "stopped";
  while (g_stop == 0 && (args.frames == 0 || recorded < args.frames)) {
    const auto r = source->read(frame, std::chrono::milliseconds(200));
    if (r.status == drivers::ReadStatus::kFrame)
      ++recorded;
    else if (r.status == drivers::ReadStatus::kEndOfStream) {
      why = "the device ended";
      break;
    } else if (r.status == drivers::ReadStatus::kDisconnected) {
      why = r.message;
      break;
    }
  }
  if (args.frames != 0 && recorded == args.frames) why = "--frames reached";
  std::printf("recorded %llu frames of %s into %s (%s)\n", static_cast<unsigned long long>(recorded),
              source->describe().c_str(), args.out.c_str(), why.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  CLI::App app(kDescription, "cvo-oni-record");
  program::describe(app, "cvo-oni-record URI OUT.oni [--frames N]");
  app.add_option("URI", args.uri, "the OpenNI2 device")->required();
  app.add_option("OUT.oni", args.out, "the recording to write")->required();
  app.add_option("--frames", args.frames, "stop after N frames (0: at the device's end)")->transform(program::kDecimal);
  return program::cli_main(app, argc, argv, [&] { return run(args); });
}
