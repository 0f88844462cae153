// cvo-trackerd end to end, as systemd and scripts run it: the real executable, real LCM (file://
// providers here, so no packet leaves the process; the UDP multicast replay is in
// trackerd_netns_test.cpp), real recordings made by tum2lcm or written event by event.
#include <sys/mount.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "libcvo/eval/ate.hpp"
#include "libcvo/eval/rpe.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/lcm/map_conversion.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"
#include "tests/lcm/image_bombs.hpp"
#include "tests/support/cli_contract.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/lcm_log.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/slowdown.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using cvo::testing::DaemonProcess;

const fs::path kTrackerd = fs::path(CVO_TOOLS_DIR) / "cvo-trackerd";
const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";

// Settings every test uses: no realtime priority or locked memory (tests share a small machine),
// results into an LCM log file.
std::vector<std::string> base_args(const fs::path& out_log) {
  return {"--lcm-url", "file://" + out_log.string() + "?mode=w",
          "--set",     "trackerd.realtime_priority=0",
          "--set",     "trackerd.lock_memory=false",
          "--set",     "trackerd.paced=false"};
}

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

std::string hex(std::int64_t session) {
  char text[19];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(session));
  return text;
}

// Messages of every channel whose session is not `session`.
std::size_t count_other_sessions(const cvo::testing::PublishedLog& log, std::int64_t session) {
  std::size_t other = 0;
  const auto count = [&](const auto& messages) {
    for (const auto& m : messages) other += m.session != session;
  };
  count(log.poses);
  count(log.keyframes);
  count(log.local_graphs);
  count(log.statuses);
  return other;
}

core::Trajectory odom_trajectory(const std::vector<cvo_lcm::pose_t>& poses) {
  core::Trajectory t;
  for (const auto& p : poses) t.push_back({lcm::from_utime(p.utime), *lcm::from_message(p.odom_pose, nullptr)});
  return t;
}

// The clip as a CVO_RGBD recording, as a camera's would be.
fs::path record_clip(const fs::path& dir) {
  const auto log = dir / "clip.lcmlog";
  const auto r = cvo::testing::run_tool("tum2lcm", cvo::testing::quoted(kClip) + " " + cvo::testing::quoted(log), dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return log;
}

TEST(Trackerd, TracksAFolderToTheEndAndPublishesEverything) {
  cvo::test::TempDir dir;
  const auto out = dir.path() / "out.lcmlog";
  DaemonProcess d(kTrackerd,
                  with(base_args(out), {"--source", "tum:" + kClip.string(), "--exit-on-eof", "--deterministic",
                                        "--set", "trackerd.robot=hall-a"}),
                  dir.path() / "stderr.txt");
  const auto code = d.wait_for(120s);
  ASSERT_TRUE(code) << "still running";
  EXPECT_EQ(*code, 0) << cvo::testing::slurp(dir.path() / "stderr.txt");

  const auto log = cvo::testing::read_published(out);
  ASSERT_EQ(log.poses.size(), 50u) << "every frame of the clip gets a pose";
  for (std::size_t i = 0; i < log.poses.size(); ++i) {
    EXPECT_EQ(log.poses[i].frame_index, static_cast<std::int64_t>(i));
    EXPECT_TRUE(log.poses[i].status == cvo_lcm::pose_t::STATUS_OK ||
                log.poses[i].status == cvo_lcm::pose_t::STATUS_FIRST_FRAME)
        << "frame " << i;
    EXPECT_GE(log.poses[i].latency_ms, 0);
  }
  // Keyframes: one per is_keyframe pose, each with its images and cloud; every closed local graph
  // starts at its keyframe.
  const auto flagged = std::count_if(log.poses.begin(), log.poses.end(), [](const auto& p) { return p.is_keyframe; });
  EXPECT_GE(log.keyframes.size(), 2u) << "50 frames of fr1/rpy rotate past the keyframe thresholds";
  EXPECT_EQ(static_cast<std::size_t>(flagged), log.keyframes.size());
  for (const auto& k : log.keyframes) {
    EXPECT_GT(k.num_points, 1000);
    EXPECT_GT(k.colour_size, 0);
  }
  // Keyframe ids count from 0 in the session; every keyframe's graph is published, the last one
  // (still open when the clip ended) too, so the back end gets every tracked frame.
  ASSERT_EQ(log.local_graphs.size(), log.keyframes.size()) << "the open local graph is published at the end";
  for (std::size_t i = 0; i < log.local_graphs.size(); ++i) {
    EXPECT_EQ(log.keyframes[i].id, static_cast<std::int64_t>(i));
    EXPECT_EQ(log.local_graphs[i].keyframe_id, log.keyframes[i].id);
    EXPECT_EQ(log.local_graphs[i].nodes.front().frame_index, log.keyframes[i].frame_index);
  }
  EXPECT_EQ(log.local_graphs.back().nodes.back().frame_index, log.poses.back().frame_index);
  EXPECT_EQ(log.poses.front().keyframe_id, 0);

  // One session: every message carries it, and the start names it.
  const std::int64_t session = log.poses.front().session;
  EXPECT_NE(session, 0);
  EXPECT_EQ(count_other_sessions(log, session), 0u);
  const auto err = cvo::testing::slurp(dir.path() / "stderr.txt");
  EXPECT_NE(err.find("session " + hex(session)), std::string::npos) << err;

  // The last status is the stopping one; the tracking thread did not allocate after warm-up.
  ASSERT_FALSE(log.statuses.empty());
  const auto& last = log.statuses.back();
  EXPECT_EQ(last.state, +cvo_lcm::status_t::STATE_STOPPING);
  EXPECT_EQ(last.process, "cvo-trackerd");
  EXPECT_EQ(last.robot, "hall-a") << "trackerd.robot";
  // ... and every tracker message names the robot.
  for (const auto& p : log.poses) EXPECT_EQ(p.robot, "hall-a") << "CVO_POSE of frame " << p.frame_index;
  for (const auto& k : log.keyframes) EXPECT_EQ(k.robot, "hall-a") << "CVO_KEYFRAME " << k.id;
  for (const auto& g : log.local_graphs) EXPECT_EQ(g.robot, "hall-a") << "CVO_LOCAL_GRAPH " << g.keyframe_id;
  EXPECT_EQ(last.allocations_after_warmup, 0);
  EXPECT_EQ(last.dropped_frames, 0) << "deterministic mode never drops";
  EXPECT_GT(last.latency_median_ms, 0);
  EXPECT_GT(last.rss_bytes, 0);

  // The daemon runs KF-CVO: same bounds as the library's KF-CVO test on this clip
  // (tests/odometry/keyframe_odometry_test.cpp, measured 0.055 m/s and 3.8-4.3 deg/s there).
  const auto groundtruth = io::TumSequence::open(kClip).groundtruth();
  const auto rpe = eval::relative_pose_error(groundtruth, odom_trajectory(log.poses));
  const auto ate = eval::absolute_trajectory_error(groundtruth, odom_trajectory(log.poses));
  std::printf("cvo-trackerd on fr1_rpy_50: RPE %.4f m/s %.3f deg/s, ATE %.4f m, latency median %.1f ms p99 %.1f ms\n",
              rpe.translation.rmse, rpe.rotation_deg.rmse, ate.error.rmse, last.latency_median_ms, last.latency_p99_ms);
  EXPECT_LT(rpe.translation.rmse, 0.10);
  EXPECT_LT(rpe.rotation_deg.rmse, 8.0);
  EXPECT_LT(ate.error.rmse, 0.06);
  // odom_pose is the library's published pose, the smooth one (smooth_position.hpp), frame for
  // frame what cvo-run --mode kf-cvo writes; the keyframes keep the tracked pose they are anchored at.
  const auto kf_cvo = cvo::testing::run_tool(
      "cvo-run", cvo::testing::quoted(kClip) + " --mode kf-cvo --out " + cvo::testing::quoted(dir.path() / "kf.txt"),
      dir.path());
  ASSERT_EQ(kf_cvo.exit_code, 0) << kf_cvo.err;
  const auto published = io::read_tum_trajectory(dir.path() / "kf.txt");
  const auto odom = odom_trajectory(log.poses);
  ASSERT_EQ(published.size(), odom.size());
  double furthest = 0;
  for (std::size_t i = 0; i < odom.size(); ++i)
    furthest = std::max(furthest, (published[i].pose.translation() - odom[i].pose.translation()).norm());
  EXPECT_LT(furthest, 1e-6) << "CVO_POSE's odom_pose against cvo-run's published pose (m)";

  // cvo-log turns the recording into what scripts use: a TUM trajectory and the last status.
  const auto poses = cvo::testing::run_tool(
      "cvo-log", "poses " + cvo::testing::quoted(out) + " --out " + cvo::testing::quoted(dir.path() / "t.txt"),
      dir.path());
  ASSERT_EQ(poses.exit_code, 0) << poses.err;
  EXPECT_EQ(io::read_tum_trajectory(dir.path() / "t.txt").size(), 50u);
  const auto status = cvo::testing::run_tool("cvo-log", "status " + cvo::testing::quoted(out) + " --json", dir.path());
  ASSERT_EQ(status.exit_code, 0) << status.err;
  EXPECT_NE(status.out.find("\"cvo-trackerd\":{"), std::string::npos) << status.out;
  EXPECT_NE(status.out.find("\"allocations_after_warmup\":0"), std::string::npos) << status.out;
  EXPECT_NE(status.out.find("\"session\":" + std::to_string(session) + ","), std::string::npos) << status.out;
  const auto text = cvo::testing::run_tool("cvo-log", "status " + cvo::testing::quoted(out), dir.path());
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("session: " + hex(session)), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("bad_messages: 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n  bus: 0\n"), std::string::npos)
      << "all seventeen kinds, an open bus\n"
      << text.out;
  EXPECT_EQ(cvo::testing::run_tool("cvo-log", "poses " + cvo::testing::quoted(dir.path() / "missing.lcm") + " --out x",
                                   dir.path())
                .exit_code,
            1);
  EXPECT_EQ(cvo::testing::run_tool("cvo-log", "frobnicate", dir.path()).exit_code, 2);
}

