// The virtual OpenNI2 device (drivers/openni2_virtual) through the real OpenNI2 runtime, which
// loads it from the project's drivers repository: frames, intrinsics and timestamps as the TUM
// folder has them; cvo-trackerd on it as on the folder; an .oni recorded with OpenNI's Recorder and
// replayed; an unplug and a return.
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "drivers/frame_source.hpp"
#include "drivers/open_source.hpp"
#include "libcvo/io/intrinsics_file.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "tests/drivers/tum_copy.hpp"
#include "tests/support/cli_contract.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/lcm_log.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/slowdown.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::drivers {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const fs::path kTrackerd = fs::path(CVO_TOOLS_DIR) / "cvo-trackerd";
const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";

// A copy of the first `count` frames of the sample that carries its own camera.yaml; with
// `one_clock`, each depth image is stamped with its colour image's time.
fs::path copy_with_camera(const fs::path& dir, std::size_t count, const core::Intrinsics& k, bool one_clock = false) {
  std::optional<std::vector<double>> stamps;
  if (one_clock) {
    const auto sample = io::TumSequence::open(kClip);
    stamps.emplace();
    for (std::size_t i = 0; i < count; ++i) stamps->push_back(sample.files().at(i).timestamp);
  }
  cvo::test::write_tum_copy(dir, count, stamps);
  std::ofstream(dir / "camera.yaml") << io::format_intrinsics_yaml(k, "test camera");
  return dir;
}

core::Intrinsics camera(double fx, double fy, double cx, double cy) {
  core::Intrinsics k;
  k.fx = fx;
  k.fy = fy;
  k.cx = cx;
  k.cy = cy;
  k.width = 640;
  k.height = 480;
  k.depth_scale = 5000;
  return k;
}

struct TrackerdRun {
  int exit_code = -2;
  std::string err;
  cvo::testing::PublishedLog log;
};

// cvo-trackerd on `spec` to its end, as fast as it tracks (every frame: --deterministic, unpaced).
TrackerdRun run_trackerd(const fs::path& dir, const std::string& name, const std::string& spec,
                         const std::vector<std::pair<std::string, std::string>>& env = {}) {
  const auto out = dir / (name + ".lcmlog");
  const auto err = dir / (name + ".stderr");
  cvo::testing::DaemonProcess d(kTrackerd,
                                {"--lcm-url", "file://" + out.string() + "?mode=w", "--set",
                                 "trackerd.realtime_priority=0", "--set", "trackerd.lock_memory=false", "--set",
                                 "trackerd.paced=false", "--source", spec, "--exit-on-eof", "--deterministic"},
                                err, env);
  TrackerdRun run;
  const auto code = d.wait_for(300s);
  run.err = cvo::testing::slurp(err);
  if (!code) {
    ADD_FAILURE() << spec << ": still running\n" << run.err;
    return run;
  }
  run.exit_code = *code;
  run.log = cvo::testing::read_published(out);
  return run;
}

// The same poses: position within `metres`, quaternion components within `metres` too (radians
// over two).
void expect_same_poses(const std::vector<cvo_lcm::pose_t>& a, const std::vector<cvo_lcm::pose_t>& b, const char* what,
                       double metres = 1e-5) {
  ASSERT_EQ(a.size(), b.size());
  double worst_position = 0, worst_orientation = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (int c = 0; c < 3; ++c)
      worst_position = std::max(worst_position, std::abs(a[i].odom_pose.position[c] - b[i].odom_pose.position[c]));
    for (int c = 0; c < 4; ++c)
      worst_orientation =
          std::max(worst_orientation, std::abs(a[i].odom_pose.orientation[c] - b[i].odom_pose.orientation[c]));
  }
  std::printf("%s: %zu poses, largest difference %.3g m, %.3g in a quaternion component\n", what, a.size(),
              worst_position, worst_orientation);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].frame_index, b[i].frame_index);
    EXPECT_EQ(a[i].status, b[i].status) << "frame " << i;
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(a[i].odom_pose.position[c], b[i].odom_pose.position[c], metres) << "frame " << i;
    for (int c = 0; c < 4; ++c)
      EXPECT_NEAR(a[i].odom_pose.orientation[c], b[i].odom_pose.orientation[c], metres) << "frame " << i;
  }
}

