// bench/map_scale: the back end as a map grows, and as a robot revisits one route (issue #27).
//
// Sessions are driven along routes (route.hpp: real and rendered sequences tracked once, every
// keyframe image perturbed per session) into the real cvo-backendd over the private bus
// (backend_probe.hpp), one session after another as a robot restarted at its dock would. Printed:
//   growth    at each map size N (keyframes fed): over the last keyframes before N (the last half
//             below 1000, the last tenth above), the latency per keyframe (keyframe in, its
//             session's map update out) p50 and p99; bytes of a CVO_MAP_CORRECTION on average,
//             bytes of CVO_MAP per keyframe fed; the daemon's RSS and store bytes at N; and the
//             same keyframes through an in-process slam::Mapper, split by what they cost: the ones
//             that only looked for loops (bag of words, RANSAC, CVO, α) and the ones whose loop
//             started an optimisation of the keyframe graph.
//   revisits  the first route driven V times: store bytes, the daemon's RSS and latency after visits 1, 2, 5,
//             every 20th and V, and the store's growth against one visit.
//   room      one tracker session revisiting one room without pause, through the real cvo-trackerd
//             (room.hpp): store, RSS and records waiting minute by minute, and the stop timed.
// Run (it enters a private network namespace itself; root, as the networked tests):
//   build/release/bin/map_scale [--keyframes 100,1000,10000] [--visits 20] [--sequence DIR]...
//   build/release/bin/map_scale --keyframes 10 --visits 0 --room-minutes 60 [--room-sequence DIR] [--room-unpaced]
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "backend_probe.hpp"
#include "libcvo/config/config.hpp"
#include "libcvo/config/mapper_parameters.hpp"
#include "libcvo/config/module_parameters.hpp"
#include "libcvo/core/units.hpp"
#include "libcvo/eval/percentile.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/lcm/local_graph_conversion.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/registration/point_selection.hpp"
#include "libcvo/slam/mapper.hpp"
#include "program/cli.hpp"
#include "room.hpp"
#include "route.hpp"
#include "tests/support/loop_orbit.hpp"

