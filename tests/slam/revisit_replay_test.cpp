// A merged keyframe replayed from its merge alone (Mapper::apply_merge, what a compacted store
// holds): the map is the one the keyframe's images gave. Keyframes of the embedded sample at their
// ground-truth poses, visited twice, the second visit in an odometry frame of its own.
#include <map>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/core/trajectory.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/registration/point_selection.hpp"
#include "libcvo/slam/mapper.hpp"
#include "tests/slam/truth_keyframes.hpp"

namespace cvo::slam {
namespace {

using Keyframe = testing::TruthKeyframe;

// Every third frame of the sample with its ground-truth pose.
std::vector<Keyframe> sample_keyframes() { return testing::keyframes_of(CVO_TEST_DATA_DIR "/fr1_rpy_50", 0, 49); }

odometry::LocalGraph graph_between(const Keyframe& a, const Keyframe& b, const core::SE3& odom_T_world) {
  return testing::graph_between(a, b, odom_T_world, 1e6);
}

std::map<std::int64_t, KeyframeMerge> feed(Mapper& mapper, core::SessionId session, const std::vector<Keyframe>& ks,
                                           const core::SE3& odom_T_world,
                                           const std::map<std::int64_t, KeyframeMerge>& replayed = {}) {
  std::map<std::int64_t, KeyframeMerge> merges;
  for (std::size_t i = 0; i < ks.size(); ++i) {
    const auto id = static_cast<std::int64_t>(i);
    if (i > 0) mapper.add_local_graph(session, id - 1, graph_between(ks[i - 1], ks[i], odom_T_world));
    if (const auto m = replayed.find(id); m != replayed.end()) {
      EXPECT_TRUE(mapper.apply_merge(m->second));
      continue;
    }
    const auto outcome = mapper.add_keyframe({session, id, ks[i].frame, odom_T_world * ks[i].truth, ks[i].cloud});
    if (outcome.merge) merges.emplace(id, *outcome.merge);
  }
  return merges;
}

TEST(RevisitReplay, AMergeReplaysWithoutTheKeyframesImagesToTheSameMap) {
  const auto keyframes = sample_keyframes();
  const core::SE3 away(Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ())),
                       Eigen::Vector3d(1.0, -0.5, 0.2));
  const auto vocabulary = [] { return loop_closure::Vocabulary::load(CVO_DEFAULT_VOCABULARY); };
  Mapper live(vocabulary(), {});
  feed(live, 1, keyframes, core::SE3());
  const auto merges = feed(live, 2, keyframes, away);
  ASSERT_FALSE(merges.empty()) << "the second visit merged nothing";

  Mapper replayed(vocabulary(), {});
  feed(replayed, 1, keyframes, core::SE3());
  feed(replayed, 2, keyframes, away, merges);
  EXPECT_FALSE(replayed.apply_merge(merges.begin()->second));  // applied already: nothing
  EXPECT_EQ(replayed.merged_keyframes(), live.merged_keyframes());

  const Map a = live.map(), b = replayed.map();
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  EXPECT_EQ(a.keyframes.size(), 2 * keyframes.size() - live.merged_keyframes());  // the map leaves merged ones out
  for (std::size_t i = 0; i < a.keyframes.size(); ++i) {
    EXPECT_EQ(a.keyframes[i].id, b.keyframes[i].id);
    EXPECT_LT((a.keyframes[i].pose.translation() - b.keyframes[i].pose.translation()).norm(), 1e-9);
  }
  EXPECT_LT((live.session(2).correction.translation() - replayed.session(2).correction.translation()).norm(), 1e-9);
}

}  // namespace
}  // namespace cvo::slam