TEST(Trackerd, ReplayingALogTwiceGivesIdenticalPoses) {
  cvo::test::TempDir dir;
  const auto recording = record_clip(dir.path());
  std::vector<std::vector<cvo_lcm::pose_t>> runs;
  std::vector<std::int64_t> sessions;
  for (int run = 0; run < 2; ++run) {
    const auto out = dir.path() / ("out" + std::to_string(run) + ".lcmlog");
    DaemonProcess d(kTrackerd,
                    with(base_args(out), {"--source", "lcm:file://" + recording.string() + "?speed=0", "--exit-on-eof",
                                          "--deterministic", "--set", "trackerd.ring_slots=1"}),
                    dir.path() / "stderr.txt");
    const auto code = d.wait_for(120s);
    ASSERT_TRUE(code);
    ASSERT_EQ(*code, 0) << cvo::testing::slurp(dir.path() / "stderr.txt");
    const auto log = cvo::testing::read_published(out);
    ASSERT_FALSE(log.poses.empty());
    sessions.push_back(log.poses.front().session);
    EXPECT_NE(sessions.back(), 0);
    EXPECT_EQ(count_other_sessions(log, sessions.back()), 0u);
    runs.push_back(log.poses);
  }
  EXPECT_NE(sessions[0], sessions[1]) << "every start is a new session";
  ASSERT_EQ(runs[0].size(), 50u);
  ASSERT_EQ(runs[1].size(), runs[0].size());
  for (std::size_t i = 0; i < runs[0].size(); ++i) {
    const auto& a = runs[0][i].odom_pose;
    const auto& b = runs[1][i].odom_pose;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a.position[k], b.position[k]) << "frame " << i;
    for (int k = 0; k < 4; ++k) EXPECT_EQ(a.orientation[k], b.orientation[k]) << "frame " << i;
    EXPECT_EQ(runs[0][i].is_keyframe, runs[1][i].is_keyframe);
  }
}

