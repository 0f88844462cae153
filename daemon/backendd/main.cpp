// cvo-backendd: loop closure and pose-graph optimisation as a separate process
// (daemon/backendd/backendd.hpp for its threads).
//
// A contract that scripts and the systemd unit rely on (extras may be added, nothing changed):
//   cvo-backendd [--config FILE] [--lcm-url URL] [--store FILE] [--set key=value]...
//                [--publish-url URL] [--exit-on-eof]
//   exit status 0 after SIGTERM/SIGINT/SIGHUP (or the end of a file:// input with --exit-on-eof); 1 when the
//   configuration, the store or the vocabulary is unusable (the message says which); 2 on a usage error.
#include <malloc.h>

#include <csignal>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "daemon/backendd/backendd.hpp"
#include "libcvo/config/config.hpp"
#include "program/cli.hpp"

namespace {

using namespace cvo;

constexpr const char* kDescription =
    R"(Receives CVO_KEYFRAME and CVO_LOCAL_GRAPH from cvo-trackerd sessions, stores them durably (a
restart resumes every session received; a keyframe repeated with other content is refused),
detects and verifies loop closures across every session (ORB bag of words, RANSAC + SVD, CVO
refinement, the alpha test), joins a new session to the map at its first verified loop, optimises
the keyframe pose graph with a Cauchy kernel on loops, and publishes the multi-session map on
CVO_MAP after each change, with a CVO_STATUS heartbeat. On SIGTERM, SIGINT or SIGHUP it runs a
final global optimisation, publishes the final map and exits 0. Under systemd it sends READY,
STATUS and WATCHDOG notifications.)";

struct Arguments {
  bool print_config = false;
  std::optional<std::string> config_file, lcm_url, store, publish_url;
  bool exit_on_eof = false;
  std::vector<std::string> sets;
};

void add_options(CLI::App& app, Arguments& args) {
  app.add_option("--config", args.config_file,
                 "YAML configuration (the backendd section; every key: libcvo/config/default.yaml)")
      ->type_name("FILE");
  app.add_option("--lcm-url", args.lcm_url, "LCM provider (backendd.lcm_url)")->type_name("URL");
  app.add_option("--store", args.store, "the keyframe store (backendd.store)")->type_name("FILE");
  app.add_option("--publish-url", args.publish_url,
                 "LCM provider CVO_MAP and CVO_STATUS go to (backendd.publish_url; default: --lcm-url)")
      ->type_name("URL");
  app.add_flag("--exit-on-eof", args.exit_on_eof,
               "with a file:// --lcm-url (a recording): at its end, the final optimisation, the final map, exit 0 "
               "(backendd.exit_on_eof)");
  program::add_set_option(app, args.sets, "backendd.status_period_s=2");
  app.add_flag("--print-config", args.print_config, "print the effective configuration as YAML and exit");
}

int run(const Arguments& args) {
  config::Config config = args.config_file ? config::load_config(*args.config_file) : config::Config{};
  for (const auto& s : args.sets) config::apply_override(config, s);
  if (args.lcm_url) config::apply_override(config, "backendd.lcm_url=" + *args.lcm_url);
  if (args.store) config::apply_override(config, "backendd.store=" + *args.store);
  if (args.publish_url) config::apply_override(config, "backendd.publish_url=" + *args.publish_url);
  if (args.exit_on_eof) config::apply_override(config, "backendd.exit_on_eof=true");
  if (args.print_config) {
    std::cout << config::dump_config(config);
    return 0;
  }
  // A file-size limit (ulimit -f, LimitFSIZE=) must fail a store write with EFBIG, which the store
  // survives (it holds the record), rather than kill the daemon with SIGXFSZ.
  std::signal(SIGXFSZ, SIG_IGN);
  daemon::backendd::Backendd backendd(std::move(config));
  return backendd.run();
}

}  // namespace

int main(int argc, char** argv) {
  // A keyframe's images and clouds (hundreds of kB each) come and go with every record. glibc's
  // threshold for mapping a block of its own rises past them after the first is freed, and from then
  // on they are cut from the heap and leave it fragmented: the resident size grows with the hours
  // while the heap in use does not (bench/odometry-tuning.md, "The back end as the map grows"). A
  // fixed threshold keeps them mapped, so each goes back to the system when freed.
  mallopt(M_MMAP_THRESHOLD, 128 * 1024);
  Arguments args;
  CLI::App app(kDescription, "cvo-backendd");
  program::describe(app, "cvo-backendd [--config FILE] [--lcm-url URL] [--store FILE] [options]");
  add_options(app, args);
  return program::cli_main(app, argc, argv, [&] { return run(args); });
}