// Reads `source` to its end and compares every frame with the folder's: colour exact, depth exact
// in 100 um units, timestamps the recording's (moved by one offset); returns the last intrinsics.
core::Intrinsics expect_the_folders_frames(FrameSource& source, const fs::path& folder, std::size_t count) {
  auto tum = io::TumSequence::open(folder);
  core::RgbdFrame frame;
  double first_stamp = 0;
  for (std::size_t i = 0; i < count; ++i) {
    ReadResult r;
    for (int tries = 0; tries < 100 && (r = source.read(frame, 100ms)).status == ReadStatus::kTimeout; ++tries) {
    }
    if (r.status != ReadStatus::kFrame) {
      ADD_FAILURE() << "frame " << i << ": " << r.message;
      return frame.intrinsics;
    }
    const auto expected = *tum.next();
    EXPECT_EQ(frame.intrinsics.depth_scale, 10000.0) << "100 um depth, exact for TUM's 0.2 mm units";
    EXPECT_EQ(cv::norm(frame.bgr, expected.bgr, cv::NORM_INF), 0.0) << "frame " << i;
    cv::Mat twice;
    expected.depth.convertTo(twice, CV_32S, 2.0);
    twice.setTo(0, twice > 65535);
    twice.convertTo(twice, CV_16U);
    EXPECT_EQ(cv::norm(frame.depth, twice, cv::NORM_INF), 0.0) << "frame " << i;
    if (i == 0) first_stamp = frame.timestamp - expected.timestamp;
    // The device clock carries the recording's stamps (microseconds), moved by one offset.
    EXPECT_NEAR(frame.timestamp - expected.timestamp, first_stamp, 2e-6) << "frame " << i;
    EXPECT_NEAR(frame.depth_timestamp - expected.depth_timestamp, first_stamp, 2e-6) << "frame " << i;
  }
  ReadResult end;
  for (int tries = 0; tries < 100 && (end = source.read(frame, 100ms)).status == ReadStatus::kTimeout; ++tries) {
  }
  EXPECT_EQ(end.status, ReadStatus::kEndOfStream) << end.message;
  EXPECT_EQ(source.lost_frames(), 0u);
  return frame.intrinsics;
}

TEST(VirtualDevice, PlaysTheFolderWithItsIntrinsicsDepthAndTimestamps) {
  cvo::test::TempDir dir;
  auto k = camera(500.25, 510.5, 300.75, 250.125);  // off-centre and distorted: only the device's own model has it
  k.distortion = {0.25, -0.5, 0.001, -0.002, 0.125};
  const auto folder = copy_with_camera(dir.path() / "fr1_copy", 5, k);
  SourceOptions options;
  options.realtime = false;
  const auto source = open_source("openni2:cvo-virtual:" + folder.string(), options);
  EXPECT_NE(source->describe().find("device"), std::string::npos) << source->describe();
  const auto got = expect_the_folders_frames(*source, folder, 5);
  EXPECT_EQ(got.fx, k.fx);
  EXPECT_EQ(got.fy, k.fy);
  EXPECT_EQ(got.cx, k.cx);
  EXPECT_EQ(got.cy, k.cy);
  EXPECT_EQ(got.distortion, k.distortion);
}

TEST(VirtualDevice, AnOniRecordingHoldsTheFoldersFrames) {
  cvo::test::TempDir dir;
  const auto k = camera(500.25, 510.5, 300.75, 250.125);
  // OpenNI's Recorder starts each stream's clock at 0: the offset between depth and colour stamps
  // is not kept, so this folder has none.
  const auto folder = copy_with_camera(dir.path() / "fr1_copy", 5, k, true);
  const auto oni = dir.path() / "five.oni";
  const auto rec = cvo::testing::run_tool(
      "cvo-oni-record", cvo::testing::quoted("cvo-virtual:" + folder.string()) + " " + cvo::testing::quoted(oni),
      dir.path());
  ASSERT_EQ(rec.exit_code, 0) << rec.err;
  SourceOptions options;
  options.realtime = false;
  const auto source = open_source("openni2:" + oni.string(), options);
  EXPECT_NE(source->describe().find("recording"), std::string::npos) << source->describe();
  const auto got = expect_the_folders_frames(*source, folder, 5);
  // What an .oni keeps of the camera: the fields of view, the principal point at the centre.
  EXPECT_EQ(got.fx, k.fx);
  EXPECT_EQ(got.fy, k.fy);
  EXPECT_EQ(got.cx, 320.0);
  EXPECT_EQ(got.cy, 240.0);
}

TEST(VirtualDevice, PacedItPlaysEveryFrameOnceInOrderThenEnds) {
  SourceOptions options;  // realtime: the device's own clock, at the recorded rate
  const auto source = open_source("openni2:cvo-virtual:" + kClip.string(), options);
  core::RgbdFrame frame;
  std::size_t frames = 0;
  double last = -1;
  for (int reads = 0; reads < 2000; ++reads) {
    const auto r = source->read(frame, 100ms);
    if (r.status == ReadStatus::kEndOfStream) break;
    ASSERT_NE(r.status, ReadStatus::kDisconnected) << r.message;
    if (r.status != ReadStatus::kFrame) continue;
    EXPECT_GT(frame.timestamp, last);
    last = frame.timestamp;
    ++frames;
  }
  // A reader that falls behind a camera loses frames, and counts them.
  EXPECT_EQ(frames + source->lost_frames(), 50u);
  EXPECT_GT(frames, 0u);
}

