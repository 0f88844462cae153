// Real cameras' recordings (issue 49), made here: the virtual device stands for the cameras
// (drivers/openni2_virtual: no field of view but PS1080 zero-plane values, colour smaller than
// depth, streams that stay mirrored), OpenNI's own Recorder writes the .oni (cvo-oni-record), and
// each is played back through the real OpenNI2 runtime; copies cut off or never closed play what
// they hold; files that cannot be played make cvo-trackerd exit 1 at once, saying why.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "drivers/factory_intrinsics.hpp"
#include "drivers/frame_source.hpp"
#include "drivers/oni_file.hpp"
#include "drivers/open_source.hpp"
#include "drivers/zero_plane.hpp"
#include "libcvo/io/intrinsics_file.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/lcm_log.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::drivers {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const fs::path kTrackerd = fs::path(CVO_TOOLS_DIR) / "cvo-trackerd";
const fs::path kClip = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";
constexpr const char* kKinect = "zpd=120&zpps=0.1042";  // a Kinect v1's zero-plane values (libfreenect)

// `frames` frames of the sample through the virtual device with `options`, recorded by OpenNI's
// Recorder (cvo-oni-record, frame by frame).
fs::path record(const fs::path& dir, const std::string& name, const std::string& options, int frames) {
  const auto oni = dir / (name + ".oni");
  const auto uri = "cvo-virtual:" + kClip.string() + (options.empty() ? "" : "?" + options);
  const auto rec = cvo::testing::run_tool(
      "cvo-oni-record",
      cvo::testing::quoted(uri) + " " + cvo::testing::quoted(oni) + " --frames " + std::to_string(frames), dir);
  EXPECT_EQ(rec.exit_code, 0) << rec.err;
  return oni;
}

// The frames a recording holds: depth and colour pairs. OpenNI's Recorder writes on a thread of its
// own and may not write the last frame it was given before it is destroyed (on a loaded machine):
// at least `asked` - 1.
std::size_t frames_in(const fs::path& oni, std::size_t asked) {
  const auto state = inspect_oni(oni);
  std::size_t pairs = state.frames_per_node.empty() ? 0 : ~std::size_t{0};
  for (const auto& [node, frames] : state.frames_per_node) pairs = std::min<std::size_t>(pairs, frames);
  EXPECT_GE(pairs + 1, asked) << state.summary();
  return pairs;
}

// Every frame of the source, to its end.
std::vector<core::RgbdFrame> read_all(FrameSource& source) {
  std::vector<core::RgbdFrame> frames;
  for (int tries = 0; tries < 600; ++tries) {
    core::RgbdFrame frame;
    const auto r = source.read(frame, 100ms);
    if (r.status == ReadStatus::kEndOfStream) return frames;
    EXPECT_NE(r.status, ReadStatus::kDisconnected) << r.message;
    EXPECT_NE(r.status, ReadStatus::kBadInput) << r.message;
    if (r.status == ReadStatus::kFrame) frames.push_back(frame);
  }
  ADD_FAILURE() << "no end after " << frames.size() << " frames";
  return frames;
}

std::unique_ptr<FrameSource> play(const fs::path& oni) {
  SourceOptions options;
  options.realtime = false;
  return open_source("openni2:" + oni.string(), options);
}

// The folder's depth in 100 um units (the virtual device's), as the frame holds it.
cv::Mat depth_100um(const core::RgbdFrame& tum) {
  cv::Mat twice;
  tum.depth.convertTo(twice, CV_32S, 2.0);
  twice.setTo(0, twice > 65535);
  twice.convertTo(twice, CV_16U);
  return twice;
}