// A recording with garbage between good frames: each bad message is counted by kind in
// CVO_STATUS and skipped; the good frames are tracked; the daemon exits cleanly.
TEST(Trackerd, BadMessagesAreCountedAndSkipped) {
  cvo::test::TempDir dir;
  auto sequence = io::TumSequence::open(kClip);
  const auto log_path = dir.path() / "bad.lcmlog";
  {
    ::lcm::LogFile log(log_path.string(), "w");
    ASSERT_TRUE(log.good());
    std::int64_t t = 0;
    const auto write = [&](const std::vector<std::uint8_t>& bytes) {
      ASSERT_EQ(cvo::testing::write_event(log, "CVO_RGBD", bytes, t += 33000), 0);
    };
    const lcm::RgbdEncoding png{lcm::ColourEncoding::kPng, lcm::DepthEncoding::kPng};
    for (int i = 0; i < 12; ++i) {
      auto frame = sequence.read(static_cast<std::size_t>(i));
      const auto good = lcm::encode(*lcm::to_message(frame, png, nullptr));
      write(good);
      switch (i) {
        case 2: write({1, 2, 3}); break;  // too short
        case 3:
          write(std::vector<std::uint8_t>(good.begin(), good.begin() + static_cast<long>(good.size() / 2)));
          break;   // truncated
        case 4: {  // oversized: trailing bytes
          auto big = good;
          big.resize(big.size() + 100, 0);
          write(big);
          break;
        }
        case 5: {  // a foreign type
          cvo_lcm::pose3d_t p{};
          p.orientation[0] = 1;
          write(lcm::encode(p));
          break;
        }
        case 6: {  // another schema version
          auto m = *lcm::to_message(frame, png, nullptr);
          m.version = 99;
          write(lcm::encode(m));
          break;
        }
        case 7: {  // raw colour of the wrong size
          auto m = *lcm::to_message(frame, lcm::RgbdEncoding{lcm::ColourEncoding::kRawBgr8, lcm::DepthEncoding::kPng},
                                    nullptr);
          m.colour.resize(m.colour.size() - 30);
          m.colour_size = static_cast<std::int32_t>(m.colour.size());
          write(lcm::encode(m));
          break;
        }
        default: break;
      }
    }
    // Frames without a single depth measurement (a covered camera): tracked as failures.
    for (int i = 12; i < 15; ++i) {
      auto frame = sequence.read(static_cast<std::size_t>(i));
      frame.depth.setTo(0);
      write(lcm::encode(*lcm::to_message(frame, png, nullptr)));
    }
  }

  const auto out = dir.path() / "out.lcmlog";
  DaemonProcess d(kTrackerd,
                  with(base_args(out), {"--source", "lcm:file://" + log_path.string() + "?speed=0", "--exit-on-eof",
                                        "--deterministic"}),
                  dir.path() / "stderr.txt");
  const auto code = d.wait_for(60s);
  ASSERT_TRUE(code);
  const auto err = cvo::testing::slurp(dir.path() / "stderr.txt");
  EXPECT_EQ(*code, 0) << err;
  const auto log = cvo::testing::read_published(out);
  EXPECT_EQ(log.poses.size(), 15u) << "12 good frames and 3 without depth";
  ASSERT_FALSE(log.statuses.empty());
  const auto& s = log.statuses.back();
  char host[256] = {};
  ASSERT_EQ(gethostname(host, sizeof host - 1), 0);
  EXPECT_EQ(s.robot, host) << "trackerd.robot's default, $HOSTNAME: the host's name";
  EXPECT_EQ(s.bad_messages[cvo_lcm::status_t::BAD_TOO_SHORT], 1);
  EXPECT_EQ(s.bad_messages[cvo_lcm::status_t::BAD_FINGERPRINT], 1);
  EXPECT_EQ(s.bad_messages[cvo_lcm::status_t::BAD_BODY], 2);
  EXPECT_EQ(s.bad_messages[cvo_lcm::status_t::BAD_VERSION], 1);
  EXPECT_EQ(s.bad_messages[cvo_lcm::status_t::BAD_CONTENT], 1);
  EXPECT_EQ(s.failed_frames, 3);
  EXPECT_NE(err.find("skipped bad input"), std::string::npos) << err;
}

// A tiny ring and a source much faster than tracking: the oldest frames are dropped and counted,
// and SIGTERM in the middle of it stops the daemon cleanly within a second.
TEST(Trackerd, ShutdownUnderLoadIsCleanAndFastAndDropsAreCounted) {
  cvo::test::TempDir dir;
  const auto recording = record_clip(dir.path());
  const auto out = dir.path() / "out.lcmlog";
  DaemonProcess d(kTrackerd,
                  with(base_args(out),
                       {"--source", "lcm:file://" + recording.string() + "?speed=0", "--set", "trackerd.ring_slots=1"}),
                  dir.path() / "stderr.txt");
  std::this_thread::sleep_for(1500ms);
  ASSERT_TRUE(d.running()) << cvo::testing::slurp(dir.path() / "stderr.txt");
  d.signal(SIGTERM);
  const auto code = d.wait_for(cvo::testing::scaled(1000ms));
  ASSERT_TRUE(code) << "not stopped within a second of SIGTERM (times the build's slowdown)";
  const auto err = cvo::testing::slurp(dir.path() / "stderr.txt");
  EXPECT_EQ(*code, 0) << err;
  EXPECT_NE(err.find("stopping on SIGTERM"), std::string::npos) << err;
  const auto log = cvo::testing::read_published(out);
  ASSERT_FALSE(log.statuses.empty());
  // A sanitizer slows the source's decoding as much as tracking: only a plain build is outpaced.
  if (cvo::testing::kSlowdown == 1) {
    EXPECT_GT(log.statuses.back().dropped_frames, 0) << err;
  }
  // Frames still unread at SIGTERM are neither: the recording simply stopped being played.
  EXPECT_LE(log.poses.size() + static_cast<std::size_t>(log.statuses.back().dropped_frames), 50u);
  EXPECT_NE(err.find("tracked " + std::to_string(log.poses.size()) + " frames"), std::string::npos)
      << "every tracked frame's pose was flushed before exit\n"
      << err;
}

// SIGHUP (a terminal closing, or `systemctl kill -s HUP`) is a stop like SIGTERM: exit 0, the open
// local graph published, not death by the signal's default action.
TEST(Trackerd, SigHupStopsCleanlyAndPublishesTheOpenLocalGraph) {
  cvo::test::TempDir dir;
  const auto out = dir.path() / "out.lcmlog";
  const auto err_file = dir.path() / "stderr.txt";
  DaemonProcess d(kTrackerd, with(base_args(out), {"--source", "tum:" + kClip.string(), "--deterministic"}), err_file);
  cvo::testing::wait_for_text(err_file, "end of", cvo::testing::scaled(120s));  // the source was read to its end
  ASSERT_TRUE(d.running()) << cvo::testing::slurp(err_file);
  d.signal(SIGHUP);
  const auto code = d.wait_for(cvo::testing::scaled(5000ms));
  ASSERT_TRUE(code) << "still running after SIGHUP";
  const auto err = cvo::testing::slurp(err_file);
  EXPECT_EQ(*code, 0) << err;
  EXPECT_NE(err.find("stopping on SIGHUP"), std::string::npos) << err;
  const auto log = cvo::testing::read_published(out);
  EXPECT_EQ(log.poses.size(), 50u);
  ASSERT_FALSE(log.keyframes.empty());
  EXPECT_EQ(log.local_graphs.size(), log.keyframes.size()) << "the open local graph went out before the exit";
}