TEST(VirtualDevice, BadUrisAreRefusedWithTheDriversReason) {
  try {
    open_source("openni2:cvo-virtual:/nonexistent/fr1_folder", SourceOptions{});
    FAIL() << "opened a missing folder";
  } catch (const SourceError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/fr1_folder"), std::string::npos) << e.what();
  }
  try {
    open_source("openni2:cvo-virtual:" + kClip.string() + "?unplug_after=x", SourceOptions{});
    FAIL() << "opened with a bad option";
  } catch (const SourceError& e) {
    EXPECT_NE(std::string(e.what()).find("unplug_after"), std::string::npos) << e.what();
  }
}

TEST(VirtualDevice, TrackerdThroughOpenNI2GivesTheFoldersPoses) {
  cvo::test::TempDir dir;
  const auto tum = run_trackerd(dir.path(), "tum", "tum:" + kClip.string());
  const auto virt = run_trackerd(dir.path(), "virtual", "openni2:cvo-virtual:" + kClip.string());
  ASSERT_EQ(tum.exit_code, 0) << tum.err;
  ASSERT_EQ(virt.exit_code, 0) << virt.err;
  EXPECT_NE(virt.err.find("end of openni2:cvo-virtual:"), std::string::npos) << virt.err;
  ASSERT_EQ(virt.log.poses.size(), 50u) << "every frame tracked\n" << virt.err;
  // The device gives its intrinsics as fields of view in float: focal lengths differ from the
  // folder's by ~1e-6 relative, enough to move a kernel pair across the sparsification threshold
  // somewhere in 50 frames and the poses by millimetres (the depth-time compensation follows
  // the published motion, so such a difference carries on for a few frames): 0.2 mm or 2.2 mm
  // depending on which pair crosses where, whether the second frame-to-frame registration reuses
  // the first one's candidates or not. A wrong or shifted frame would move them by centimetres.
  expect_same_poses(tum.log.poses, virt.log.poses, "tum vs virtual device", 5e-3);
  ASSERT_FALSE(virt.log.statuses.empty());
  EXPECT_EQ(virt.log.statuses.back().source_gaps, 0);
}

TEST(VirtualDevice, AnOniRecordingReplaysToTheSamePoses) {
  cvo::test::TempDir dir;
  // An .oni keeps fields of view, not a principal point (OpenNI's model: the image centre), and no
  // offset between the depth and colour clocks: this copy's camera has its principal point at the
  // centre, and its depth images the stamps of their colour images.
  const auto folder = copy_with_camera(dir.path() / "fr1_centred", 50, camera(517.3, 516.5, 320, 240), true);
  const auto oni = dir.path() / "clip.oni";
  const auto rec = cvo::testing::run_tool(
      "cvo-oni-record", cvo::testing::quoted("cvo-virtual:" + folder.string()) + " " + cvo::testing::quoted(oni),
      dir.path());
  ASSERT_EQ(rec.exit_code, 0) << rec.err;
  EXPECT_NE(rec.out.find("recorded 50 frames"), std::string::npos) << rec.out;

  const auto tum = run_trackerd(dir.path(), "tum", "tum:" + folder.string());
  const auto replay = run_trackerd(dir.path(), "replay", "openni2:" + oni.string());
  ASSERT_EQ(tum.exit_code, 0) << tum.err;
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  EXPECT_NE(replay.err.find("recording"), std::string::npos) << replay.err;
  ASSERT_EQ(replay.log.poses.size(), 50u) << replay.err;
  expect_same_poses(tum.log.poses, replay.log.poses, "tum vs .oni replay");

  // --frames stops early; a missing device is exit 1 naming it, a missing argument exit 2.
  const auto five = cvo::testing::run_tool("cvo-oni-record",
                                           cvo::testing::quoted("cvo-virtual:" + folder.string()) + " " +
                                               cvo::testing::quoted(dir.path() / "five.oni") + " --frames 5",
                                           dir.path());
  EXPECT_EQ(five.exit_code, 0) << five.err;
  EXPECT_NE(five.out.find("recorded 5 frames"), std::string::npos) << five.out;
  const auto missing = cvo::testing::run_tool("cvo-oni-record", "cvo-virtual:/nonexistent/fr1 x.oni", dir.path());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("/nonexistent/fr1"), std::string::npos) << missing.err;
  EXPECT_EQ(cvo::testing::run_tool("cvo-oni-record", "any", dir.path()).exit_code, 2);
}