TEST(RealRecordings, ZeroPlaneValuesGiveTheKinectFocalLength) {
  cvo::test::TempDir dir;
  const auto oni = record(dir.path(), "kinect", std::string("fov=0&") + kKinect, 5);
  const auto source = play(oni);
  const auto frames = read_all(*source);
  ASSERT_EQ(frames.size(), frames_in(oni, 5));
  const auto factory = factory_camera(0x045e, 0x02ae, "");
  ASSERT_TRUE(factory.has_value());
  for (const auto& f : frames) {
    EXPECT_NEAR(f.intrinsics.fx, factory->focal_px_at_640, 0.01 * factory->focal_px_at_640);
    EXPECT_NEAR(f.intrinsics.fy, factory->focal_px_at_640, 0.01 * factory->focal_px_at_640);
    EXPECT_DOUBLE_EQ(f.intrinsics.fx, zero_plane_focal_px(120, 0.1042, 640));
    EXPECT_EQ(f.intrinsics.cx, 320.0);
  }
  EXPECT_NE(source->describe().find("zero-plane distance 120 mm and pixel size 0.1042 mm"), std::string::npos)
      << source->describe();
  // The same device live: its zero-plane values, not a field of view, give the focal length.
  const auto live = open_source("openni2:cvo-virtual:" + kClip.string() + "?fov=0&" + kKinect, SourceOptions{});
  EXPECT_NE(live->describe().find("zero-plane"), std::string::npos) << live->describe();
}

TEST(RealRecordings, NoFieldOfViewNoZeroPlaneAndNoKnownCameraAsksForACameraFile) {
  try {
    open_source("openni2:cvo-virtual:" + kClip.string() + "?fov=0", SourceOptions{});
    FAIL() << "opened without intrinsics";
  } catch (const SourceError& e) {
    EXPECT_NE(std::string(e.what()).find("camera file"), std::string::npos) << e.what();
  }
}

TEST(RealRecordings, ColourSmallerThanDepthGivesFramesOfColoursSize) {
  cvo::test::TempDir dir;
  const auto oni = record(dir.path(), "xtion", "colour_size=320x240", 4);
  const auto source = play(oni);
  const auto frames = read_all(*source);
  ASSERT_EQ(frames.size(), frames_in(oni, 4));
  auto tum = io::TumSequence::open(kClip);
  for (const auto& f : frames) {
    const auto expected = *tum.next();
    ASSERT_EQ(f.bgr.size(), cv::Size(320, 240));
    ASSERT_EQ(f.depth.size(), cv::Size(320, 240));
    cv::Mat nearest;
    cv::resize(depth_100um(expected), nearest, cv::Size(320, 240), 0, 0, cv::INTER_NEAREST);
    EXPECT_EQ(cv::norm(f.depth, nearest, cv::NORM_INF), 0.0) << "depth taken pixel for pixel, none made up";
    // The fields of view are angles: the focal length follows colour's size.
    EXPECT_NEAR(f.intrinsics.fx, expected.intrinsics.fx / 2, 1e-3);
    EXPECT_EQ(f.intrinsics.width, 320);
  }
  EXPECT_NE(source->describe().find("depth 640x480"), std::string::npos) << source->describe();
}

