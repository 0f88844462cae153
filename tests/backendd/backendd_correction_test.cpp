// cvo-backendd's map updates cost what a tracker can afford (issue 27): fed the keyframes and local
// graphs of a tracker session from a file:// log, it publishes after each of them that session's
// CVO_MAP_CORRECTION, whose size does not grow with the map (the same bytes after the 10th keyframe
// as after the 500th), while the full CVO_MAP (which does) goes out rarely with
// backendd.map_period_s > 0, and after every change with 0.
//
// The keyframes are tiny (8x6 images, three points: nothing for ORB, so no loop), so that 500 of
// them take seconds. No network: the input is a log and the output another.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/core.hpp>

#include "cvo_lcm/map_correction_t.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/lcm/local_graph_conversion.hpp"
#include "tests/support/daemon_process.hpp"
#include "tests/support/lcm_log.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr std::int64_t kSession = 0x27c0'77ec'7000'0001;
constexpr std::int64_t kStride = 3;  // frames between keyframes

core::SE3 odometry(std::int64_t frame) {
  return {core::so3_exp({0, 0.002 * static_cast<double>(frame), 0}),
          Eigen::Vector3d(0.01 * static_cast<double>(frame), 0, 0)};
}
double stamp(std::int64_t frame) { return 1305031229.0 + 0.033 * static_cast<double>(frame); }

// Keyframe `id` at frame id * kStride: an 8x6 gradient and three points.
std::vector<std::uint8_t> keyframe(std::int64_t id) {
  lcm::Keyframe k;
  k.session = kSession;
  k.robot = "hall-a";
  k.id = id;
  k.frame.index = static_cast<std::uint64_t>(id * kStride);
  k.frame.timestamp = k.frame.depth_timestamp = stamp(id * kStride);
  k.frame.intrinsics.fx = k.frame.intrinsics.fy = 10;
  k.frame.intrinsics.cx = 4;
  k.frame.intrinsics.cy = 3;
  k.frame.intrinsics.width = 8;
  k.frame.intrinsics.height = 6;
  k.frame.bgr.create(6, 8, CV_8UC3);
  k.frame.depth.create(6, 8, CV_16UC1);
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 8; ++x) {
      k.frame.bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>(30 * x), static_cast<uchar>(40 * y), 128);
      k.frame.depth.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(5000 + 100 * x + 10 * y);
    }
  k.pose = odometry(id * kStride);
  for (int p = 0; p < 3; ++p) k.cloud.push_back({0.1f * p, -0.1f * p, 1.0f + p}, registration::Feature{});
  std::string error;
  const auto m = lcm::to_message(k, {lcm::ColourEncoding::kPng, lcm::DepthEncoding::kPng}, &error);
  EXPECT_TRUE(m) << error;
  return lcm::encode(m.value_or(cvo_lcm::keyframe_t{}));
}

// The local graph of keyframe `id`, closed at the next keyframe's frame: one edge.
std::vector<std::uint8_t> local_graph(std::int64_t id) {
  const std::int64_t from = id * kStride, to = from + kStride;
  odometry::LocalGraph graph(2);
  graph.add_node({static_cast<std::uint64_t>(from), stamp(from), odometry(from)});
  graph.add_node({static_cast<std::uint64_t>(to), stamp(to), odometry(to)});
  graph.add_edge({static_cast<std::uint64_t>(from), static_cast<std::uint64_t>(to),
                  odometry(from).inverse() * odometry(to), 1e4 * core::Matrix6d::Identity()});
  return lcm::encode(lcm::to_message(graph, kSession, id, static_cast<std::int64_t>(stamp(to) * 1e6), "hall-a"));
}

// A session of `keyframes` keyframes in the tracker's order (the graph of keyframe k - 1 closes
// when keyframe k is made, and goes out first), the back end on it, what it published.
struct BackendRun {
  int exit_code = -9;
  std::string err;
  cvo::testing::PublishedLog published;
};

// `store`: the keyframe store's name in `dir` (`name` when empty).
BackendRun run_backendd(const fs::path& dir, const std::string& name, std::int64_t keyframes,
                        const std::vector<std::string>& settings = {}, const std::string& store = "") {
  const auto input = dir / (name + ".lcmlog"), out = dir / (name + ".out.lcmlog");
  {
    ::lcm::LogFile log(input.string(), "w");
    std::int64_t t = 0;
    for (std::int64_t id = 0; id < keyframes; ++id) {
      if (id > 0) cvo::testing::write_event(log, "CVO_LOCAL_GRAPH", local_graph(id - 1), t += 1000);
      cvo::testing::write_event(log, "CVO_KEYFRAME", keyframe(id), t += 1000);
    }
    // LCM cannot open a log without an event: none, the first keyframe again (a repeat, not used).
    if (keyframes == 0) cvo::testing::write_event(log, "CVO_KEYFRAME", keyframe(0), t += 1000);
  }
  std::vector<std::string> args{"--lcm-url",     "file://" + input.string() + "?speed=0",
                                "--publish-url", "file://" + out.string() + "?mode=w",
                                "--store",       (dir / ((store.empty() ? name : store) + ".store")).string(),
                                "--exit-on-eof"};
  for (const auto& s : settings) args.insert(args.end(), {"--set", s});
  cvo::testing::DaemonProcess backendd(fs::path(CVO_TOOLS_DIR) / "cvo-backendd", args, dir / (name + ".txt"));
  BackendRun r;
  r.exit_code = backendd.wait_for(600s).value_or(-9);
  r.err = cvo::testing::slurp(dir / (name + ".txt"));
  r.published = cvo::testing::read_published(out);
  return r;
}

