// Robots on a real (simulated) LAN, issue 28: each cvo-trackerd in its own network namespace, the
// back end in another, joined by a bridge (tests/support/in-simulated-lan), LCM udpm with ttl=1,
// every host losing CVO_LAN_LOSS % of the UDP datagrams it receives (nftables). Three live robots
// track the embedded clip at its 30 Hz and stay up after its last frame, as a robot's tracker does;
// every keyframe each of them made must be in the back end's map while they run, and in its final
// map after they stop and it stops.
//
// Eight robots (a fleet's back end): eight recorded tracker streams (each a robot of its own name, in
// slices, at the camera's rate) played from eight hosts at once; every session joins the map with
// every keyframe, the back end drops nothing from its queue, and `cvo-log status` lists all eight.
//
// Runs as the last host (ip netns exec lan-N under in-simulated-lan --hosts N, N = robots + 1); the
// robots run on lan-1 ... (ip netns exec lan-K).
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "cvo_lcm/status_t.hpp"
#include "tests/backendd/netns_support.hpp"
#include "tests/support/private_network.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::Captured;
using cvo::testing::DaemonProcess;
using cvo::testing::KeyframeName;
using cvo::testing::LcmCapture;

const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";
constexpr const char* kLanUrl = "udpm://239.255.76.67:7667?ttl=1&recv_buf_size=8388608";
constexpr int kRobots = 3;

// Bytes this host's eth0 has received (the kernel's count).
double received_bytes() {
  std::ifstream in("/sys/class/net/eth0/statistics/rx_bytes");
  double bytes = 0;
  in >> bytes;
  return bytes;
}

std::string lan_skip_reason(int robots) {
  const std::string last = "lan-" + std::to_string(robots + 1);
  const char* hosts = std::getenv("CVO_LAN_HOSTS");
  if (hosts == nullptr || !std::string(hosts).ends_with(last))
    return "runs only as " + last + " of tests/support/in-simulated-lan --hosts " + std::to_string(robots + 1);
  return {};
}

