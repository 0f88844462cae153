// slam::Mapper localizing sessions in a read-only map: the first half of the embedded fr1/rpy
// sample is the map (keyframes at their ground-truth poses), the second half a visitor whose
// odometry frame is far from the map's; the visitor is localized by verified loops, its correction
// is the offset between the frames, the map does not change, and the visitor's window stays
// bounded. An unrelated rendered scene is never localized.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/core/trajectory.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/registration/point_selection.hpp"
#include "libcvo/sim/sequence.hpp"
#include "libcvo/slam/mapper.hpp"
#include "tests/slam/truth_keyframes.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::slam {
namespace {

using core::LocalizationState;

using Keyframe = testing::TruthKeyframe;
using testing::keyframes_of;

std::vector<Keyframe> sample_keyframes(std::size_t first, std::size_t last) {
  return keyframes_of(CVO_TEST_DATA_DIR "/fr1_rpy_50", first, last);
}

// The keyframe→next-keyframe local graph a tracker would close, exact: its information far above
// any registration's (σ 0.1 mm), so that the map's loops do not bend the ground truth.
odometry::LocalGraph graph_between(const Keyframe& a, const Keyframe& b, const core::SE3& odom_T_world) {
  return testing::graph_between(a, b, odom_T_world, 1e8);
}

// A session: its keyframes in order (ids from 0), each with the graph of the one before.
void feed(Mapper& mapper, core::SessionId session, const std::vector<Keyframe>& keyframes,
          const core::SE3& odom_T_world, std::vector<LocalizationState>* states = nullptr) {
  for (std::size_t i = 0; i < keyframes.size(); ++i) {
    if (i > 0)
      mapper.add_local_graph(session, static_cast<std::int64_t>(i - 1),
                             graph_between(keyframes[i - 1], keyframes[i], odom_T_world));
    const Keyframe& k = keyframes[i];
    mapper.add_keyframe({session, static_cast<std::int64_t>(i), k.frame, odom_T_world * k.truth, k.cloud,
                         "robot-" + std::to_string(session)});
    if (states) states->push_back(mapper.session(session).state);
  }
}

Mapper stored_map(const std::vector<Keyframe>& keyframes, MapperParameters parameters = {}) {
  Mapper mapper(loop_closure::Vocabulary::load(CVO_DEFAULT_VOCABULARY), parameters);
  feed(mapper, 0x3a9, keyframes, core::SE3());
  mapper.finish();
  mapper.localize_only();
  return mapper;
}

const core::SE3 kFarAway(Eigen::Quaterniond(Eigen::AngleAxisd(2.0, Eigen::Vector3d::UnitZ())),
                         Eigen::Vector3d(4.0, -3.0, 0.5));

TEST(Localization, AVisitorIsLocalizedAndItsCorrectionIsTheOffsetBetweenTheFrames) {
  Mapper mapper = stored_map(sample_keyframes(0, 24));
  const Map before = mapper.map();
  std::vector<LocalizationState> states;
  feed(mapper, 0x715, sample_keyframes(26, 49), kFarAway, &states);

  EXPECT_EQ(states.front(), LocalizationState::kLocalizing);  // a first keyframe has no η normaliser
  ASSERT_EQ(states.back(), LocalizationState::kLocalized);
  const MapSession visitor = mapper.session(0x715);
  EXPECT_TRUE(visitor.placed);
  EXPECT_TRUE(visitor.visitor);
  EXPECT_EQ(visitor.robot, "robot-" + std::to_string(0x715));  // a visitor is named too
  EXPECT_GE(visitor.since_match_s, 0.0);
  // T_map_odom is the inverse of the offset the visitor's odometry has from the map's frame.
  const core::SE3 error = visitor.correction * kFarAway;
  EXPECT_LT(error.translation().norm(), 0.05);
  EXPECT_LT(error.log().tail<3>().norm(), 2.0 * M_PI / 180.0);

  // The map is read only: its keyframes and poses are what they were; the visitor is listed.
  const Map after = mapper.map();
  ASSERT_EQ(after.keyframes.size(), before.keyframes.size());
  for (std::size_t i = 0; i < after.keyframes.size(); ++i)
    EXPECT_EQ(after.keyframes[i].pose.translation(), before.keyframes[i].pose.translation());
  EXPECT_EQ(after.sessions.size(), before.sessions.size() + 1);
  EXPECT_EQ(after.loops.size(), before.loops.size());
}

TEST(Localization, AVisitorsWindowIsBoundedAndLeavesTheDetectorAsItMovesOn) {
  MapperParameters parameters;
  parameters.localization.window_keyframes = 3;
  Mapper mapper = stored_map(sample_keyframes(0, 24), parameters);
  const std::size_t map_nodes = mapper.backend().keyframe_graph().nodes().size();
  feed(mapper, 0x715, sample_keyframes(26, 49), kFarAway);
  EXPECT_EQ(mapper.window_keyframes(), 3u);
  EXPECT_EQ(mapper.session(0x715).keyframes, 3u);
  EXPECT_EQ(mapper.backend().keyframe_graph().nodes().size(), map_nodes);  // the map's keyframes only

  mapper.mark_lost(0x715);
  EXPECT_EQ(mapper.session(0x715).state, LocalizationState::kLost);
  EXPECT_EQ(mapper.window_keyframes(), 0u);
}

TEST(Localization, TheStoredSessionsCannotGrowTheReadOnlyMap) {
  const auto keyframes = sample_keyframes(0, 30);
  Mapper mapper = stored_map({keyframes.begin(), keyframes.end() - 1});
  const Keyframe& last = keyframes.back();
  EXPECT_THROW(mapper.add_keyframe({0x3a9, 10, last.frame, last.truth, last.cloud}), MapperError);
  // The same keyframe again is a duplicate, as before.
  const Keyframe& first = keyframes.front();
  EXPECT_TRUE(mapper.add_keyframe({0x3a9, 0, first.frame, first.truth, first.cloud}).duplicate);
}

TEST(Localization, AnUnrelatedSceneIsNeverLocalized) {
  Mapper mapper = stored_map(sample_keyframes(0, 24));
  const cvo::test::TempDir dir;
  sim::SequenceOptions options;  // the textured room, orbiting
  options.frames = 36;
  options.rate_hz = 10.0;
  options.noise.enabled = true;
  options.render.supersample = false;
  options.intrinsics = {262.5, 262.5, 159.25, 119.25, 320, 240, 5000.0};
  sim::write_sequence(dir.path() / "room", options);
  std::vector<LocalizationState> states;
  feed(mapper, 0x0dd, keyframes_of(dir.path() / "room", 0, 35), core::SE3(), &states);
  for (const auto state : states) EXPECT_EQ(state, LocalizationState::kLocalizing);
}

}  // namespace
}  // namespace cvo::slam