// Whether `pid` blocks SIGTERM now (/proc/PID/status, SigBlk: a hexadecimal mask, bit n-1 for signal n).
bool blocks_sigterm(pid_t pid) {
  const auto status = cvo::testing::slurp("/proc/" + std::to_string(pid) + "/status");
  const auto at = status.find("SigBlk:");
  if (at == std::string::npos) return false;
  return (std::stoull(status.substr(at + 7), nullptr, 16) >> (SIGTERM - 1) & 1) != 0;
}

// A stop that comes before the daemon is up (here: while it waits to read its configuration from a
// FIFO) is held until it can stop cleanly: exit 0, never the 143 of a process killed half-started.
TEST(Trackerd, AStopSignalInTheFirstInstantIsACleanStop) {
  cvo::test::TempDir dir;
  const auto fifo = dir.path() / "config.yaml";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const auto out = dir.path() / "out.lcmlog";
  const auto err_file = dir.path() / "stderr.txt";
  DaemonProcess d(kTrackerd, with(base_args(out), {"--config", fifo.string()}), err_file);
  bool blocked = false;
  for (const auto until = std::chrono::steady_clock::now() + cvo::testing::scaled(5s);
       !(blocked = blocks_sigterm(d.pid())) && std::chrono::steady_clock::now() < until;)
    std::this_thread::sleep_for(1ms);
  ASSERT_TRUE(blocked) << "SIGTERM is not blocked while the daemon starts up";
  d.signal(SIGTERM);  // the daemon has not read its configuration yet
  std::this_thread::sleep_for(50ms);
  {
    std::ofstream config(fifo);
    config << "trackerd:\n  source: tum:" << kClip.string() << "\n";
  }
  const auto code = d.wait_for(cvo::testing::scaled(20000ms));
  ASSERT_TRUE(code) << "still running";
  const auto err = cvo::testing::slurp(err_file);
  EXPECT_EQ(*code, 0) << err;
  EXPECT_NE(err.find("stopping on SIGTERM"), std::string::npos) << err;
}

// Under systemd: READY=1 once running, WATCHDOG=1 at half WATCHDOG_USEC, STATUS=..., STOPPING=1.
TEST(Trackerd, NotifiesSystemd) {
  cvo::test::TempDir dir;
  const auto socket_path = dir.path() / "notify.sock";
  const int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(fd, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", socket_path.c_str());
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  timeval tv{0, 100000};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);

  const auto out = dir.path() / "out.lcmlog";
  DaemonProcess d(kTrackerd, with(base_args(out), {"--source", "tum:" + kClip.string()}), dir.path() / "stderr.txt",
                  {{"NOTIFY_SOCKET", socket_path.string()}, {"WATCHDOG_USEC", "200000"}});
  std::string received;
  // Profilers and allocation counters attribute work by thread name (named once they have started).
  const std::vector<std::string> names = {"cvo-acquire", "cvo-track", "cvo-publish"};
  std::string threads;
  const auto all_named = [&] {
    return std::all_of(names.begin(), names.end(), [&](const auto& n) { return threads.find(n) != std::string::npos; });
  };
  for (const auto until = std::chrono::steady_clock::now() + cvo::testing::scaled(3s);
       !all_named() && std::chrono::steady_clock::now() < until;) {
    std::this_thread::sleep_for(100ms);
    threads.clear();
    for (const auto& task : fs::directory_iterator("/proc/" + std::to_string(d.pid()) + "/task"))
      threads += cvo::testing::slurp(task.path() / "comm");
  }
  for (const auto& name : names) EXPECT_NE(threads.find(name), std::string::npos) << name << " in\n" << threads;
  const auto deadline = std::chrono::steady_clock::now() + 3s;
  char buffer[4096];
  while (std::chrono::steady_clock::now() < deadline) {
    const auto n = recv(fd, buffer, sizeof buffer, 0);
    if (n > 0) received.append(buffer, static_cast<std::size_t>(n)).append("\n");
  }
  d.signal(SIGTERM);
  const auto code = d.wait_for(cvo::testing::scaled(2000ms));
  for (int i = 0; i < 10; ++i) {
    const auto n = recv(fd, buffer, sizeof buffer, 0);
    if (n > 0) received.append(buffer, static_cast<std::size_t>(n)).append("\n");
  }
  close(fd);
  ASSERT_TRUE(code);
  EXPECT_EQ(*code, 0);
  EXPECT_NE(received.find("READY=1"), std::string::npos) << received;
  EXPECT_NE(received.find("WATCHDOG=1"), std::string::npos) << received;
  EXPECT_NE(received.find("STATUS="), std::string::npos) << received;
  EXPECT_NE(received.find("STOPPING=1"), std::string::npos) << received;
}

// With the production defaults (SCHED_FIFO 40, mlockall) the daemon either gets them or says once
// why not, and tracks either way.
TEST(Trackerd, RealtimeSettingsAreAppliedOrWarnedAboutOnce) {
  cvo::test::TempDir dir;
  const auto out = dir.path() / "out.lcmlog";
  DaemonProcess d(kTrackerd,
                  {"--lcm-url", "file://" + out.string() + "?mode=w", "--source", "tum:" + kClip.string(), "--set",
                   "trackerd.paced=false", "--exit-on-eof", "--deterministic", "--set", "trackerd.cpu=0"},
                  dir.path() / "stderr.txt");
  const auto code = d.wait_for(120s);
  ASSERT_TRUE(code);
  const auto err = cvo::testing::slurp(dir.path() / "stderr.txt");
  EXPECT_EQ(*code, 0) << err;
  for (const char* what : {"SCHED_FIFO", "mlockall", "affinity"}) {
    const auto first = err.find(what);
    if (first != std::string::npos) {
      EXPECT_EQ(err.find(what, first + 1), std::string::npos) << what << " warned twice:\n" << err;
    }
  }
  EXPECT_EQ(cvo::testing::read_published(out).poses.size(), 50u) << err;
}