// CPU seconds a process has used so far (/proc/PID/stat: utime + stime).
double cpu_seconds(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::istringstream fields(text.substr(text.rfind(')') + 2));
  std::string field;
  double ticks = 0;
  for (int k = 3; k <= 15 && fields >> field; ++k)
    if (k == 14 || k == 15) ticks += std::stod(field);
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// A program on host lan-K of the simulated LAN.
std::unique_ptr<DaemonProcess> on_host(int k, const fs::path& program, std::vector<std::string> args,
                                       const fs::path& stderr_file) {
  args.insert(args.begin(), {"netns", "exec", "lan-" + std::to_string(k), program.string()});
  return std::make_unique<DaemonProcess>("/usr/sbin/ip", args, stderr_file);
}

// The back end on this host, on a store in `dir`; null (a failure said) when its CVO_STATUS is not heard.
std::unique_ptr<DaemonProcess> start_backend(const fs::path& dir, LcmCapture& capture) {
  const auto err = dir / "backendd.txt";
  auto backend = std::make_unique<DaemonProcess>(
      fs::path(CVO_TOOLS_DIR) / "cvo-backendd",
      std::vector<std::string>{"--lcm-url", kLanUrl, "--store", (dir / "keyframes.store").string()}, err);
  const int pid = backend->pid();
  if (capture.wait_until([&](const Captured& c) { return c.status_from(pid); }, 60s)) return backend;
  ADD_FAILURE() << "no CVO_STATUS from the back end\n" << cvo::testing::slurp(err);
  return nullptr;
}

// Every keyframe each session's poses name (ids from 0 to its newest).
std::set<KeyframeName> made(const Captured& c) {
  std::set<KeyframeName> names;
  for (const auto& [session, newest] : c.newest_keyframe)
    for (std::int64_t id = 0; id <= newest; ++id) names.emplace(session, id);
  return names;
}

TEST(FleetLan, ThreeLiveRobotsOverALossyLanHaveEveryKeyframeInTheMap) {
  if (const auto why = lan_skip_reason(kRobots); !why.empty()) GTEST_SKIP() << why;
  const char* loss = std::getenv("CVO_LAN_LOSS");
  cvo::test::TempDir dir;
  LcmCapture capture(dir.path() / "maps.lcmlog", kLanUrl);
  ASSERT_TRUE(capture.good());
  const auto backend_err = dir.path() / "backendd.txt";
  auto backend_process = start_backend(dir.path(), capture);
  ASSERT_TRUE(backend_process);
  DaemonProcess& backendd = *backend_process;

  const double received_before = received_bytes();
  std::vector<std::unique_ptr<DaemonProcess>> robots;
  std::vector<fs::path> robot_err;
  for (int k = 1; k <= kRobots; ++k) {
    robot_err.push_back(dir.path() / ("robot-" + std::to_string(k) + ".txt"));
    robots.push_back(on_host(k, fs::path(CVO_TOOLS_DIR) / "cvo-trackerd",
                             {"--source", "tum:" + kClip.string(), "--lcm-url", kLanUrl, "--deterministic", "--set",
                              "trackerd.realtime_priority=0", "--set", "trackerd.lock_memory=false", "--set",
                              "trackerd.robot=robot-" + std::to_string(k)},
                             robot_err.back()));
  }
  const auto logs = [&] {
    std::string text = cvo::testing::slurp(backend_err);
    for (const auto& e : robot_err) text += cvo::testing::slurp(e);
    return text;
  };
  // Every robot tracked its clip to the end (its own word), then every keyframe is in the map.
  for (const auto& e : robot_err) {
    bool ended = false;
    for (int i = 0; i < 1200 && !ended; ++i, std::this_thread::sleep_for(100ms))
      ended = cvo::testing::slurp(e).find("end of tum:") != std::string::npos;
    ASSERT_TRUE(ended) << logs();
  }
  ASSERT_TRUE(capture.wait_until([](const Captured& c) { return c.newest_keyframe.size() == kRobots; }, 10s));
  const auto keyframes = made(capture.snapshot());
  EXPECT_TRUE(capture.wait_until([&](const Captured& c) { return c.map_holds(keyframes); }, 120s))
      << "not every keyframe reached the map while the robots run\n"
      << logs();
  const double received = received_bytes() - received_before;

  for (auto& robot : robots) robot->signal(SIGTERM);
  for (auto& robot : robots) EXPECT_EQ(robot->wait_for(60s).value_or(-9), 0) << logs();
  backendd.signal(SIGTERM);
  EXPECT_EQ(backendd.wait_for(120s).value_or(-9), 0) << logs();
  ASSERT_TRUE(capture.wait_until(
      [&](const Captured& c) { return c.status_from(backendd.pid(), +cvo_lcm::status_t::STATE_STOPPING); }, 30s));
  const Captured captured = capture.snapshot();
  EXPECT_TRUE(captured.map_holds(keyframes)) << "the final map lacks keyframes\n" << logs();
  const auto& backend = captured.backend_statuses.back();
  std::cout << kRobots << " robots at " << (loss != nullptr ? loss : "0") << " % loss: " << keyframes.size()
            << " keyframes made; back end: requested " << backend.keyframes_requested << ", recovered "
            << backend.keyframes_recovered << ", lost " << backend.keyframes_lost << ", queue drops "
            << backend.queue_drops << "; the back end's link received " << received / 1e6 << " MB, "
            << received / static_cast<double>(keyframes.size()) / 1e3 << " kB per keyframe (poses, statuses included)"
            << std::endl;
  EXPECT_EQ(backend.keyframes_lost, 0) << logs();
  EXPECT_EQ(backend.queue_drops, 0);
}

// A robot's recording: cvo-trackerd on the clip at the camera's rate into an LCM log, keyframes in
// slices as on a network, under its own name.
fs::path record_robot(const fs::path& dir, int k) {
  const auto log = dir / ("robot-" + std::to_string(k) + ".lcmlog");
  DaemonProcess tracker(
      fs::path(CVO_TOOLS_DIR) / "cvo-trackerd",
      {"--source", "tum:" + kClip.string(), "--lcm-url", "file://" + log.string() + "?mode=w", "--deterministic",
       "--exit-on-eof", "--set", "trackerd.realtime_priority=0", "--set", "trackerd.lock_memory=false", "--set",
       "trackerd.keyframe_transport=chunks", "--set", "trackerd.robot=robot-" + std::to_string(k)},
      dir / ("robot-" + std::to_string(k) + ".txt"));
  EXPECT_EQ(tracker.wait_for(120s).value_or(-9), 0)
      << cvo::testing::slurp(dir / ("robot-" + std::to_string(k) + ".txt"));
  return log;
}

TEST(FleetLan, EightReplayedRobotsAllJoinWithNoQueueDropAndStatusListsThemAll) {
  constexpr int kFleet = 8;
  if (const auto why = lan_skip_reason(kFleet); !why.empty()) GTEST_SKIP() << why;
  cvo::test::TempDir dir;
  std::vector<fs::path> logs;
  for (int k = 1; k <= kFleet; ++k) logs.push_back(record_robot(dir.path(), k));
  LcmCapture capture(dir.path() / "fleet.lcmlog", kLanUrl);
  ASSERT_TRUE(capture.good());
  const auto backend_err = dir.path() / "backendd.txt";
  auto backend_process = start_backend(dir.path(), capture);
  ASSERT_TRUE(backend_process);
  DaemonProcess& backendd = *backend_process;

  const double cpu_before = cpu_seconds(backendd.pid()), received_before = received_bytes();
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::unique_ptr<DaemonProcess>> players;
  for (int k = 1; k <= kFleet; ++k)
    players.push_back(on_host(k, cvo::testing::which("lcm-logplayer"),
                              {"--lcm-url=" + std::string(kLanUrl), logs[static_cast<std::size_t>(k - 1)].string()},
                              dir.path() / ("player-" + std::to_string(k) + ".txt")));
  for (auto& p : players) EXPECT_EQ(p->wait_for(120s).value_or(-9), 0);
  ASSERT_TRUE(capture.wait_until([](const Captured& c) { return c.newest_keyframe.size() == kFleet; }, 10s));
  const auto keyframes = made(capture.snapshot());
  const auto joined = [&](const Captured& c) {
    return c.map_holds(keyframes) && c.map && c.map->sessions.size() == kFleet &&
           std::all_of(c.map->sessions.begin(), c.map->sessions.end(), [](const auto& s) { return s.placed; });
  };
  EXPECT_TRUE(capture.wait_until(joined, 180s)) << "not every robot joined the map with every keyframe\n"
                                                << cvo::testing::slurp(backend_err);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double cpu = cpu_seconds(backendd.pid()) - cpu_before, received = received_bytes() - received_before;
  backendd.signal(SIGTERM);
  EXPECT_EQ(backendd.wait_for(120s).value_or(-9), 0) << cvo::testing::slurp(backend_err);
  ASSERT_TRUE(capture.wait_until(
      [&](const Captured& c) { return c.status_from(backendd.pid(), +cvo_lcm::status_t::STATE_STOPPING); }, 30s));
  const auto& backend = capture.snapshot().backend_statuses.back();
  EXPECT_EQ(backend.queue_drops, 0);
  EXPECT_EQ(backend.keyframes_lost, 0);
  std::cout << kFleet << " robots, " << keyframes.size() << " keyframes, all joined in " << seconds
            << " s: the back end used " << cpu << " CPU s (" << cpu / kFleet << " per robot, each a "
            << "1.7 s clip); its link received " << received / static_cast<double>(keyframes.size()) / 1e3
            << " kB per keyframe; queue drops " << backend.queue_drops << "; keyframes requested "
            << backend.keyframes_requested << ", recovered " << backend.keyframes_recovered << ", lost "
            << backend.keyframes_lost << std::endl;

  const auto status = cvo::testing::run_tool("cvo-log", "status " + (dir.path() / "fleet.lcmlog").string(), dir.path());
  EXPECT_EQ(status.exit_code, 0) << status.err;
  for (int k = 1; k <= kFleet; ++k)
    EXPECT_NE(status.out.find("robot-" + std::to_string(k)), std::string::npos) << status.out;
}

}  // namespace
}  // namespace cvo::daemon