TEST(CvoOniRecord, HelpListsEveryOptionAndAnUnknownOneExitsTwoNamingIt) {
  cvo::test::TempDir dir;
  cvo::testing::expect_cli_contract("cvo-oni-record", "", {"URI", "OUT.oni", "--frames", "cvo-virtual:DIR"},
                                    dir.path());
}

TEST(VirtualDevice, UnplugAndReturnIsAGapAndANewSession) {
  cvo::test::TempDir dir;
  const auto run = run_trackerd(dir.path(), "unplug",
                                "openni2:cvo-virtual:" + kClip.string() + "?unplug_after=20&replug_after_s=0.3");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("source lost"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("frames again"), std::string::npos) << run.err;
  // Every frame played is tracked: 20 before the unplug, the other 30 after, numbered from 0 again
  // in a session of their own.
  ASSERT_EQ(run.log.poses.size(), 50u) << run.err;
  std::set<std::int64_t> sessions;
  for (std::size_t i = 0; i < 50; ++i) {
    const auto& p = run.log.poses[i];
    EXPECT_EQ(p.frame_index, static_cast<std::int64_t>(i < 20 ? i : i - 20)) << "pose " << i;
    sessions.insert(p.session);
  }
  EXPECT_EQ(sessions.size(), 2u);
  EXPECT_NE(run.log.poses[19].session, run.log.poses[20].session);
  EXPECT_EQ(run.log.poses[20].status, +cvo_lcm::pose_t::STATUS_FIRST_FRAME);
  ASSERT_FALSE(run.log.statuses.empty());
  EXPECT_EQ(run.log.statuses.back().source_gaps, 1);
}

// systemd's notification socket, as the service manager holds it: every datagram with the time it
// arrived, gathered by a thread while the daemon runs.
class NotifySocket {
 public:
  explicit NotifySocket(const fs::path& path) : path_(path), fd_(::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0)) {
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::snprintf(address.sun_path, sizeof address.sun_path, "%s", path.c_str());
    EXPECT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
    timeval tv{0, 50000};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    reader_ = std::thread([this] {
      char buffer[4096];
      while (!stop_) {
        const auto n = ::recv(fd_, buffer, sizeof buffer, 0);
        if (n > 0)
          received_.emplace_back(std::chrono::steady_clock::now(), std::string(buffer, static_cast<std::size_t>(n)));
      }
    });
  }
  ~NotifySocket() {
    stop_reading();
    ::close(fd_);
  }
  NotifySocket(const NotifySocket&) = delete;
  NotifySocket& operator=(const NotifySocket&) = delete;

  /// Once the daemon has exited: the longest time between two WATCHDOG=1 pings, and their count.
  std::pair<std::chrono::milliseconds, int> watchdog_pings() {
    stop_reading();
    std::optional<std::chrono::steady_clock::time_point> last;
    std::chrono::milliseconds longest{0};
    int count = 0;
    for (const auto& [when, text] : received_) {
      if (text.find("WATCHDOG=1") == std::string::npos) continue;
      if (last) longest = std::max(longest, std::chrono::duration_cast<std::chrono::milliseconds>(when - *last));
      last = when;
      ++count;
    }
    return {longest, count};
  }

 private:
  void stop_reading() {
    stop_ = true;
    if (reader_.joinable()) reader_.join();
  }

  fs::path path_;
  int fd_;
  std::atomic<bool> stop_{false};
  std::vector<std::pair<std::chrono::steady_clock::time_point, std::string>> received_;
  std::thread reader_;
};

// Under systemd the watchdog must go on being served while the camera is away (here 3 s, fifteen
// watchdog periods): a daemon that stopped pinging would be killed, and restarted without need.
TEST(VirtualDevice, TheWatchdogIsServedWhileTheCameraIsAway) {
  cvo::test::TempDir dir;
  const auto socket_path = dir.path() / "notify.sock";
  std::pair<std::chrono::milliseconds, int> pings;
  TrackerdRun run;
  {
    NotifySocket notify(socket_path);
    run = run_trackerd(dir.path(), "watchdog",
                       "openni2:cvo-virtual:" + kClip.string() + "?unplug_after=10&replug_after_s=3",
                       {{"NOTIFY_SOCKET", socket_path.string()}, {"WATCHDOG_USEC", "200000"}});
    pings = notify.watchdog_pings();  // the daemon has exited: nothing more arrives
  }
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("source lost"), std::string::npos) << run.err;
  EXPECT_EQ(run.log.poses.size(), 50u) << run.err;
  EXPECT_GE(pings.second, 10) << "WATCHDOG=1 pings";
  // Not a speed limit: a daemon that stopped pinging for the 3 s away would show a 3 s gap.
  EXPECT_LT(pings.first, cvo::testing::scaled(std::chrono::milliseconds(1500))) << "longest time without a ping";
}

}  // namespace
}  // namespace cvo::drivers