TEST(Trackerd, UnusableSourceOrSettingsFailWithAMessage) {
  cvo::test::TempDir dir;
  const auto out = dir.path() / "out.lcmlog";
  {
    DaemonProcess d(kTrackerd, with(base_args(out), {"--source", "tum:/nonexistent/folder", "--exit-on-eof"}),
                    dir.path() / "stderr.txt");
    const auto code = d.wait_for(10s);
    ASSERT_TRUE(code);
    EXPECT_EQ(*code, 1);
    EXPECT_NE(cvo::testing::slurp(dir.path() / "stderr.txt").find("/nonexistent/folder"), std::string::npos);
  }
  const auto r = cvo::testing::run_tool("cvo-trackerd", "--set trackerd.ring_slots=0", dir.path());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("trackerd.ring_slots"), std::string::npos) << r.err;
  EXPECT_EQ(cvo::testing::run_tool("cvo-trackerd", "--bogus", dir.path()).exit_code, 2);
  const auto help = cvo::testing::run_tool("cvo-trackerd", "--help", dir.path());
  EXPECT_EQ(help.exit_code, 0);
  for (const char* option : {"--config", "--source", "--lcm-url", "--exit-on-eof"})
    EXPECT_NE(help.out.find(option), std::string::npos) << option;
}

// Issue 48: a spool the tracker cannot write in is refused at the start (exit 1, as any unusable
// setting) naming the key and the errno, rather than each keyframe failing to be kept later.
// `spool`: the directory; `error`: the errno's text and name expected.
void expect_spool_refused_at_start(const fs::path& spool, const std::string& error) {
  cvo::test::TempDir dir;
  DaemonProcess d(kTrackerd,
                  with(base_args(dir.path() / "out.lcmlog"), {"--source", "tum:" + kClip.string(), "--exit-on-eof",
                                                              "--set", "trackerd.spool=" + spool.string()}),
                  dir.path() / "stderr.txt");
  const auto code = d.wait_for(60s);
  ASSERT_TRUE(code) << "still running";
  const auto err = cvo::testing::slurp(dir.path() / "stderr.txt");
  EXPECT_EQ(*code, 1) << err;
  EXPECT_NE(err.find("trackerd.spool"), std::string::npos) << err;
  EXPECT_NE(err.find(spool.string()), std::string::npos) << err;
  EXPECT_NE(err.find(error), std::string::npos) << err;
}

TEST(Trackerd, ASpoolUnderAFileIsRefusedAtStartNamingItsErrno) {
  cvo::test::TempDir dir;
  expect_spool_refused_at_start(dir.write("a-file", "in the way") / "spool", "Not a directory (ENOTDIR)");
}

// A read-only mount, which root cannot write through either (mode 0555 alone does not stop root):
// bound inside the private mount namespace of tests/support/in-private-mountns (CVO_SMALL_FS), so
// no other process sees it (trackerd_read_only_spool in CMakeLists.txt).
TEST(Trackerd, AReadOnlySpoolIsRefusedAtStartNamingItsErrno) {
  const char* small = std::getenv("CVO_SMALL_FS");
  if (small == nullptr) GTEST_SKIP() << "needs tests/support/in-private-mountns (CVO_SMALL_FS)";
  const fs::path spool = fs::path(small) / "spool";
  fs::create_directories(spool);
  fs::permissions(spool, fs::perms(0555));
  ASSERT_EQ(::mount(spool.c_str(), spool.c_str(), nullptr, MS_BIND, nullptr), 0) << std::strerror(errno);
  ASSERT_EQ(::mount(nullptr, spool.c_str(), nullptr, MS_REMOUNT | MS_BIND | MS_RDONLY, nullptr), 0)
      << std::strerror(errno);
  expect_spool_refused_at_start(spool, "Read-only file system (EROFS)");
  ::umount(spool.c_str());
}

TEST(Trackerd, HelpListsEveryOptionAndAnUnknownOneExitsTwoNamingIt) {
  cvo::test::TempDir dir;
  cvo::testing::expect_cli_contract("cvo-trackerd", "",
                                    {"--config", "--source", "--lcm-url", "--exit-on-eof", "--deterministic", "--set",
                                     "--print-config", "tum:DIR", "lcm:URL", "openni2:URI", "v4l2:COLOUR,DEPTH"},
                                    dir.path());
}

TEST(Trackerd, SetWithoutAnEqualsSignIsAUsageError) {
  cvo::test::TempDir dir;
  cvo::testing::expect_set_needs_key_equals_value("cvo-trackerd", "--print-config", dir.path());
}

