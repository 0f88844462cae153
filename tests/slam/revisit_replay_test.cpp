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
                  const core::SE3& odom_T_world, const MergesByStep& replayed = {}, bool settle = false) {
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
    if (settle) mapper.settle();
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

// A map revisited again and again, settled after every step as a service does (Mapper::settle):
// the frames, records and loops it holds stop growing after the first revisit, and its map is the
// one the unsettled mapper has (the settled edges hold what the forgotten graphs and loops added).
TEST(RevisitSettle, ASettledMapHoldsWhatTheAreaNeedsAndStaysTheMapItWas) {
  const auto keyframes = sample_keyframes();
  const auto vocabulary = [] { return loop_closure::Vocabulary::load(CVO_DEFAULT_VOCABULARY); };
  Mapper kept(vocabulary(), {}), settled(vocabulary(), {});
  std::vector<std::size_t> graphs_held;
  for (core::SessionId visit = 1; visit <= 4; ++visit) {
    const core::SE3 odom_T_world(Eigen::Quaterniond(Eigen::AngleAxisd(0.2 * visit, Eigen::Vector3d::UnitZ())),
                                 Eigen::Vector3d(0.3 * visit, 0, 0));
    feed(kept, visit, keyframes, odom_T_world);
    feed(settled, visit, keyframes, odom_T_world, {}, true);
    graphs_held.push_back(settled.backend().local_graphs());
  }
  ASSERT_GT(kept.merged_keyframes(), 2 * keyframes.size()) << "the revisits were not merged";
  EXPECT_GT(settled.forgotten_keyframes(), kept.merged_keyframes() / 2);
  std::printf("local graphs held after each visit: %zu %zu %zu %zu (unsettled: %zu); keyframes forgotten %zu\n",
              graphs_held[0], graphs_held[1], graphs_held[2], graphs_held[3], kept.backend().local_graphs(),
              settled.forgotten_keyframes());
  // Each revisit leaves a few graphs (its entry into the mapped area, its newest two, its last).
  EXPECT_LE(graphs_held[3] - graphs_held[1], 2 * (graphs_held[1] - graphs_held[0]));
  EXPECT_LT(graphs_held[3], kept.backend().local_graphs() / 2);
  EXPECT_LE(settled.backend().merged_keyframes(), kept.merged_keyframes() / 2);

  const auto same_maps = [&](double metres) {
    const Map a = kept.map(), b = settled.map();
    ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
    for (std::size_t i = 0; i < a.keyframes.size(); ++i) {
      EXPECT_EQ(a.keyframes[i].id, b.keyframes[i].id);
      EXPECT_LT((a.keyframes[i].pose.translation() - b.keyframes[i].pose.translation()).norm(), metres);
    }
    for (core::SessionId visit = 1; visit <= 4; ++visit) {
      EXPECT_EQ(kept.session(visit).keyframes, settled.session(visit).keyframes) << "it counts those it forgot";
      EXPECT_LT((kept.session(visit).correction.translation() - settled.session(visit).correction.translation()).norm(),
                metres)
          << "visit " << visit;
    }
  };
  same_maps(1e-6);  // the keyframe graph is not touched by settling
  // The global optimisation: the unsettled one relaxes each merged keyframe from the one covering
  // it (a robust edge), the settled one holds forgotten ones rigidly, as the keyframe graph does
  // (the first visit's keyframes lie at their ground-truth poses; the loops' own error is what
  // moves them). That relaxation is what settling gives up: within twice the unsettled error.
  kept.finish();
  settled.finish();
  const core::SE3 odom_T_world(Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ())),
                               Eigen::Vector3d(0.3, 0, 0));
  const auto worst_error = [&](const Mapper& mapper) {
    double worst = 0;
    for (const auto& k : mapper.map().keyframes)
      if (k.session == 1)
        worst = std::max(worst, (k.pose.translation() -
                                 (odom_T_world * keyframes[static_cast<std::size_t>(k.id)].truth).translation())
                                    .norm());
    return worst;
  };
  std::printf(
      "first visit's keyframes from the truth after the global optimisation: %.4f m unsettled, %.4f m settled\n",
      worst_error(kept), worst_error(settled));
  EXPECT_LT(worst_error(settled), std::max(0.01, 2 * worst_error(kept)));
}

}  // namespace
}  // namespace cvo::slam
