// slam::Mapper at its door: a keyframe is (session, id); a repeat is a duplicate, a repeat with
// other content or out of order is refused with a message, and the mapper goes on.
#include "libcvo/slam/mapper.hpp"

#include <string>

#include <gtest/gtest.h>

#include "libcvo/io/tum_dataset.hpp"
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

}  // namespace
}  // namespace cvo::slam