TEST(Trackerd, RepeatedSetOptionsEachTakeOneValue) {
  cvo::test::TempDir dir;
  const auto r = cvo::testing::run_tool(
      "cvo-trackerd", "--set trackerd.ring_slots=7 --set trackerd.warmup_frames=9 --print-config", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("ring_slots: 7"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("warmup_frames: 9"), std::string::npos) << r.out;
}

// cvo-log map: a recording with two CVO_MAPs (and a broken one after them) as the back end sends
// them; the last readable one is written, its placed sessions' keyframes merged in time order.
// CVO_RGBD messages as a recording, 33 ms apart.
void write_rgbd_log(const fs::path& path, const std::vector<std::vector<std::uint8_t>>& messages) {
  ::lcm::LogFile log(path.string(), "w");
  ASSERT_TRUE(log.good());
  std::int64_t t = 0;
  for (const auto& bytes : messages) ASSERT_EQ(cvo::testing::write_event(log, "CVO_RGBD", bytes, t += 33000), 0);
}

struct Replayed {
  cvo::testing::PublishedLog log;
  long peak_rss_bytes = 0;
  std::string err;
};

// cvo-trackerd over a recording, deterministic, to its end.
Replayed replay_recording(const fs::path& dir, const fs::path& recording, const std::string& name,
                          const std::vector<std::string>& extra = {}) {
  const auto out = dir / (name + ".out.lcmlog");
  const auto err = dir / (name + ".stderr.txt");
  DaemonProcess d(kTrackerd,
                  with(with(base_args(out), {"--source", "lcm:file://" + recording.string() + "?speed=0",
                                             "--exit-on-eof", "--deterministic"}),
                       extra),
                  err);
  Replayed r;
  const auto code = d.wait_for(120s);
  r.err = cvo::testing::slurp(err);
  EXPECT_TRUE(code) << "still running";
  EXPECT_EQ(code.value_or(-2), 0) << r.err;
  r.peak_rss_bytes = d.peak_rss_bytes();
  r.log = cvo::testing::read_published(out);
  return r;
}

// Decompression bombs (PNG and JPEG headers claiming 16384x16384, 805 MB of colour: a trusting
// decoder allocates and fills it, about 1.3 GB and seconds of CPU each) and files of another format
// than declared (a PNG labelled JPEG, Radiance HDR labelled PNG or JPEG) between the 50 frames of
// the clip: each refused by its kind before any decoder runs, every frame tracked, and the
// tracker's peak memory that of the same run without them.
TEST(Trackerd, ImageBombsAreRefusedByKindWithoutCostingMemory) {
  cvo::test::TempDir dir;
  auto sequence = io::TumSequence::open(kClip);
  const lcm::RgbdEncoding png{lcm::ColourEncoding::kPng, lcm::DepthEncoding::kPng};
  const lcm::RgbdEncoding jpeg{lcm::ColourEncoding::kJpeg, lcm::DepthEncoding::kPng};
  std::vector<std::vector<std::uint8_t>> clean, bombed;
  const auto colour_of = [](cvo_lcm::rgbd_frame_t m, std::vector<std::uint8_t> colour) {
    m.colour = std::move(colour);
    m.colour_size = static_cast<std::int32_t>(m.colour.size());
    return lcm::encode(m);
  };
  for (std::size_t i = 0; i < 50; ++i) {
    const auto frame = sequence.read(i);
    const auto as_png = *lcm::to_message(frame, png, nullptr);
    clean.push_back(lcm::encode(as_png));
    bombed.push_back(clean.back());
    const auto as_jpeg = *lcm::to_message(frame, jpeg, nullptr);
    switch (i) {
      case 4: bombed.push_back(colour_of(as_png, test::png_bomb(16384, 16384, false))); break;
      case 9: bombed.push_back(colour_of(as_jpeg, test::jpeg_bomb(16384, 16384))); break;
      case 14: {
        auto m = as_png;
        m.depth = test::png_bomb(16384, 16384, true);
        m.depth_size = static_cast<std::int32_t>(m.depth.size());
        bombed.push_back(lcm::encode(m));
        break;
      }
      case 19: bombed.push_back(colour_of(as_jpeg, as_png.colour)); break;  // a PNG labelled JPEG
      case 24: bombed.push_back(colour_of(as_png, test::hdr_file(640, 480))); break;
      case 29: bombed.push_back(colour_of(as_jpeg, test::hdr_file(640, 480))); break;
      case 34: bombed.push_back(colour_of(as_jpeg, test::jpeg_bomb(16384, 16384))); break;  // again: still nothing
      default: break;
    }
  }
  write_rgbd_log(dir.path() / "clean.lcmlog", clean);
  write_rgbd_log(dir.path() / "bombed.lcmlog", bombed);

  const auto without = replay_recording(dir.path(), dir.path() / "clean.lcmlog", "clean");
  const auto with_bombs = replay_recording(dir.path(), dir.path() / "bombed.lcmlog", "bombed");
  EXPECT_EQ(without.log.poses.size(), 50u);
  EXPECT_EQ(with_bombs.log.poses.size(), 50u) << "every frame of the clip tracked, no bomb as a frame";
  ASSERT_FALSE(with_bombs.log.statuses.empty());
  const auto& s = with_bombs.log.statuses.back();
  EXPECT_EQ(s.bad_messages[cvo_lcm::status_t::BAD_IMAGE_SIZE], 4) << "PNG, JPEG (twice) and depth PNG bombs";
  EXPECT_EQ(s.bad_messages[cvo_lcm::status_t::BAD_IMAGE_FORMAT], 3) << "PNG labelled JPEG, HDR labelled PNG and JPEG";
  EXPECT_EQ(s.bad_messages[cvo_lcm::status_t::BAD_CONTENT], 0);
  EXPECT_EQ(s.allocations_after_warmup, 0);
  EXPECT_NE(with_bombs.err.find("PNG header says 16384x16384"), std::string::npos) << with_bombs.err;
  std::printf("cvo-trackerd peak RSS: %.1f MB without bombs, %.1f MB with 7 bombs\n", without.peak_rss_bytes / 1e6,
              with_bombs.peak_rss_bytes / 1e6);
  EXPECT_GT(without.peak_rss_bytes, 0);
  EXPECT_LT(with_bombs.peak_rss_bytes, without.peak_rss_bytes + 50'000'000L);
}

// A frame of another camera size first (8x6), then the clip: the clip's camera is the tracker's
// after trackerd.camera_change_frames frames in a row, in a new session counted from frame 0 with
// a re-warmed tracking thread; a lone 8x6 frame in the middle of the clip is refused and changes
// nothing.
TEST(Trackerd, ACameraOfAnotherSizeIsTrackedAfterAFewFrames) {
  cvo::test::TempDir dir;
  auto sequence = io::TumSequence::open(kClip);
  const lcm::RgbdEncoding png{lcm::ColourEncoding::kPng, lcm::DepthEncoding::kPng};
  auto tiny = sequence.read(0);
  tiny.bgr = tiny.bgr(cv::Rect(0, 0, 8, 6)).clone();
  tiny.depth = tiny.depth(cv::Rect(0, 0, 8, 6)).clone();
  tiny.intrinsics.width = 8;
  tiny.intrinsics.height = 6;
  tiny.intrinsics.cx = 4;
  tiny.intrinsics.cy = 3;
  std::vector<std::vector<std::uint8_t>> messages = {lcm::encode(*lcm::to_message(tiny, png, nullptr))};
  for (std::size_t i = 0; i < 50; ++i) {
    messages.push_back(lcm::encode(*lcm::to_message(sequence.read(i), png, nullptr)));
    if (i == 30) messages.push_back(messages.front());  // a lone odd frame
  }
  write_rgbd_log(dir.path() / "change.lcmlog", messages);
  const auto r = replay_recording(dir.path(), dir.path() / "change.lcmlog", "change");

  constexpr int kChangeFrames = 5;  // trackerd.camera_change_frames' default
  ASSERT_FALSE(r.log.poses.empty());
  const std::int64_t session = r.log.poses.back().session;
  std::vector<cvo_lcm::pose_t> clip;
  for (const auto& p : r.log.poses)
    if (p.session == session) clip.push_back(p);
  EXPECT_EQ(clip.size(), 50u - (kChangeFrames - 1)) << "the clip from its 5th frame on";
  EXPECT_EQ(r.log.poses.size() - clip.size(), 1u) << "the 8x6 frame, in a session of its own";
  EXPECT_NE(r.log.poses.front().session, session);
  ASSERT_FALSE(clip.empty());
  EXPECT_EQ(clip.front().frame_index, 0) << "frame indices count from 0 in the new session";
  EXPECT_EQ(clip.back().frame_index, static_cast<std::int64_t>(clip.size()));  // the lone frame took an index
  const auto tracked =
      std::count_if(clip.begin(), clip.end(), [](const auto& p) { return p.status == cvo_lcm::pose_t::STATUS_OK; });
  EXPECT_EQ(static_cast<std::size_t>(tracked), clip.size() - 1) << "all but the first registered";
  ASSERT_FALSE(r.log.statuses.empty());
  const auto& s = r.log.statuses.back();
  EXPECT_EQ(s.bad_messages[cvo_lcm::status_t::BAD_CONTENT], (kChangeFrames - 1) + 1)
      << "4 clip frames before the change, and the lone 8x6 frame";
  EXPECT_EQ(s.allocations_after_warmup, 0)
      << "the new pipeline's allocations are the camera change's, then warm-up again";
  const auto note = r.err.find("camera changed (8x6 to 640x480");
  ASSERT_NE(note, std::string::npos) << r.err;
  std::printf("%s\n", r.err.substr(note, r.err.find('\n', note) - note).c_str());
  EXPECT_FALSE(r.log.keyframes.empty());
  EXPECT_EQ(r.log.keyframes.back().width, 640);
}

TEST(CvoLog, MapWritesTheLastMapsPlacedKeyframesSortedByTime) {
  cvo::test::TempDir dir;
  constexpr std::int64_t kFirst = 0x1111, kJoined = -0x2222, kAlone = 0x3333;  // any 64 bits
  const auto at = [](double x) { return core::SE3::from_translation({x, 0, 0}); };
  slam::Map early;
  early.revision = 1;
  early.sessions = {{kFirst, true, kFirst, 1, 0, {}}};
  early.keyframes = {{kFirst, 0, 100.0, at(9)}};
  slam::Map last;
  last.revision = 2;
  last.sessions = {
      {kFirst, true, kFirst, 2, 0, {}}, {kJoined, true, kFirst, 2, 1, at(1)}, {kAlone, false, kAlone, 3, -1, at(5)}};
  last.keyframes = {{kFirst, 0, 100.0, at(1)},  {kFirst, 1, 103.0, at(2)}, {kJoined, 0, 101.5, at(3)},
                    {kJoined, 1, 104.0, at(4)}, {kAlone, 0, 100.5, at(7)}, {kAlone, 1, 102.0, at(7)},
                    {kAlone, 2, 105.0, at(7)}};
  const auto log_path = dir.path() / "map.lcmlog";
  {
    ::lcm::LogFile log(log_path.string(), "w");
    ASSERT_TRUE(log.good());
    std::int64_t t = 0;
    const auto write = [&](const std::vector<std::uint8_t>& bytes) {
      ASSERT_EQ(cvo::testing::write_event(log, "CVO_MAP", bytes, t += 1000), 0);
    };
    write(lcm::encode(lcm::to_message(early, 1)));
    write(lcm::encode(lcm::to_message(last, 2)));
    write({1, 2, 3});  // a logger killed mid-write
  }
  const auto traj = dir.path() / "map.txt";
  const auto map_of = [&](const fs::path& log, const std::string& out) {
    return cvo::testing::run_tool("cvo-log", "map " + cvo::testing::quoted(log) + " --out " + out, dir.path());
  };
  const auto r = map_of(log_path, cvo::testing::quoted(traj));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto written = io::read_tum_trajectory(traj);
  const std::vector<std::pair<double, double>> expected = {{100.0, 1}, {101.5, 3}, {103.0, 2}, {104.0, 4}};
  ASSERT_EQ(written.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_NEAR(written[i].timestamp, expected[i].first, 1e-6) << i;
    EXPECT_NEAR(written[i].pose.translation().x(), expected[i].second, 1e-9) << i;
  }
  EXPECT_NE(r.err.find("session " + hex(kAlone) + " not placed in the map: its 3 keyframes left out"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("skipped"), std::string::npos) << "the broken event is reported\n" << r.err;

  // No map at all, or none that places a keyframe: exit 1 with a message.
  const auto empty_path = dir.path() / "empty.lcmlog";
  {
    ::lcm::LogFile log(empty_path.string(), "w");
    ASSERT_TRUE(log.good());
  }
  const auto none = map_of(empty_path, "x.txt");
  EXPECT_EQ(none.exit_code, 1);
  EXPECT_NE(none.err.find("no CVO_MAP"), std::string::npos) << none.err;
  slam::Map unplaced;
  unplaced.sessions = {{kAlone, false, kAlone, 1, -1, {}}};
  unplaced.keyframes = {{kAlone, 0, 100.0, at(1)}};
  const auto unplaced_path = dir.path() / "unplaced.lcmlog";
  {
    ::lcm::LogFile log(unplaced_path.string(), "w");
    ASSERT_EQ(cvo::testing::write_event(log, "CVO_MAP", lcm::encode(lcm::to_message(unplaced, 1)), 0), 0);
  }
  const auto nothing = map_of(unplaced_path, "x.txt");
  EXPECT_EQ(nothing.exit_code, 1);
  EXPECT_NE(nothing.err.find("places no keyframe"), std::string::npos) << nothing.err;
  EXPECT_FALSE(fs::exists(dir.path() / "x.txt"));
  EXPECT_EQ(cvo::testing::run_tool("cvo-log", "map " + cvo::testing::quoted(log_path), dir.path()).exit_code, 2)
      << "map needs --out";
}

TEST(CvoLog, HelpListsEveryOptionAndAnUnknownOneExitsTwoNamingIt) {
  cvo::test::TempDir dir;
  cvo::testing::expect_cli_contract("cvo-log", "", {"poses", "map", "status"}, dir.path());
  cvo::testing::expect_cli_contract("cvo-log", "poses", {"LOG", "--out", "--map"}, dir.path());
  cvo::testing::expect_cli_contract("cvo-log", "map", {"LOG", "--out"}, dir.path());
  cvo::testing::expect_cli_contract("cvo-log", "status", {"LOG", "--json"}, dir.path());
}

// cvo-log status --json: the status_t fields with their types (the 64-bit session and counters as
// exact integers, the rates as numbers, bad_messages an array), on one line; the text form too.
TEST(CvoLog, StatusJsonKeepsTheFieldTypes) {
  cvo::test::TempDir dir;
  cvo_lcm::status_t s{};
  s.version = cvo_lcm::status_t::SCHEMA_VERSION;
  s.session = -0x123456789abcdef1;  // any 64 bits: not a double's
  s.utime = 1'700'000'000'123'456;
  s.pid = 4242;
  s.state = cvo_lcm::status_t::STATE_DEGRADED;
  s.rate_hz = 29.5;
  s.rss_bytes = 123'456'789;
  s.bad_messages[cvo_lcm::status_t::BAD_STALE] = 3;
  s.process = "cvo-backendd";
  s.detail = "a \"quoted\" note";
  const auto log_path = dir.path() / "status.lcmlog";
  {
    ::lcm::LogFile log(log_path.string(), "w");
    ASSERT_EQ(cvo::testing::write_event(log, "CVO_STATUS", lcm::encode(s), 1000), 0);
  }
  const auto r = cvo::testing::run_tool("cvo-log", "status " + cvo::testing::quoted(log_path) + " --json", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << "one line\n" << r.out;
  const auto json = nlohmann::ordered_json::parse(r.out, nullptr, false);
  ASSERT_TRUE(json.contains("cvo-backendd")) << r.out;
  const auto& status = json["cvo-backendd"];
  EXPECT_EQ(status.begin().key(), "session");
  EXPECT_EQ(status["session"].get<std::int64_t>(), s.session);
  EXPECT_TRUE(status["utime"].is_number_integer()) << r.out;
  EXPECT_EQ(status["utime"].get<std::int64_t>(), s.utime);
  EXPECT_EQ(status["pid"], 4242);
  EXPECT_EQ(status["state"], 2);
  EXPECT_EQ(status["rate_hz"].get<double>(), 29.5);
  EXPECT_EQ(status["rss_bytes"], 123'456'789);
  ASSERT_TRUE(status["bad_messages"].is_array());
  EXPECT_EQ(status["bad_messages"].size(), std::size_t{cvo_lcm::status_t::NUM_BAD_KINDS});
  EXPECT_EQ(status["bad_messages"][cvo_lcm::status_t::BAD_STALE], 3);
  EXPECT_EQ(status["detail"], s.detail);
  EXPECT_EQ(status.back(), s.detail) << "detail last";

  const auto text = cvo::testing::run_tool("cvo-log", "status " + cvo::testing::quoted(log_path), dir.path());
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("cvo-backendd:\n  session: " + hex(s.session) + "\n"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("  pid: 4242\n"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("  bad_messages: 0 0 0 0 0 0 0 0 0 0 0 3 0 0 0 0 0\n  bus: 0\n  sender: 0x0000000000000000\n"
                          "  detail: a \"quoted\" note\n"),
            std::string::npos)
      << text.out;
}

// Three robots' trackers, one of them in two sessions, and a back end: cvo-log status shows every
// robot's every process and session (keyed by process alone it showed one tracker), and --json
// lists them under "senders" while each process's key keeps its last status.
TEST(CvoLog, StatusShowsEveryRobotAndSession) {
  cvo::test::TempDir dir;
  const auto log_path = dir.path() / "fleet.lcmlog";
  {
    ::lcm::LogFile log(log_path.string(), "w");
    std::int64_t t = 1000;
    const auto status = [&](const std::string& process, const std::string& robot, std::int64_t session) {
      cvo_lcm::status_t s{};
      s.version = cvo_lcm::status_t::SCHEMA_VERSION;
      s.process = process;
      s.robot = robot;
      s.session = session;
      s.utime = t;
      ASSERT_EQ(cvo::testing::write_event(log, "CVO_STATUS", lcm::encode(s), t += 1000), 0);
    };
    status("cvo-trackerd", "hall-a", 0x11);
    status("cvo-trackerd", "hall-b", 0x22);
    status("cvo-trackerd", "dock-1", 0x33);
    status("cvo-trackerd", "hall-a", 0x44);  // hall-a's tracker restarted: a new session
    status("cvo-backendd", "server", 0);
    status("cvo-trackerd", "hall-b", 0x22);  // a later status of a known sender replaces its last
  }
  const auto text = cvo::testing::run_tool("cvo-log", "status " + cvo::testing::quoted(log_path), dir.path());
  ASSERT_EQ(text.exit_code, 0) << text.err;
  for (const auto& [robot, session] : std::vector<std::pair<std::string, std::int64_t>>{
           {"hall-a", 0x11}, {"hall-a", 0x44}, {"hall-b", 0x22}, {"dock-1", 0x33}, {"server", 0}})
    EXPECT_NE(text.out.find("  session: " + hex(session) + "\n  robot: " + robot + "\n"), std::string::npos)
        << robot << "\n"
        << text.out;
  const auto blocks = [&](const std::string& header) {
    std::size_t n = 0;
    for (auto at = text.out.find(header); at != std::string::npos; at = text.out.find(header, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(blocks("cvo-trackerd:\n"), 4u) << text.out;
  EXPECT_EQ(blocks("cvo-backendd:\n"), 1u) << text.out;

  const auto r = cvo::testing::run_tool("cvo-log", "status " + cvo::testing::quoted(log_path) + " --json", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto json = nlohmann::ordered_json::parse(r.out, nullptr, false);
  ASSERT_TRUE(json.contains("senders")) << r.out;
  EXPECT_EQ(json["cvo-trackerd"]["robot"], "hall-b") << "the process's key keeps its last status";
  EXPECT_EQ(json["cvo-backendd"]["robot"], "server");
  const auto& senders = json["senders"];
  ASSERT_EQ(senders.size(), 5u) << r.out;
  std::set<std::string> seen;
  for (const auto& s : senders) {
    EXPECT_EQ(s.begin().key(), "process");
    seen.insert(s["robot"].get<std::string>() + "/" + std::to_string(s["session"].get<std::int64_t>()));
  }
  EXPECT_EQ(seen, (std::set<std::string>{"dock-1/51", "hall-a/17", "hall-a/68", "hall-b/34", "server/0"}));
}

}  // namespace
}  // namespace cvo::daemon