namespace cvo::bench {
namespace {
namespace fs = std::filesystem;

struct Options {
  std::vector<std::size_t> sizes{100, 1000};
  std::size_t visits = 20;
  std::vector<fs::path> sequences;
  std::vector<std::string> settings;
  bool mapper = true;
  double room_minutes = 0;
  bool room_paced = true;
  fs::path room_sequence;  // "": fr1/rpy of ../shared, else the sample
  fs::path keep;           // "": a temporary scratch folder
};

// A folder of its own, removed with everything in it; or `keep`, made if need be and kept (the
// daemons' logs and stores, to look into after the run).
class ScratchDir {
 public:
  explicit ScratchDir(const fs::path& keep) : keep_(!keep.empty()) {
    if (keep_) {
      fs::create_directories(keep);
      path_ = keep;
      return;
    }
    std::string name = (fs::temp_directory_path() / "map_scale_XXXXXX").string();
    if (!mkdtemp(name.data())) throw std::runtime_error("map_scale: cannot make a temporary folder");
    path_ = name;
  }
  ~ScratchDir() {
    std::error_code ec;
    if (!keep_) fs::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  [[nodiscard]] const fs::path& path() const { return path_; }

 private:
  fs::path path_;
  bool keep_ = false;
};

std::vector<Route> routes(const Options& options, const config::Config& config, const fs::path& scratch) {
  std::vector<fs::path> folders = options.sequences;
  if (folders.empty()) {
    folders = {fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50", testing::write_loop_orbit(scratch)};
    const fs::path shared = fs::path(CVO_SHARED_DATA_DIR) / "tum" / "fr1_rpy";
    if (fs::exists(shared / "rgb.txt")) folders.push_back(shared);
  }
  std::vector<Route> out;
  for (const auto& f : folders) {
    out.push_back(track_route(f.filename().string(), f, config));
    std::fprintf(stderr, "route %s: %zu keyframes\n", out.back().name.c_str(), out.back().keyframes);
  }
  return out;
}

// What one session sends, message by message, with the in-process mapper fed alongside.
class SessionDriver {
 public:
  SessionDriver(const config::Config& config, BackendProbe& probe, slam::Mapper* mapper)
      : config_(config),
        probe_(probe),
        mapper_(mapper),
        encoding_{*lcm::parse_colour_encoding(config.trackerd.keyframe_colour_encoding), lcm::DepthEncoding::kPng} {}

  struct KeyframeCost {
    std::optional<double> latency_ms;
    double mapper_ms = 0;
    bool optimised = false;
  };

  static constexpr const char* kRobot = "map-scale";  // the robot its messages name

  // Drives `route` as session `session`, images perturbed by `seed`; calls `each` per keyframe.
  template <class Each>
  void drive(const Route& route, std::int64_t session, std::uint64_t seed, Each&& each) {
    std::size_t held = 0;
    for (const auto& step : route.steps) {
      if (step.graph) graph(session, *step.graph);
      if (step.keyframe) each(keyframe(session, *step.keyframe, seed, ++held));
    }
  }

 private:
  void graph(std::int64_t session, const RouteGraph& g) {
    probe_.publish_graph(lcm::encode(lcm::to_message(g.graph, session, g.keyframe_id, core::wall_utime(), kRobot)));
    if (mapper_) mapper_->add_local_graph(session, g.keyframe_id, g.graph);
  }

  KeyframeCost keyframe(std::int64_t session, const RouteKeyframe& k, std::uint64_t seed, std::size_t held) {
    lcm::Keyframe message{session,
                          k.id,
                          perturbed(k.frame, seed ^ static_cast<std::uint64_t>(k.id) << 20),
                          k.pose,
                          registration::PointCloud(config_.odometry.max_points),
                          kRobot};
    registration::PointSelector selector(k.frame.bgr.cols, k.frame.bgr.rows, config_.selection);
    selector.select(message.frame, message.cloud);
    std::string error;
    const auto encoded = lcm::to_message(message, encoding_, &error);
    if (!encoded) throw std::runtime_error("map_scale: keyframe not encoded: " + error);
    KeyframeCost cost;
    cost.latency_ms = probe_.publish_keyframe(session, held, lcm::encode(*encoded));
    if (mapper_) {
      const auto optimisations = mapper_->optimisations();
      const auto start = core::SteadyClock::now();
      mapper_->add_keyframe({session, k.id, message.frame, k.pose, message.cloud, kRobot});
      cost.mapper_ms = core::ms_since(start);
      cost.optimised = mapper_->optimisations() != optimisations;
    }
    return cost;
  }

  const config::Config& config_;
  BackendProbe& probe_;
  slam::Mapper* mapper_;
  lcm::RgbdEncoding encoding_;
};

std::int64_t session_id(std::size_t ordinal) {
  std::mt19937_64 g(ordinal + 1);
  return static_cast<std::int64_t>(g() >> 1) + 1;
}

struct Window {
  std::vector<double> latency_ms, search_ms, optimise_ms;
  std::size_t missing = 0;  // keyframes whose update did not come
};

double p(const std::vector<double>& v, double q) { return v.empty() ? NAN : eval::percentile(v, q); }

void print_growth_header(bool mapper) {
  std::printf(
      "\n| keyframes | sessions | latency p50 ms | latency p99 ms | CVO_MAP_CORRECTION bytes | CVO_MAP bytes / "
      "keyframe "
      "| RSS MB | store MB |%s\n| --- | --- | --- | --- | --- | --- | --- | --- |%s\n",
      mapper ? " loop search p50 / p99 ms | with optimisation p50 / p99 ms (n) |" : "", mapper ? " --- | --- |" : "");
}

void print_growth_row(std::size_t n, std::size_t sessions, const Window& w, const Snapshot& from, const Snapshot& to,
                      std::size_t fed, bool mapper) {
  const auto corrections = to.published.corrections - from.published.corrections;
  const double per_correction =
      corrections ? double(to.published.correction_bytes - from.published.correction_bytes) / double(corrections) : NAN;
  const double map_per_keyframe = double(to.published.map_bytes - from.published.map_bytes) / double(fed);
  std::printf("| %zu | %zu | %.1f | %.1f | %.0f | %.0f | %.0f | %.1f |", n, sessions, p(w.latency_ms, 50),
              p(w.latency_ms, 99), per_correction, map_per_keyframe, double(to.rss_bytes) / 1e6,
              double(to.store_bytes) / 1e6);
  if (mapper)
    std::printf(" %.1f / %.1f | %.1f / %.1f (%zu) |", p(w.search_ms, 50), p(w.search_ms, 99), p(w.optimise_ms, 50),
                p(w.optimise_ms, 99), w.optimise_ms.size());
  if (w.missing) std::printf(" %zu updates missing", w.missing);
  std::printf("\n");
  std::fflush(stdout);
}

std::size_t window_of(std::size_t n) { return n <= 1000 ? n / 2 : n / 10; }

// Returns the keyframes whose update never came.
std::size_t growth(const Options& options, const config::Config& config, const std::vector<Route>& routes,
                   const fs::path& scratch) {
  const fs::path dir = scratch / "growth";
  fs::create_directories(dir);
  BackendProbe probe(fs::path(CVO_TOOLS_DIR) / "cvo-backendd", dir, options.settings);
  std::optional<slam::Mapper> mapper;
  if (options.mapper)
    mapper.emplace(loop_closure::Vocabulary::load(loop_closure::default_vocabulary_file()),
                   config::mapper_parameters(config));
  SessionDriver driver(config, probe, mapper ? &*mapper : nullptr);
  auto sizes = options.sizes;
  std::sort(sizes.begin(), sizes.end());
  print_growth_header(options.mapper);
  std::size_t fed = 0, next = 0, session = 0, missing = 0;
  Window window;
  Snapshot start = probe.snapshot();
  while (next < sizes.size()) {
    const Route& route = routes[session % routes.size()];
    driver.drive(route, session_id(session), session + 1, [&](const SessionDriver::KeyframeCost& c) {
      if (next >= sizes.size()) return;
      ++fed;
      if (fed + window_of(sizes[next]) == sizes[next] + 1) {
        window = {};
        start = probe.snapshot();
      }
      if (c.latency_ms) {
        window.latency_ms.push_back(*c.latency_ms);
      } else {
        ++window.missing;
        ++missing;
      }
      if (mapper) (c.optimised ? window.optimise_ms : window.search_ms).push_back(c.mapper_ms);
      if (fed == sizes[next]) {
        print_growth_row(fed, session + 1, window, start, probe.snapshot(), window_of(fed), options.mapper);
        ++next;
      }
    });
    ++session;
  }
  probe.stop();
  return missing;
}

// Returns the keyframes whose update never came.
std::size_t revisits(const Options& options, const config::Config& config, const Route& route,
                     const fs::path& scratch) {
  const fs::path dir = scratch / "revisits";
  fs::create_directories(dir);
  BackendProbe probe(fs::path(CVO_TOOLS_DIR) / "cvo-backendd", dir, options.settings);
  SessionDriver driver(config, probe, nullptr);
  std::printf(
      "\nrevisits of %s (%zu keyframes a visit):\n\n| visits | keyframes fed | store MB | store / one visit | "
      "latency p50 ms | latency p99 ms | RSS MB |\n| --- | --- | --- | --- | --- | --- | --- |\n",
      route.name.c_str(), route.keyframes);
  double one_visit = 0;
  std::size_t missing = 0;
  for (std::size_t v = 1; v <= options.visits; ++v) {
    std::vector<double> latency;
    driver.drive(route, session_id(1000000 + v), 1000000 + v, [&](const SessionDriver::KeyframeCost& c) {
      if (c.latency_ms)
        latency.push_back(*c.latency_ms);
      else
        ++missing;
    });
    const auto snapshot = probe.snapshot();
    const double store = double(snapshot.store_bytes);
    if (v == 1) one_visit = store;
    if (v == 1 || v == 2 || v == 5 || v % 20 == 0 || v == options.visits)
      std::printf("| %zu | %zu | %.2f | %.2f | %.1f | %.1f | %.1f |\n", v, v * route.keyframes, store / 1e6,
                  store / one_visit, p(latency, 50), p(latency, 99), double(snapshot.rss_bytes) / 1e6);
    std::fflush(stdout);
  }
  probe.stop();
  std::printf("\nkeyframes in the final CVO_MAP: %zu\n", probe.snapshot().published.last_map_keyframes);
  return missing;
}

fs::path room_sequence(const Options& options) {
  if (!options.room_sequence.empty()) return options.room_sequence;
  const fs::path shared = fs::path(CVO_SHARED_DATA_DIR) / "tum" / "fr1_rpy";
  return fs::exists(shared / "rgb.txt") ? shared : fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";
}

int run(Options options) {
  std::erase(options.sizes, std::size_t{0});
  config::Config config;
  for (const auto& s : options.settings) config::apply_override(config, s);
  const ScratchDir scratch(options.keep);
  std::size_t missing = 0;
  if (!options.sizes.empty() || options.visits > 0) {
    const auto all = routes(options, config, scratch.path());
    if (!options.sizes.empty()) missing += growth(options, config, all, scratch.path());
    if (options.visits > 0) missing += revisits(options, config, all.front(), scratch.path());
  }
  if (options.room_minutes > 0)
    missing +=
        room({room_sequence(options), options.room_minutes, options.room_paced, options.settings}, scratch.path());
  if (missing)
    std::fprintf(stderr, "map_scale: %zu keyframes had no map update within 60 s, or records waited\n", missing);
  return missing ? 1 : 0;
}

// The bench speaks UDP multicast: only ever inside a private network namespace of its own.
void enter_private_network(int argc, char** argv) {
  if (std::getenv("CVO_PRIVATE_NETNS")) return;
  const std::string script = std::string(CVO_SOURCE_DIR) + "/tests/support/in-private-netns";
  std::vector<char*> args{const_cast<char*>(script.c_str())};
  const std::string self = fs::canonical("/proc/self/exe").string();
  args.push_back(const_cast<char*>(self.c_str()));
  for (int i = 1; i < argc; ++i) args.push_back(argv[i]);
  args.push_back(nullptr);
  execv(script.c_str(), args.data());
  std::perror("map_scale: in-private-netns");
  std::exit(1);
}

}  // namespace
}  // namespace cvo::bench

int main(int argc, char** argv) {
  cvo::bench::enter_private_network(argc, argv);
  CLI::App app;
  cvo::program::describe(app, "map_scale [--keyframes N,N,...] [--visits V] [--sequence DIR]... [--set key=value]...",
                         "The back end (cvo-backendd) as the map grows and as one route is revisited: a table.");
  cvo::bench::Options o;
  app.add_option("--keyframes", o.sizes, "map sizes to report at (keyframes fed; 0: none)")->delimiter(',');
  app.add_option("--visits", o.visits, "visits of the first route in the revisit run (0: none)");
  app.add_option("--sequence", o.sequences, "TUM folders to drive (default: the sample, a rendered orbit, fr1/rpy)");
  app.add_option("--room-minutes", o.room_minutes, "room run: minutes of frames at 30 Hz (0: none)");
  app.add_option("--room-sequence", o.room_sequence,
                 "room run: the TUM folder played back and forth (default: fr1/rpy)");
  app.add_flag("!--room-unpaced", o.room_paced, "room run: frames as fast as the tracker takes them");
  app.add_option("--keep", o.keep, "scratch folder to use and keep (the daemons' logs and stores)");
  app.add_flag("!--no-mapper", o.mapper, "skip the in-process mapper's loop-search / optimisation split");
  cvo::program::add_set_option(app, o.settings, "backendd.map_period_s=5");
  return cvo::program::cli_main(app, argc, argv, [&] { return cvo::bench::run(o); });
}