// The session's first correction that counts `keyframes` keyframes: the one after that keyframe.
const cvo_lcm::map_correction_t* after_keyframe(const BackendRun& r, std::int32_t keyframes) {
  for (const auto& c : r.published.map_corrections)
    if (c.session.session == kSession && c.session.keyframes == keyframes) return &c;
  return nullptr;
}

TEST(BackenddCorrection, BytesPerUpdateDoNotGrowWithTheMapAndTheFullMapGoesRarely) {
  const cvo::test::TempDir dir("backendd_correction");
  constexpr std::int64_t kKeyframes = 500;
  const BackendRun r = run_backendd(dir.path(), "long", kKeyframes);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.published.undecodable, 0);
  ASSERT_FALSE(r.published.maps.empty()) << r.err;
  const auto& last_map = r.published.maps.back();
  EXPECT_EQ(last_map.num_keyframes, kKeyframes) << "every keyframe in the final map\n" << r.err;
  EXPECT_EQ(last_map.num_loops, 0) << "tiny frames: no loop, so no correction carries one";

  // A correction after every record: each changes the session's entry (its keyframes, correction,
  // covariance); and the one after the 500th keyframe is exactly as large as after the 10th.
  EXPECT_GE(r.published.map_corrections.size(), static_cast<std::size_t>(2 * kKeyframes - 1));
  const auto* tenth = after_keyframe(r, 10);
  const auto* last = after_keyframe(r, static_cast<std::int32_t>(kKeyframes));
  ASSERT_TRUE(tenth && last) << r.err;
  EXPECT_EQ(last->getEncodedSize(), tenth->getEncodedSize());
  EXPECT_EQ(last->session.covariance_keyframe, kKeyframes - 1) << "its newest keyframe's covariance";
  EXPECT_GT(last->revision, tenth->revision);
  std::printf(
      "CVO_MAP_CORRECTION after keyframe 10: %d bytes, after keyframe %lld: %d bytes; final CVO_MAP: %d bytes; "
      "%zu CVO_MAPs and %zu CVO_MAP_CORRECTIONs for %lld keyframes and %lld local graphs\n",
      tenth->getEncodedSize(), static_cast<long long>(kKeyframes), last->getEncodedSize(), last_map.getEncodedSize(),
      r.published.maps.size(), r.published.map_corrections.size(), static_cast<long long>(kKeyframes),
      static_cast<long long>(kKeyframes - 1));
  // The full map at most every backendd.map_period_s (5 s): a few for a run of seconds, not one a
  // record (it would be 999).
  EXPECT_LT(r.published.maps.size(), static_cast<std::size_t>(kKeyframes / 10)) << r.err;
  EXPECT_GT(last_map.getEncodedSize(), 20 * last->getEncodedSize());
  EXPECT_NE(r.err.find("CVO_MAP_CORRECTION sent ("), std::string::npos) << r.err;

  // Restarted on its store (nothing new comes): the store's map goes out once every record of it is
  // in, not a correction per record replayed; then the final map at the stop.
  const BackendRun again = run_backendd(dir.path(), "again", 0, {}, "long");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  ASSERT_EQ(again.published.maps.size(), 2u) << again.err;
  EXPECT_EQ(again.published.maps.front().num_keyframes, kKeyframes) << "the whole store's";
  EXPECT_LE(again.published.map_corrections.size(), 2u) << "the replayed map's, and the final one's if it changed";
  ASSERT_FALSE(again.published.map_corrections.empty());
  EXPECT_EQ(again.published.map_corrections.front().session.keyframes, kKeyframes);
}

TEST(BackenddCorrection, WithAMapPeriodOfZeroTheFullMapGoesAfterEveryChange) {
  const cvo::test::TempDir dir("backendd_correction_zero");
  constexpr std::int64_t kKeyframes = 12;
  const BackendRun r = run_backendd(dir.path(), "short", kKeyframes, {"backendd.map_period_s=0"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Every keyframe and local graph, and the final map after the final optimisation.
  EXPECT_EQ(r.published.maps.size(), static_cast<std::size_t>(2 * kKeyframes - 1 + 1)) << r.err;
  EXPECT_GE(r.published.map_corrections.size(), static_cast<std::size_t>(2 * kKeyframes - 1));
}

}  // namespace
}  // namespace cvo::daemon
