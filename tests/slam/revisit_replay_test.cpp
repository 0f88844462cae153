// A merged keyframe replayed from its merge alone (Mapper::apply_merge, what a compacted store
// holds): the map is the one the keyframe's images gave. Keyframes of the embedded sample at their
// ground-truth poses, visited twice, the second visit in an odometry frame of its own.
#include <map>
#include <set>
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

// The merges each step made, by step: a store holds them after that step's records.
using MergesByStep = std::map<std::int64_t, std::vector<KeyframeMerge>>;

// One visit, step by step. Replaying `replayed`, a keyframe merged is applied from its merge alone
// (its images dropped, as a compacted store has them), at the step whose records its merge followed.
MergesByStep feed(Mapper& mapper, core::SessionId session, const std::vector<Keyframe>& ks,
                  const core::SE3& odom_T_world, const MergesByStep& replayed = {}) {
  MergesByStep merges;
  std::set<std::int64_t> dropped;
  for (const auto& [step, made] : replayed)
    for (const auto& m : made) dropped.insert(m.id);
  for (std::size_t i = 0; i < ks.size(); ++i) {
    const auto id = static_cast<std::int64_t>(i);
    if (i > 0) mapper.add_local_graph(session, id - 1, graph_between(ks[i - 1], ks[i], odom_T_world));
    if (!dropped.contains(id)) {
      auto outcome = mapper.add_keyframe({session, id, ks[i].frame, odom_T_world * ks[i].truth, ks[i].cloud});
      if (!outcome.merges.empty()) merges.emplace(id, std::move(outcome.merges));
    }
    if (const auto step = replayed.find(id); step != replayed.end()) {
      for (const auto& m : step->second) EXPECT_TRUE(mapper.apply_merge(m)) << "keyframe " << m.id;
    }
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
  EXPECT_FALSE(replayed.apply_merge(merges.begin()->second.front()));  // applied already: nothing
  EXPECT_EQ(replayed.merged_keyframes(), live.merged_keyframes());

  // The same graph (the merges hold every constraint), built in other steps and so optimised from
  // other points: after the final optimisation, the same optimum (to its convergence: 0.1 mm).
  live.finish();
  replayed.finish();
  const Map a = live.map(), b = replayed.map();
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  EXPECT_EQ(a.keyframes.size(), 2 * keyframes.size() - live.merged_keyframes());  // the map leaves merged ones out
  for (std::size_t i = 0; i < a.keyframes.size(); ++i) {
    EXPECT_EQ(a.keyframes[i].id, b.keyframes[i].id);
    EXPECT_LT((a.keyframes[i].pose.translation() - b.keyframes[i].pose.translation()).norm(), 1e-4);
  }
  EXPECT_LT((live.session(2).correction.translation() - replayed.session(2).correction.translation()).norm(), 1e-4);
}

}  // namespace
}  // namespace cvo::slam
