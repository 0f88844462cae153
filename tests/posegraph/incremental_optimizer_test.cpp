// The incremental optimiser against the batch one: fed node by node, it ends at the batch
// optimum; a loop between recent nodes changes few factor columns; fixed nodes stay put.
#include "libcvo/posegraph/incremental_optimizer.hpp"

#include <cstdio>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "libcvo/posegraph/arrivals.hpp"
#include "libcvo/posegraph/cost.hpp"
#include "libcvo/posegraph/g2o_io.hpp"
#include "libcvo/posegraph/optimizer.hpp"
#include "libcvo/sim/patrol_graph.hpp"

namespace cvo::posegraph {
namespace {

// Node after node with its edges, an update() after every `stride` nodes; then updates without
// new edges until the step is negligible (robust edges converge linearly, as IRLS does: many
// updates).
void feed(IncrementalOptimizer& optimizer, const PoseGraph& graph, std::size_t stride = 1,
          std::size_t* final_updates = nullptr) {
  std::size_t arrived = 0;
  for (const Arrival& arrival : arrivals(graph)) {
    add_arrival(optimizer, arrival, graph.node(arrival.node).pose);
    if (++arrived % stride == 0) optimizer.update();
  }
  std::size_t updates = 0;
  for (; updates < 200; ++updates)
    if (optimizer.update().max_step < 1e-7) break;
  if (final_updates != nullptr) *final_updates = updates;
}

// At most this many updates while a graph is fed: an update after every node on the patrol and
// the grids, every few nodes on the three large shared graphs (their odometry guess is far off, so
// many of their updates are rebuilds: a test of minutes otherwise).
constexpr std::size_t kMaxFeedUpdates = 300;

// The batch optimum itself: LM's own stop (1e-6 decrease) is a little short of it.
OptimizationReport batch_optimum(PoseGraph& graph) {
  OptimizerOptions converged;
  converged.relative_decrease = 1e-12;
  converged.pose_graph.max_iterations = 1000;
  return optimize(graph, converged);
}

// Where the incremental optimiser ends is the batch optimum: batch LM started there finds nothing
// lower (within 1e-6), and it is no worse than batch LM's from the odometry guess. (That one may
// stop in a worse local minimum: torus3D's guess leads LM to about twice the cost the incremental
// optimiser, whose guesses are corrected loop by loop, finds; that is the torus' known optimum.)
void expect_batch_optimum(const PoseGraph& graph, const std::string& name, const IncrementalOptions& options = {}) {
  IncrementalOptimizer incremental(options);
  std::size_t final_updates = 0;
  const std::size_t stride = (graph.nodes().size() + kMaxFeedUpdates - 1) / kMaxFeedUpdates;
  feed(incremental, graph, stride, &final_updates);
  const double incremental_cost = incremental.cost();
  PoseGraph from_guess = graph, from_incremental = graph;
  for (const auto& [id, node] : graph.nodes()) from_incremental.set_pose(id, incremental.pose(id));
  const auto guess = batch_optimum(from_guess);
  const auto polished = batch_optimum(from_incremental);
  ASSERT_TRUE(guess.converged) << guess.stop_reason;
  ASSERT_TRUE(polished.converged) << polished.stop_reason;
  std::printf(
      "%s: incremental cost %.9g; batch from it %.9g, from the odometry guess %.9g (an update every %zu "
      "nodes, %d rebuilds, %zu final updates)\n",
      name.c_str(), incremental_cost, polished.final_cost, guess.final_cost, stride, incremental.rebuilds(),
      final_updates);
  EXPECT_NEAR(incremental_cost, polished.final_cost, 1e-6 * polished.final_cost) << name;
  EXPECT_LE(incremental_cost, guess.final_cost * (1 + 1e-6)) << name;
}

TEST(IncrementalOptimizer, ReachesTheBatchOptimumOnAPatrolFedNodeByNode) {
  const sim::PatrolGraph patrol = sim::patrol_graph();
  ASSERT_GT(patrol.loops, 10u);
  expect_batch_optimum(patrol.graph, "patrol");
}

// With rebuilds for large corrections off, every update but a few (capacity, fill) goes through
// the rank updates alone: they must give the same optimum.
TEST(IncrementalOptimizer, ReachesTheBatchOptimumThroughRankUpdatesAlone) {
  IncrementalOptions updates_only;
  updates_only.rebuild_fraction = 2.0;
  updates_only.rebuild_when_cheaper = false;
  sim::PatrolOptions shorter;  // the final updates relinearise every node by rank updates: slow on long patrols
  shorter.route_poses = 50;
  const sim::PatrolGraph patrol = sim::patrol_graph(shorter);
  expect_batch_optimum(patrol.graph, "patrol, rank updates only", updates_only);
}

class SharedPoseGraphFed : public ::testing::TestWithParam<const char*> {};

TEST_P(SharedPoseGraphFed, ReachesTheBatchOptimumFedNodeByNode) {
  const auto file = std::filesystem::path(CVO_SHARED_DATA_DIR) / "posegraph" / (std::string(GetParam()) + ".g2o");
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "shared data absent: " << file;
  expect_batch_optimum(read_g2o(file), GetParam());
}

INSTANTIATE_TEST_SUITE_P(Shared, SharedPoseGraphFed,
                         ::testing::Values("tinyGrid3D", "smallGrid3D", "parking-garage", "sphere2500", "torus3D"));

TEST(IncrementalOptimizer, ALoopAtTheEndOfALongCorridorTouchesFewFactorColumns) {
  sim::PatrolOptions corridor;
  corridor.route_poses = 2000;
  corridor.laps = 1;
  const sim::PatrolGraph patrol = sim::patrol_graph(corridor);
  IncrementalOptimizer optimizer;
  feed(optimizer, patrol.graph);
  const NodeId last = static_cast<NodeId>(corridor.route_poses) - 1;
  optimizer.add_edge({last - 5, last, patrol.truth[last - 5].inverse() * patrol.truth[last],
                      core::Matrix6d::Identity() * 100.0, true});
  const UpdateReport report = optimizer.update();
  EXPECT_FALSE(report.rebuilt);
  EXPECT_EQ(report.new_edges, 1u);
  std::printf("loop over the last 6 of %zu nodes: %zu of %zu factor columns touched\n", corridor.route_poses,
              report.touched_columns, optimizer.factor_columns());
  EXPECT_GT(report.touched_columns, 0u);
  EXPECT_LT(report.touched_columns, 6u * 100u);  // of 6 x 2000 variables
}

TEST(IncrementalOptimizer, HoldsFixedNodesWhereTheyAre) {
  sim::PatrolOptions small;
  small.route_poses = 40;
  PoseGraph graph = sim::patrol_graph(small).graph;
  graph.set_fixed(0, true);
  graph.set_fixed(60, true);
  IncrementalOptimizer optimizer;
  feed(optimizer, graph);
  EXPECT_TRUE(optimizer.fixed(60));
  const core::SE3 held = optimizer.pose(60);
  // Node 60 was placed by dead reckoning when it arrived and has not moved since.
  EXPECT_LT((optimizer.pose(0).translation() - graph.node(0).pose.translation()).norm(), 1e-12);
  for (int k = 0; k < 5; ++k) optimizer.update();
  EXPECT_LT((optimizer.pose(60).translation() - held.translation()).norm(), 1e-12);
  PoseGraph batch = optimizer.graph();  // the same fixed poses
  const auto report = optimize(batch);
  EXPECT_NEAR(optimizer.cost(), report.final_cost, 1e-6 * report.final_cost);
}

TEST(IncrementalOptimizer, RefusesWhatAPoseGraphRefuses) {
  IncrementalOptimizer optimizer;
  optimizer.add_node(1, {});
  EXPECT_THROW(optimizer.add_node(1, {}), std::invalid_argument);
  EXPECT_THROW(optimizer.add_edge({1, 2, {}, core::Matrix6d::Identity(), false}), std::invalid_argument);
}

}  // namespace
}  // namespace cvo::posegraph
