// cvo-trackerd: the realtime tracking daemon (daemon/trackerd/trackerd.hpp for its threads).
//
// A contract that scripts and the systemd unit rely on (extras may be added, nothing changed):
//   cvo-trackerd [--config FILE] [--source SPEC] [--lcm-url URL] [--exit-on-eof] [--set key=value]...
//   exit status 0 after SIGTERM/SIGINT/SIGHUP or the end of the source with --exit-on-eof; 1 when the
//   configuration or the source is unusable (the message says which); 2 on a usage error.
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "daemon/trackerd/trackerd.hpp"
#include "libcvo/config/config.hpp"
#include "program/cli.hpp"

namespace {

using namespace cvo;

constexpr const char* kDescription =
    R"(Tracks an RGB-D stream with keyframe-based CVO in a realtime thread and publishes on LCM:
CVO_POSE (every frame), CVO_KEYFRAME, CVO_LOCAL_GRAPH (when a keyframe closes one, and the open
one at the end) and CVO_STATUS (once a second). Every start, and every camera that comes back
after a disconnection, is a new session with a random id carried by every message. The map pose
follows the newest CVO_MAP_CORRECTION (or CVO_MAP) from cvo-backendd once it places this
session. Stops cleanly on SIGTERM, SIGINT or SIGHUP, even in the first instant; under systemd it
sends READY, STATUS and WATCHDOG notifications.)";

constexpr const char* kSources = R"(sources (--source, trackerd.source):
  tum:DIR              a TUM RGB-D folder (trackerd.paced: at recorded rate)
  lcm:URL              CVO_RGBD messages, live (udpm://...) or a log (file://...)
  openni2:URI          an OpenNI2 device (openni2:any) or an .oni recording
  v4l2:COLOUR,DEPTH    V4L2 device nodes (intrinsics from the camera key))";

struct Arguments {
  bool print_config = false;
  std::optional<std::string> config_file, source, lcm_url;
  bool exit_on_eof = false, deterministic = false;
  std::vector<std::string> sets;
};

void add_options(CLI::App& app, Arguments& args) {
  app.add_option(
         "--config", args.config_file,
         "YAML configuration (every key: libcvo/config/default.yaml; the trackerd section configures this daemon)")
      ->type_name("FILE");
  app.add_option("--source", args.source, "frame source (trackerd.source; the forms below)")->type_name("SPEC");
  app.add_option("--lcm-url", args.lcm_url, "where results are published (trackerd.lcm_url)")->type_name("URL");
  app.add_flag("--exit-on-eof", args.exit_on_eof, "exit 0 when a finite source ends, after tracking every frame");
  app.add_flag("--deterministic", args.deterministic, "never drop frames: a replay gives the same poses every time");
  program::add_set_option(app, args.sets, "trackerd.ring_slots=8");
  app.add_flag("--print-config", args.print_config, "print the effective configuration as YAML and exit");
}

int run(const Arguments& args) {
  config::Config config = args.config_file ? config::load_config(*args.config_file) : config::Config{};
  for (const auto& s : args.sets) config::apply_override(config, s);
  if (args.source) config::apply_override(config, "trackerd.source=" + *args.source);
  if (args.lcm_url) config::apply_override(config, "trackerd.lcm_url=" + *args.lcm_url);
  if (args.exit_on_eof) config.trackerd.exit_on_eof = true;
  if (args.deterministic) config.trackerd.deterministic = true;
  if (args.print_config) {
    std::cout << config::dump_config(config);
    return 0;
  }
  daemon::trackerd::Trackerd trackerd(std::move(config));
  return trackerd.run();
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  CLI::App app(kDescription, "cvo-trackerd");
  program::describe(app, "cvo-trackerd [--config FILE] [--source SPEC] [--lcm-url URL] [options]", kSources);
  add_options(app, args);
  return program::cli_main(app, argc, argv, [&] { return run(args); });
}
