// Keyframe <-> keyframe_t, LocalGraph <-> local_graph_t and the map <-> map_t: lossless round trips
// through bytes, and malformed messages refused with a message.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <opencv2/core.hpp>

#include "lcm/sample_messages.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/lcm/local_graph_conversion.hpp"
#include "libcvo/lcm/map_conversion.hpp"
#include "libcvo/lcm/map_correction_conversion.hpp"
#include "libcvo/registration/point_selection.hpp"
#include "tests/lcm/through_bytes.hpp"
#include "tests/support/map_session.hpp"

namespace cvo::lcm {
namespace {

TEST(KeyframeConversion, RoundTripIsLosslessWithPng) {
  Keyframe k;
  k.session = -0x0123'4567'89ab'cdef;  // 64 random bits: any sign
  k.id = 7;
  k.robot = "hall-a_2.east";
  k.frame = io::TumSequence::open(std::filesystem::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50").read(5);
  k.pose = core::SE3::exp((core::Vector6d() << 0.1, -0.2, 0.3, 0.01, 0.02, -0.03).finished());
  registration::PointSelector selector(k.frame.bgr.cols, k.frame.bgr.rows, core::SelectionParameters{});
  k.cloud = registration::PointCloud(8192);
  selector.select(k.frame, k.cloud);
  ASSERT_GT(k.cloud.size(), 1000u);

  std::string error;
  const auto message = to_message(k, RgbdEncoding{ColourEncoding::kPng, DepthEncoding::kPng}, &error);
  ASSERT_TRUE(message) << error;
  const auto decoded = through_bytes(*message);
  ASSERT_TRUE(decoded);
  const auto back = from_message(*decoded, &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->session, -0x0123'4567'89ab'cdef);
  EXPECT_EQ(back->id, 7);
  EXPECT_EQ(back->robot, "hall-a_2.east");
  EXPECT_EQ(back->frame.index, k.frame.index);
  EXPECT_EQ(back->frame.timestamp, k.frame.timestamp);
  ASSERT_TRUE(k.frame.intrinsics.has_distortion());  // tum_fr1
  EXPECT_EQ(back->frame.intrinsics.distortion, k.frame.intrinsics.distortion);
  EXPECT_EQ(cv::norm(back->frame.bgr, k.frame.bgr, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(back->frame.depth, k.frame.depth, cv::NORM_INF), 0);
  EXPECT_LT((back->pose.matrix() - k.pose.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  ASSERT_EQ(back->cloud.size(), k.cloud.size());
  for (std::size_t i = 0; i < k.cloud.size(); i += 97) {
    EXPECT_EQ(back->cloud.position(i), k.cloud.position(i));
    EXPECT_EQ(back->cloud.feature(i), k.cloud.feature(i));
  }
}

TEST(KeyframeConversion, NonFinitePointsAndBadPosesAreRefused) {
  Keyframe k;
  k.frame = io::TumSequence::open(std::filesystem::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50").read(0);
  k.robot = "hall-a";
  k.cloud = registration::PointCloud(4);
  k.cloud.push_back({0, 0, 1}, registration::Feature{});
  std::string error;
  auto message = to_message(k, RgbdEncoding{ColourEncoding::kJpeg, DepthEncoding::kPng}, &error);
  ASSERT_TRUE(message) << error;
  EXPECT_TRUE(from_message(*message, &error)) << error;

  auto bad_point = *message;
  bad_point.xyz[0][2] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(from_message(bad_point, &error));
  EXPECT_NE(error.find("not finite"), std::string::npos) << error;

  auto bad_pose = *message;
  bad_pose.pose.orientation[0] = 3;  // not a unit quaternion
  EXPECT_FALSE(from_message(bad_pose, &error));
  EXPECT_NE(error.find("pose"), std::string::npos) << error;

  auto bad_image = *message;
  bad_image.colour.resize(10);
  bad_image.colour_size = 10;
  EXPECT_FALSE(from_message(bad_image, &error));
}

odometry::LocalGraph sample_graph() {
  odometry::LocalGraph g(8);
  for (std::uint64_t i = 10; i < 14; ++i)
    g.add_node({i, 100.0 + 0.033 * static_cast<double>(i),
                core::SE3::from_translation({0.01 * static_cast<double>(i), 0, 0})});
  for (std::uint64_t i = 11; i < 14; ++i) {
    core::Matrix6d information = core::Matrix6d::Identity() * static_cast<double>(i);
    information(0, 1) = information(1, 0) = 0.5;
    g.add_edge({10, i, core::SE3::from_translation({0.01 * static_cast<double>(i - 10), 0, 0}), information});
    g.add_edge({i - 1, i, core::SE3::from_translation({0.01, 0, 0}), information * 2});
  }
  return g;
}

// Every tracker message names its robot (proto/pose_t.lcm): a keyframe or local graph that names
// none, or a name no log or status line could show, is refused as content.
TEST(RobotNames, AKeyframeOrLocalGraphWithoutARobotNameIsRefused) {
  const auto keyframe = through_bytes(test::sample_keyframe());
  const auto graph = through_bytes(to_message(sample_graph(), 1, 3, 0, "hall-a"));
  ASSERT_TRUE(keyframe && graph);
  EXPECT_EQ(graph->robot, "hall-a");
  for (const std::string& bad :
       {std::string(), std::string("hall a"), std::string("r\n"), std::string(65, 'r'), std::string("caf\xc3\xa9")}) {
    std::string error;
    auto failure = ContentFailure::kNotFinite;
    auto k = *keyframe;
    k.robot = bad;
    EXPECT_FALSE(from_message(k, &error, &failure)) << bad;
    EXPECT_EQ(failure, ContentFailure::kContent);
    EXPECT_NE(error.find("no robot name"), std::string::npos) << error;
    auto g = *graph;
    g.robot = bad;
    failure = ContentFailure::kNotFinite;
    EXPECT_FALSE(from_message(g, &error, &failure)) << bad;
    EXPECT_EQ(failure, ContentFailure::kContent);
    EXPECT_NE(error.find("no robot name"), std::string::npos) << error;
  }
  auto g = *graph;
  g.robot = std::string(64, 'r');  // the longest name
  EXPECT_TRUE(from_message(g, nullptr));
}

TEST(LocalGraphConversion, RoundTripKeepsNodesEdgesAndInformation) {
  const auto graph = sample_graph();
  const auto decoded = through_bytes(to_message(graph, 0x7e57, 3, 123456, "hall-a"));
  ASSERT_TRUE(decoded);
  EXPECT_EQ(decoded->session, 0x7e57);
  EXPECT_EQ(decoded->keyframe_id, 3);
  std::string error;
  const auto back = from_message(*decoded, &error);
  ASSERT_TRUE(back) << error;
  ASSERT_EQ(back->nodes().size(), graph.nodes().size());
  ASSERT_EQ(back->edges().size(), graph.edges().size());
  EXPECT_EQ(back->keyframe().frame_index, 10u);
  for (std::size_t i = 0; i < graph.edges().size(); ++i) {
    EXPECT_EQ(back->edges()[i].from, graph.edges()[i].from);
    EXPECT_EQ(back->edges()[i].to, graph.edges()[i].to);
    EXPECT_EQ(back->edges()[i].information, graph.edges()[i].information);
    EXPECT_LT((back->edges()[i].measurement.matrix() - graph.edges()[i].measurement.matrix()).cwiseAbs().maxCoeff(),
              1e-12);
  }
}

TEST(LocalGraphConversion, EdgesToUnknownFramesAndBadInformationAreRefused) {
  auto message = to_message(sample_graph(), 1, 3, 0, "hall-a");
  std::string error;
  auto dangling = message;
  dangling.edges[1].to = 99;
  EXPECT_FALSE(from_message(dangling, &error));
  EXPECT_NE(error.find("not in the graph"), std::string::npos) << error;

  auto nan = message;
  nan.edges[0].information[7] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(from_message(nan, &error));
  EXPECT_NE(error.find("information"), std::string::npos) << error;

  auto empty = message;
  empty.nodes.clear();
  empty.num_nodes = 0;
  EXPECT_FALSE(from_message(empty, &error));
}

// The sample every encoding and door test uses is a graph the back end accepts.
TEST(LocalGraphConversion, TheSampleMessageIsUsable) {
  std::string error;
  EXPECT_TRUE(from_message(test::sample_local_graph(), &error)) << error;
}

// Which check refused a graph (the back end counts each kind in CVO_STATUS): an indefinite or
// non-symmetric information matrix, a NaN, or a malformed graph.
TEST(LocalGraphConversion, RefusalsSayWhichKind) {
  const auto message = to_message(sample_graph(), 1, 3, 0, "hall-a");
  std::string error;
  auto failure = ContentFailure::kContent;

  // Edge 10->12 with the translation x-y block [[12, 13], [13, 12]]: eigenvalues 25 and -1.
  auto indefinite = message;
  indefinite.edges[2].information[1] = indefinite.edges[2].information[6] = 13;
  EXPECT_FALSE(from_message(indefinite, &error, &failure));
  EXPECT_EQ(failure, ContentFailure::kInformation);
  EXPECT_NE(error.find("edge 10->12: information is not positive semi-definite (eigenvalues -1 .. 25)"),
            std::string::npos)
      << error;

  auto asymmetric = message;
  asymmetric.edges[1].information[6 * 4 + 2] = 0.5;  // (4, 2) but not (2, 4)
  EXPECT_FALSE(from_message(asymmetric, &error, &failure));
  EXPECT_EQ(failure, ContentFailure::kInformation);
  EXPECT_NE(error.find("edge 10->11: information is not symmetric"), std::string::npos) << error;

  auto nan = message;
  nan.edges[3].information[0] = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(from_message(nan, &error, &failure));
  EXPECT_EQ(failure, ContentFailure::kNotFinite);

  auto nan_pose = message;
  nan_pose.nodes[2].pose.position[1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(from_message(nan_pose, &error, &failure));
  EXPECT_EQ(failure, ContentFailure::kNotFinite);
  EXPECT_NE(error.find("node 12"), std::string::npos) << error;

  auto not_unit = message;
  not_unit.edges[0].measurement.orientation[0] = 3;
  EXPECT_FALSE(from_message(not_unit, &error, &failure));
  EXPECT_EQ(failure, ContentFailure::kContent);

  auto dangling = message;
  dangling.edges[1].to = 99;
  failure = ContentFailure::kInformation;
  EXPECT_FALSE(from_message(dangling, &error, &failure));
  EXPECT_EQ(failure, ContentFailure::kContent);

  // Semi-definite is information too: a direction without any (a registration on a flat wall).
  auto semi = message;
  for (double& v : semi.edges[0].information) v = 0;
  semi.edges[0].information[0] = semi.edges[0].information[7] = 1e4;
  EXPECT_TRUE(from_message(semi, &error)) << error;
}

}  // namespace
}  // namespace cvo::lcm

namespace cvo::lcm {
namespace {

// A two-session map: CVO_MAP carries each session's placement and correction, every keyframe by
// (session, id) with its time, and loops across sessions, and comes back as it was sent.
TEST(MapConversion, RoundTripKeepsSessionsKeyframesAndLoops) {
  slam::Map map;
  map.revision = 42;
  const core::SE3 correction = core::SE3::from_translation({0.5, -0.25, 2.0});
  map.sessions = {test::map_session(-7, true, -7, 2, 0, core::SE3()),
                  test::map_session(99, false, 99, 1, -1, correction)};
  map.sessions[0].robot = "hall-a";  // the second's robot is not known (none of its keyframes came)
  map.keyframes = {{-7, 0, 1305031229.528748, core::SE3()},
                   {-7, 1, 1305031230.5, core::SE3::from_translation({1, 0, 0})},
                   {99, 0, 1305031240.25, correction}};
  slam::MapLoop loop;
  loop.from_session = -7;
  loop.from_id = 1;
  loop.to_session = 99;
  loop.to_id = 0;
  loop.loop.measurement = core::SE3::from_translation({0, 0.1, 0});
  loop.loop.information = 3.0 * core::Matrix6d::Identity();
  map.loops = {loop};

  const auto decoded = through_bytes(to_message(map, 1234));
  ASSERT_TRUE(decoded);
  EXPECT_EQ(decoded->utime, 1234);
  std::string error;
  const auto back = from_message(*decoded, &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->revision, 42u);
  ASSERT_EQ(back->sessions.size(), 2u);
  EXPECT_TRUE(back->sessions[0].placed);
  EXPECT_FALSE(back->sessions[1].placed);
  EXPECT_EQ(back->sessions[1].session, 99);
  EXPECT_EQ(back->sessions[1].joined_at_keyframe, -1);
  EXPECT_EQ(back->sessions[0].robot, "hall-a");
  EXPECT_EQ(back->sessions[1].robot, "");
  EXPECT_LT((back->sessions[1].correction.translation() - correction.translation()).norm(), 1e-12);
  ASSERT_EQ(back->keyframes.size(), 3u);
  EXPECT_EQ(back->keyframes[2].session, 99);
  EXPECT_NEAR(back->keyframes[1].timestamp, 1305031230.5, 1e-6);
  ASSERT_EQ(back->loops.size(), 1u);
  EXPECT_EQ(back->loops[0].from_session, -7);
  EXPECT_EQ(back->loops[0].to_id, 0);
  EXPECT_EQ(back->loops[0].loop.information(2, 2), 3.0);

  auto forged = *decoded;
  forged.robots[1] = "hall a";
  EXPECT_FALSE(from_message(forged, &error));
  EXPECT_NE(error.find("session 99: robot of 6 bytes is no robot name"), std::string::npos) << error;

  auto old = *decoded;
  old.version = 1;  // a back end from before sessions
  EXPECT_FALSE(from_message(old, &error));
  EXPECT_NE(error.find("schema version 1"), std::string::npos) << error;
}

// CVO_MAP_CORRECTION says whose session it places: the robot comes with the entry, and a forged
// name is refused as the whole correction.
TEST(MapCorrectionConversion, TheSessionsRobotComesWithItsEntry) {
  slam::SessionCorrection c{5, test::map_session(99, true, -7, 1, 0, core::SE3()), {}};
  c.session.robot = "dock.b_2";
  const auto decoded = through_bytes(to_message(c, 1234, 1));
  ASSERT_TRUE(decoded);
  EXPECT_EQ(decoded->robot, "dock.b_2");
  std::string error;
  const auto back = from_message(*decoded, &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->session.robot, "dock.b_2");
  auto forged = *decoded;
  forged.robot = "dock b";
  EXPECT_FALSE(from_message(forged, &error));
  EXPECT_NE(error.find("no robot name"), std::string::npos) << error;
}

}  // namespace
}  // namespace cvo::lcm
