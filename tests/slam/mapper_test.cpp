// slam::Mapper at its door: a keyframe is (session, id); a repeat is a duplicate, a repeat with
// other content or out of order is refused with a message, and the mapper goes on.
#include "libcvo/slam/mapper.hpp"

#include <string>

#include <gtest/gtest.h>

#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/posegraph/marginals.hpp"
#include "libcvo/registration/point_selection.hpp"

namespace cvo::slam {
namespace {

struct RealKeyframe {
  core::RgbdFrame frame;
  registration::PointCloud cloud{4096};
};

RealKeyframe real_keyframe(std::size_t i) {
  const auto sequence = io::TumSequence::open(CVO_TEST_DATA_DIR "/fr1_rpy_50");
  RealKeyframe k;
  k.frame = sequence.read(i);
  registration::PointSelector selector(k.frame.bgr.cols, k.frame.bgr.rows, core::SelectionParameters{});
  selector.select(k.frame, k.cloud);
  return k;
}

std::string refusal(Mapper& mapper, const SessionKeyframe& k) {
  try {
    mapper.add_keyframe(k);
  } catch (const MapperError& e) {
    return e.what();
  }
  return "";
}

TEST(Mapper, AKeyframeRepeatedWithOtherContentIsRefusedAndTheMapperGoesOn) {
  Mapper mapper(loop_closure::Vocabulary::load(CVO_DEFAULT_VOCABULARY), MapperParameters{});
  const RealKeyframe a = real_keyframe(0), b = real_keyframe(10);
  constexpr core::SessionId kSession = 0x5e55;
  EXPECT_FALSE(mapper.add_keyframe({kSession, 0, a.frame, core::SE3(), a.cloud}).duplicate);
  EXPECT_TRUE(mapper.add_keyframe({kSession, 0, a.frame, core::SE3(), a.cloud}).duplicate);  // re-sent

  const std::string moved = refusal(mapper, {kSession, 0, a.frame, core::SE3::from_translation({0.1, 0, 0}), a.cloud});
  EXPECT_NE(moved.find("keyframe 0 of session 0x0000000000005e55 is known with other content"), std::string::npos)
      << moved;
  EXPECT_FALSE(refusal(mapper, {kSession, 0, b.frame, core::SE3(), b.cloud}).empty());  // another frame

  EXPECT_FALSE(mapper.add_keyframe({kSession, 2, b.frame, core::SE3(), b.cloud}).duplicate);
  // Id 1 may come late (a re-sent keyframe), but not with a frame after id 2's.
  RealKeyframe late = real_keyframe(12);
  const std::string order = refusal(mapper, {kSession, 1, late.frame, core::SE3(), late.cloud});
  EXPECT_NE(order.find("out of order"), std::string::npos) << order;
  late.frame.index = 5;
  EXPECT_TRUE(refusal(mapper, {kSession, 1, late.frame, core::SE3(), late.cloud}).empty());

  // The same ids in another session are other keyframes.
  EXPECT_FALSE(mapper.add_keyframe({kSession + 1, 0, b.frame, core::SE3(), b.cloud}).duplicate);
  const Map map = mapper.map();
  ASSERT_EQ(map.sessions.size(), 2u);
  EXPECT_EQ(map.sessions[0].keyframes, 3u);
  EXPECT_TRUE(map.sessions[0].placed);  // the first session defines the map
  EXPECT_EQ(map.sessions[0].joined_at_keyframe, 0);
  EXPECT_EQ(map.keyframes.size(), 4u);
  EXPECT_TRUE(mapper.knows(kSession, 1));
}

// Several robots, one map: each session's entry names the robot its first keyframe named (a
// later keyframe of the same session cannot rename it), in map() and in its correction alike.
TEST(Mapper, EachSessionIsNamedByItsRobot) {
  Mapper mapper(loop_closure::Vocabulary::load(CVO_DEFAULT_VOCABULARY), MapperParameters{});
  const RealKeyframe a = real_keyframe(0), b = real_keyframe(10);
  mapper.add_keyframe({1, 0, a.frame, core::SE3(), a.cloud, "hall-a"});
  mapper.add_keyframe({1, 1, b.frame, core::SE3(), b.cloud, "impostor"});
  mapper.add_keyframe({2, 0, b.frame, core::SE3(), b.cloud, "dock.b_2"});
  mapper.add_keyframe({3, 0, a.frame, core::SE3(), a.cloud});  // no robot named
  const Map map = mapper.map();
  ASSERT_EQ(map.sessions.size(), 3u);
  EXPECT_EQ(map.sessions[0].robot, "hall-a");
  EXPECT_EQ(map.sessions[1].robot, "dock.b_2");
  EXPECT_EQ(map.sessions[2].robot, "");
  EXPECT_EQ(mapper.session(2).robot, "dock.b_2");
  EXPECT_EQ(mapper.robot(2), "dock.b_2");
  EXPECT_EQ(mapper.robot(99), "");  // not seen
  EXPECT_EQ(mapper.correction(1, 8).session.robot, "hall-a");
}

TEST(Mapper, ALocalGraphThatDoesNotStartAtItsKeyframeIsRefused) {
  Mapper mapper(loop_closure::Vocabulary::load(CVO_DEFAULT_VOCABULARY), MapperParameters{});
  const RealKeyframe a = real_keyframe(0);
  mapper.add_keyframe({7, 0, a.frame, core::SE3(), a.cloud});
  odometry::LocalGraph graph(2);
  graph.add_node({3, 0.0, core::SE3()});
  graph.add_node({4, 0.1, core::SE3()});
  graph.add_edge({3, 4, core::SE3(), core::Matrix6d::Identity()});
  EXPECT_THROW(mapper.add_local_graph(7, 0, graph), MapperError);                    // keyframe 0 is frame 0
  EXPECT_THROW(mapper.add_local_graph(7, 1, odometry::LocalGraph(1)), MapperError);  // empty
  EXPECT_EQ(mapper.backend().local_graphs(), 0u);
  EXPECT_NO_THROW(mapper.add_local_graph(7, 3, graph));  // keyframe 3 not here yet: the graph is
  EXPECT_EQ(mapper.backend().local_graphs(), 1u);
}

// One session's entry without the map (what CVO_MAP_CORRECTION carries): the same as map()'s, its
// covariance the marginal a factorisation of the keyframe graph gives, and, while local graphs
// only add leaves, no factorisation after the first.
TEST(Mapper, ASessionsEntryIsMapsWithoutAFactorisationPerLocalGraph) {
  MapperParameters parameters;
  parameters.detector.loop.similarity_threshold = 2;  // above any score: no loop, only leaves
  Mapper mapper(loop_closure::Vocabulary::load(CVO_DEFAULT_VOCABULARY), parameters);
  constexpr core::SessionId kSession = 0x5e55;
  constexpr std::int64_t kStride = 4;  // frames between keyframes
  const auto odometry = [](std::int64_t frame) {
    return core::SE3(core::so3_exp({0, 0.01 * static_cast<double>(frame), 0}),
                     Eigen::Vector3d(0.02 * static_cast<double>(frame), 0, 0));
  };
  const auto add_keyframe = [&](std::int64_t id) {
    const RealKeyframe k = real_keyframe(static_cast<std::size_t>(id * kStride));
    mapper.add_keyframe({kSession, id, k.frame, odometry(id * kStride), k.cloud});
  };
  add_keyframe(0);
  for (std::int64_t id = 1; id < 10; ++id) {
    const std::int64_t from = (id - 1) * kStride, to = id * kStride;  // the graph of keyframe id - 1
    odometry::LocalGraph graph(2);
    graph.add_node({static_cast<std::uint64_t>(from), 0.1 * static_cast<double>(from), odometry(from)});
    graph.add_node({static_cast<std::uint64_t>(to), 0.1 * static_cast<double>(to), odometry(to)});
    core::Matrix6d information = 1e4 * core::Matrix6d::Identity();
    information(0, 5) = information(5, 0) = 50.0 * static_cast<double>(id);
    graph.add_edge({static_cast<std::uint64_t>(from), static_cast<std::uint64_t>(to),
                    odometry(from).inverse() * odometry(to), information});
    mapper.add_local_graph(kSession, id - 1, graph);
    add_keyframe(id);

    const MapSession entry = mapper.session(kSession);
    ASSERT_TRUE(entry.keyframe_covariance) << "keyframe " << id;
    EXPECT_EQ(entry.covariance_keyframe, id) << "the newest keyframe's";
    const core::Matrix6d factorised =
        posegraph::marginal_covariances(mapper.backend().keyframe_graph(), {to}, {}).at(to);
    EXPECT_LT((*entry.keyframe_covariance - factorised).norm(), 1e-9 * factorised.norm()) << "keyframe " << id;
  }
  EXPECT_EQ(mapper.loops_accepted(), 0u);
  EXPECT_EQ(mapper.covariance_factorisations(), 1u) << "the first entry's only";
  const Map map = mapper.map();
  const SessionCorrection correction = mapper.correction(kSession, 8);
  EXPECT_EQ(correction.revision, map.revision);
  EXPECT_EQ(correction.session.keyframes, map.sessions.front().keyframes);
  EXPECT_EQ(correction.session.correction.translation(), map.sessions.front().correction.translation());
  EXPECT_EQ(*correction.session.keyframe_covariance, *map.sessions.front().keyframe_covariance);
  EXPECT_TRUE(correction.loops.empty());
  EXPECT_EQ(mapper.covariance_factorisations(), 1u) << "map() too takes the held covariances";
  mapper.finish();  // the global optimisation moves every pose: the next entry factorises again
  EXPECT_TRUE(mapper.session(kSession).keyframe_covariance);
  EXPECT_EQ(mapper.covariance_factorisations(), 2u);
}

}  // namespace
}  // namespace cvo::slam
