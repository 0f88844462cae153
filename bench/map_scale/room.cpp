#include "room.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "backend_probe.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/private_network.hpp"

namespace cvo::bench {
namespace fs = std::filesystem;
using namespace std::chrono_literals;

fs::path write_back_and_forth(const fs::path& sequence, const fs::path& dir, std::size_t frames) {
  const auto seq = io::TumSequence::open(sequence);
  const auto& files = seq.files();
  if (files.size() < 2) throw std::runtime_error("map_scale: " + sequence.string() + " has fewer than 2 frames");
  fs::create_directories(dir);
  if (fs::exists(sequence / "camera.yaml"))
    fs::copy_file(sequence / "camera.yaml", dir / "camera.yaml", fs::copy_options::overwrite_existing);
  std::ofstream rgb(dir / "rgb.txt"), depth(dir / "depth.txt");
  const std::size_t period = 2 * (files.size() - 1);  // 0 1 .. n-1 n-2 .. 1, then again
  for (std::size_t k = 0; k < frames; ++k) {
    const std::size_t phase = k % period;
    const auto& f = files[phase < files.size() ? phase : period - phase];
    char stamp[32];
    std::snprintf(stamp, sizeof stamp, "%.6f", 1.0e9 + static_cast<double>(k) / 30.0);
    rgb << stamp << ' ' << fs::absolute(f.rgb).string() << '\n';
    depth << stamp << ' ' << fs::absolute(f.depth).string() << '\n';
  }
  if (!rgb || !depth) throw std::runtime_error("map_scale: cannot write " + dir.string());
  return dir;
}

namespace {

void print_row(double minutes, const Snapshot& s) {
  std::printf("| %.1f | %zu | %zu | %zu | %.1f | %.1f | %d |\n", minutes, s.published.tracker_poses,
              s.published.tracker_keyframes, s.published.last_map_keyframes, double(s.store_bytes) / 1e6,
              double(s.rss_bytes) / 1e6, s.published.waiting);
  std::fflush(stdout);
}

std::unique_ptr<testing::DaemonProcess> start_tracker(const fs::path& folder, const RoomRun& run, const fs::path& log) {
  std::vector<std::string> args{"--source",        "tum:" + folder.string(),
                                "--lcm-url",       testing::kPrivateLcmUrl,
                                "--deterministic", "--exit-on-eof",
                                "--set",           run.paced ? "trackerd.paced=true" : "trackerd.paced=false",
                                "--set",           "trackerd.realtime_priority=0",
                                "--set",           "trackerd.lock_memory=false"};
  for (const auto& s : run.settings) args.insert(args.end(), {"--set", s});
  return std::make_unique<testing::DaemonProcess>(fs::path(CVO_TOOLS_DIR) / "cvo-trackerd", args, log);
}

}  // namespace

std::size_t room(const RoomRun& run, const fs::path& scratch) {
  const fs::path dir = scratch / "room";
  const auto frames = static_cast<std::size_t>(std::lround(run.minutes * 60 * 30));
  const auto folder =
      write_back_and_forth(run.sequence, dir / (run.sequence.filename().string() + "_back_and_forth"), frames);
  BackendProbe probe(fs::path(CVO_TOOLS_DIR) / "cvo-backendd", dir, run.settings);
  const auto start = std::chrono::steady_clock::now();
  const auto minutes = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / 60;
  };
  std::printf(
      "\nroom: %s forward and back, %zu frames (%.0f min at 30 Hz), %s:\n\n| minutes | frames tracked | "
      "keyframes sent | keyframes in the map | store MB | RSS MB | records waiting |\n| --- | --- | --- | --- | --- | "
      "--- | --- |\n",
      run.sequence.filename().c_str(), frames, run.minutes, run.paced ? "paced" : "unpaced");
  auto tracker = start_tracker(folder, run, dir / "trackerd.txt");
  for (double next = 1; !tracker->wait_for(1000ms);)
    if (minutes() >= next) {
      print_row(minutes(), probe.snapshot());
      next += 1;
    }
  std::this_thread::sleep_for(6s);  // the back end's next CVO_STATUS and CVO_MAP (map_period_s 5)
  const auto done = probe.snapshot();
  print_row(minutes(), done);
  const auto stop_start = std::chrono::steady_clock::now();
  const int code = probe.stop();
  const double stop_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - stop_start).count();
  std::printf("\ntracker exit %d; SIGTERM to cvo-backendd: exit %d after %.1f s; final store %.1f MB\n",
              tracker->wait_for(0ms).value_or(-9), code, stop_s, double(probe.snapshot().store_bytes) / 1e6);
  return static_cast<std::size_t>(std::max(0, done.published.waiting)) + (code != 0 || stop_s > 30 ? 1 : 0);
}

}  // namespace cvo::bench