TEST(RealRecordings, AMirroredRecordingIsFlippedBack) {
  cvo::test::TempDir dir;
  const auto oni = record(dir.path(), "mirrored", "mirrored=1", 3);
  const auto source = play(oni);
  const auto frames = read_all(*source);
  ASSERT_EQ(frames.size(), frames_in(oni, 3));
  auto tum = io::TumSequence::open(kClip);
  for (const auto& f : frames) {
    const auto expected = *tum.next();
    EXPECT_EQ(cv::norm(f.bgr, expected.bgr, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(f.depth, depth_100um(expected), cv::NORM_INF), 0.0);
  }
  EXPECT_NE(source->describe().find("mirrored"), std::string::npos) << source->describe();
}

TEST(RealRecordings, ACopyCutOffPlaysTheFramesItHolds) {
  cvo::test::TempDir dir;
  const auto oni = record(dir.path(), "whole", "", 10);
  const auto cut = dir.path() / "cut.oni";
  fs::copy_file(oni, cut);
  fs::resize_file(cut, fs::file_size(oni) * 2 / 5);
  const auto state = inspect_oni(cut);
  EXPECT_TRUE(state.problem.empty()) << state.problem;
  EXPECT_TRUE(state.needs_repair());
  const auto source = play(cut);
  const auto frames = read_all(*source);
  EXPECT_GT(frames.size(), 0u);
  EXPECT_LT(frames.size(), 10u);
  auto tum = io::TumSequence::open(kClip);
  for (const auto& f : frames) EXPECT_EQ(cv::norm(f.bgr, tum.next()->bgr, cv::NORM_INF), 0.0) << "in order, whole";
  EXPECT_NE(source->describe().find("repaired copy"), std::string::npos) << source->describe();
}

TEST(RealRecordings, ARecordingNeverClosedPlaysTheFramesItHolds) {
  cvo::test::TempDir dir;
  const auto oni = dir.path() / "killed.oni";
  // The recorder killed mid-recording, once a few frames are written: OpenNI never closes it.
  const auto command =
      "(" + (fs::path(CVO_TOOLS_DIR) / "cvo-oni-record").string() + " " +
      cvo::testing::quoted("cvo-virtual:" + kClip.string()) + " " + cvo::testing::quoted(oni) +
      " > /dev/null 2>&1 & pid=$!; for i in $(seq 2000); do [ $(stat -c %s " + cvo::testing::quoted(oni) +
      " 2>/dev/null || echo 0) -gt 4000000 ] && break; sleep 0.005; done;" + " kill -9 $pid; wait $pid) 2>/dev/null";
  ASSERT_NE(std::system(command.c_str()), -1);
  const auto state = inspect_oni(oni);
  ASSERT_TRUE(state.problem.empty()) << state.problem;
  if (state.closed) GTEST_SKIP() << "the recorder finished before it could be killed (" << state.summary() << ")";
  const auto source = play(oni);
  const auto frames = read_all(*source);
  EXPECT_GT(frames.size(), 0u);
  EXPECT_NE(source->describe().find("never closed"), std::string::npos) << source->describe();
}

// cvo-trackerd on a file that cannot be played: exit 1 within 5 s, naming the file's state, no
// USB wording, the last CVO_STATUS FAILED.
void expect_exit_one(const fs::path& dir, const std::string& name, const fs::path& file, const std::string& says) {
  const auto out = dir / (name + ".lcmlog"), err = dir / (name + ".stderr");
  const auto start = std::chrono::steady_clock::now();
  cvo::testing::DaemonProcess d(
      kTrackerd,
      {"--lcm-url", "file://" + out.string() + "?mode=w", "--set", "trackerd.realtime_priority=0", "--set",
       "trackerd.lock_memory=false", "--source", "openni2:" + file.string(), "--exit-on-eof"},
      err);
  const auto code = d.wait_for(30s);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto text = cvo::testing::slurp(err);
  ASSERT_TRUE(code.has_value()) << name << ": still running\n" << text;
  EXPECT_EQ(*code, 1) << text;
  EXPECT_LT(seconds, 5.0) << text;
  EXPECT_NE(text.find(says), std::string::npos) << text;
  EXPECT_EQ(text.find("USB"), std::string::npos) << text;
  EXPECT_EQ(text.find("libusb"), std::string::npos) << text;
  EXPECT_EQ(text.find("back-off"), std::string::npos) << text;
  const auto log = cvo::testing::read_published(out);
  ASSERT_FALSE(log.statuses.empty());
  const int failed = cvo_lcm::status_t::STATE_FAILED;  // a copy: the constant has no definition to bind to
  EXPECT_EQ(log.statuses.back().state, failed);
  EXPECT_NE(log.statuses.back().detail.find(says), std::string::npos) << log.statuses.back().detail;
}

TEST(RealRecordings, TrackerdExitsOneOnAFileItCannotPlay) {
  cvo::test::TempDir dir;
  expect_exit_one(dir.path(), "missing", dir.path() / "missing.oni", "no such file");
  std::ofstream(dir.path() / "text.oni") << "not a recording\n";
  expect_exit_one(dir.path(), "text", dir.path() / "text.oni", "not an ONI recording");
  const auto oni = record(dir.path(), "whole", "", 2);
  fs::copy_file(oni, dir.path() / "stub.oni");
  fs::resize_file(dir.path() / "stub.oni", 10);
  expect_exit_one(dir.path(), "stub", dir.path() / "stub.oni", "truncated: 10 bytes");
  fs::copy_file(oni, dir.path() / "no_frame.oni");
  fs::resize_file(dir.path() / "no_frame.oni", 600);
  expect_exit_one(dir.path(), "no_frame", dir.path() / "no_frame.oni", "holds no frame");
  // A recording that says nothing of its camera (no field of view, no zero plane, no camera
  // OpenNI's player names): exit 1 naming what it lacks.
  const auto blind = record(dir.path(), "blind", "fov=0", 2);
  expect_exit_one(dir.path(), "blind", blind, "no intrinsics");
}

TEST(RealRecordings, TheCameraKeyGivesARecordingItsIntrinsics) {
  cvo::test::TempDir dir;
  const auto blind = record(dir.path(), "blind", "fov=0", 5);
  core::Intrinsics k;
  k.fx = 525.0, k.fy = 525.0, k.cx = 319.5, k.cy = 239.5, k.width = 640, k.height = 480, k.depth_scale = 1000;
  const auto camera = dir.path() / "kinect_rgb.yaml";
  std::ofstream(camera) << io::format_intrinsics_yaml(k, "a Kinect's colour camera");
  const auto out = dir.path() / "c.lcmlog", err = dir.path() / "c.stderr";
  cvo::testing::DaemonProcess d(
      kTrackerd,
      {"--lcm-url", "file://" + out.string() + "?mode=w", "--set", "trackerd.realtime_priority=0", "--set",
       "trackerd.lock_memory=false", "--set", "trackerd.paced=false", "--set", "camera=" + camera.string(), "--source",
       "openni2:" + blind.string(), "--exit-on-eof", "--deterministic"},
      err);
  const auto code = d.wait_for(120s);
  const auto text = cvo::testing::slurp(err);
  ASSERT_TRUE(code.has_value()) << text;
  EXPECT_EQ(*code, 0) << text;
  EXPECT_NE(text.find("fx 525.0000 fy 525.0000 cx 319.50 cy 239.50 from the camera file"), std::string::npos) << text;
  EXPECT_EQ(cvo::testing::read_published(out).poses.size(), frames_in(blind, 5)) << text;
}

TEST(RealRecordings, TrackerdTracksEveryFrameOfAZeroPlaneRecording) {
  cvo::test::TempDir dir;
  const auto oni = record(dir.path(), "kinect", std::string("fov=0&") + kKinect, 20);
  const auto out = dir.path() / "k.lcmlog", err = dir.path() / "k.stderr";
  cvo::testing::DaemonProcess d(
      kTrackerd,
      {"--lcm-url", "file://" + out.string() + "?mode=w", "--set", "trackerd.realtime_priority=0", "--set",
       "trackerd.lock_memory=false", "--set", "trackerd.paced=false", "--source", "openni2:" + oni.string(),
       "--exit-on-eof", "--deterministic"},
      err);
  const auto code = d.wait_for(120s);
  const auto text = cvo::testing::slurp(err);
  ASSERT_TRUE(code.has_value()) << text;
  EXPECT_EQ(*code, 0) << text;
  EXPECT_NE(text.find("fx 575.8157 fy 575.8157 cx 320.00 cy 240.00 from the depth stream's zero-plane"),
            std::string::npos)
      << text;
  const auto log = cvo::testing::read_published(out);
  ASSERT_EQ(log.poses.size(), frames_in(oni, 20)) << text;
  for (const auto& p : log.poses)
    for (const double v : p.odom_pose.position) EXPECT_TRUE(std::isfinite(v));

  // cvo-run measures the same recording offline with one command: the daemon's poses (its
  // odom_pose is KF-CVO's published pose, as cvo-run --mode kf-cvo writes).
  const auto kf = dir.path() / "kf.txt";
  const auto run = cvo::testing::run_tool(
      "cvo-run", cvo::testing::quoted("openni2:" + oni.string()) + " --mode kf-cvo --out " + cvo::testing::quoted(kf),
      dir.path());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("zero-plane"), std::string::npos) << run.err;
  const auto offline = io::read_tum_trajectory(kf);
  ASSERT_EQ(offline.size(), log.poses.size());
  double furthest = 0;
  for (std::size_t i = 0; i < offline.size(); ++i) {
    const Eigen::Vector3d daemon(log.poses[i].odom_pose.position[0], log.poses[i].odom_pose.position[1],
                                 log.poses[i].odom_pose.position[2]);
    furthest = std::max(furthest, (offline[i].pose.translation() - daemon).norm());
  }
  std::printf("cvo-run vs cvo-trackerd --deterministic on a zero-plane .oni: largest difference %.3g m\n", furthest);
  EXPECT_LT(furthest, 1e-5);
}

}  // namespace
}  // namespace cvo::drivers
