// The edge algebra of a merged keyframe (slam/keyframe_merge.hpp) and the Backend's merge.
#include <gtest/gtest.h>

#include "libcvo/posegraph/cost.hpp"
#include "libcvo/posegraph/optimizer.hpp"
#include "libcvo/slam/backend.hpp"
#include "libcvo/slam/keyframe_merge.hpp"

namespace cvo::slam {
namespace {

using core::SE3;
using posegraph::Edge;

SE3 pose(double x, double y, double z, double rx, double ry, double rz) {
  return SE3::exp((core::Vector6d() << x, y, z, rx, ry, rz).finished());
}

core::Matrix6d information(double scale) {
  core::Matrix6d a = core::Matrix6d::Identity() * scale;
  a(0, 1) = a(1, 0) = 0.2 * scale;
  a(3, 5) = a(5, 3) = 0.1 * scale;
  return a;
}

double chi2(const SE3& xi, const SE3& xj, const Edge& e) {
  posegraph::PoseGraph g;
  g.add_node(e.from, xi);
  g.add_node(e.to, xj);
  g.add_edge(e);
  return posegraph::edge_chi2(g, g.edges().front());
}

// With X_k = X_c · T, an edge into k and one out of k cost what their rerouted edges to c cost (to
// first order: the poses are a few millimetres off the measurements).
TEST(KeyframeMerge, ARerouteEdgeCostsWhatTheEdgeToTheMergedKeyframeCost) {
  const SE3 T = pose(0.05, -0.02, 0.01, 0.02, -0.01, 0.03);
  const KeyframeAlias alias{2, 1, T};
  const SE3 xc = pose(0.3, 0.1, -0.2, 0.1, 0.2, -0.1), xk = xc * T, xi = pose(-0.2, 0.4, 0.1, -0.1, 0.05, 0.2);
  const SE3 noise = pose(0.003, -0.002, 0.001, 0.002, 0.001, -0.002);
  const Edge into{3, 2, xi.inverse() * xk * noise, information(50), false};
  const Edge out{2, 3, xk.inverse() * xi * noise, information(50), false};
  const Edge into_c = reroute(into, alias), out_c = reroute(out, alias);
  EXPECT_EQ(into_c.to, 1);
  EXPECT_EQ(out_c.from, 1);
  EXPECT_NEAR(chi2(xi, xc, into_c), chi2(xi, xk, into), 1e-3 * chi2(xi, xk, into));
  EXPECT_NEAR(chi2(xc, xi, out_c), chi2(xk, xi, out), 1e-3 * chi2(xk, xi, out));
}

TEST(KeyframeMerge, AFusedEdgesInformationIsTheSumAndItsMeasurementLiesBetween) {
  const Edge a{1, 2, pose(0.1, 0, 0, 0, 0, 0), information(100), false};
  const Edge b{1, 2, pose(0.2, 0, 0, 0, 0, 0), information(300), false};
  const Edge f = fused(a, b);
  EXPECT_TRUE(f.information.isApprox(a.information + b.information));
  EXPECT_NEAR(f.measurement.translation().x(), 0.175, 1e-6);  // (100·0.1 + 300·0.2) / 400
  // The same measurement given the other way round fuses to the same edge.
  const Edge g = fused(a, reversed(b));
  EXPECT_TRUE(g.information.isApprox(f.information, 1e-9));
  EXPECT_NEAR(g.measurement.translation().x(), 0.175, 1e-6);
}

// Two keyframes' chain, the second merged into the first: it leaves the graph, the edges it had
// become the first's, and its pose is the first's times the merge's relative pose.
TEST(KeyframeMerge, AMergedKeyframeLeavesTheGraphAndKeepsItsPoseThroughTheOneCoveringIt) {
  Backend backend;
  const SE3 p1 = pose(0.1, 0, 0, 0, 0, 0), p2 = pose(0.2, 0, 0, 0, 0, 0);
  odometry::LocalGraph first(2), second(2);
  first.add_node({0, 0.0, SE3()});
  first.add_node({1, 0.1, p1});
  first.add_edge({0, 1, p1, information(100)});
  second.add_node({1, 0.1, p1});
  second.add_node({2, 0.2, p2});
  second.add_edge({1, 2, p1.inverse() * p2, information(100)});
  backend.add_local_graph(0, first);
  ASSERT_TRUE(backend.keyframe_graph().contains(1));
  const SE3 T = pose(0.1, 0, 0, 0, 0, 0);
  backend.merge_keyframe(1, 0, T, information(10));
  EXPECT_FALSE(backend.keyframe_graph().contains(1));
  EXPECT_TRUE(backend.holds(1));
  EXPECT_EQ(backend.resolve(1), 0);
  EXPECT_TRUE(backend.pose_of(1).translation().isApprox(T.translation()));
  EXPECT_TRUE(backend.keyframe_graph().edges().empty());  // 0 -> 1 became 0 -> 0: the alias holds it
  backend.add_local_graph(1, second);                     // starts at the merged keyframe
  ASSERT_EQ(backend.keyframe_graph().edges().size(), 1u);
  EXPECT_EQ(backend.keyframe_graph().edges().front().from, 0);
  EXPECT_NEAR(backend.keyframe_graph().node(2).pose.translation().x(), 0.2, 1e-6);
  EXPECT_THROW(backend.merge_keyframe(0, 2, T, information(10)), std::invalid_argument);  // 0 is the anchor
}

// A settled edge replayed over one that holds part of it adds what it holds beyond: the
// increment, fused into the part, gives the whole; a repeat adds nothing.
TEST(KeyframeMerge, AnIncrementFusedIntoThePartGivesTheWhole) {
  const Edge part{0, 1, pose(0.1, 0, 0, 0, 0, 0.01), information(100)};
  const Edge added{0, 1, pose(0.12, 0.01, 0, 0, 0.01, 0), information(300)};
  const Edge whole = fused(part, added);
  const auto more = increment(part, whole);
  ASSERT_TRUE(more);
  EXPECT_TRUE(more->information.isApprox(added.information, 1e-9));
  const Edge again = fused(part, *more);
  EXPECT_LT((again.measurement.translation() - whole.measurement.translation()).norm(), 1e-9);
  EXPECT_LT(again.measurement.rotation().angularDistance(whole.measurement.rotation()), 1e-9);
  EXPECT_FALSE(increment(whole, whole)) << "a repeat holds nothing more";
}

// Keyframe k merged into b, b merged into a: the chained edge a -> k measures the composed pose, and
// its covariance is the two edges' in series (b's uncertainty carried to k, plus k's own).
TEST(KeyframeMerge, AChainedEdgeComposesThePosesAndAddsTheCovariancesInSeries) {
  const SE3 ab = pose(0.3, 0.1, 0, 0, 0, 0.4), bk = pose(0.2, -0.1, 0.05, 0.1, 0, -0.2);
  const Edge first{1, 2, ab, information(100), false};
  const Edge second{2, 3, bk, information(400), false};
  const Edge e = chained(first, second);
  EXPECT_EQ(e.from, 1);
  EXPECT_EQ(e.to, 3);
  EXPECT_LT((e.measurement.translation() - (ab * bk).translation()).norm(), 1e-12);
  const core::Matrix6d ad = bk.inverse().adjoint();  // b's error seen at k
  const core::Matrix6d series = ad * first.information.inverse() * ad.transpose() + second.information.inverse();
  EXPECT_TRUE(e.information.inverse().isApprox(series, 1e-9));
  EXPECT_THROW((void)chained(second, first), std::invalid_argument) << "3 -> ... does not start at 2";
}

// A chain of keyframes 0.1 m apart whose odometry over-reads each step by 1 cm; keyframe 6 merged
// into keyframe 2 (it sees 2's view from 0.4 m on) and a loop 9 -> 3 later: the incremental
// optimisation of the keyframe graph lands where a batch optimisation of that graph does, however
// often it ran in between (the optimiser must follow the merge: node 6 gone, its edges moved and
// fused, later edges on it).
TEST(KeyframeMerge, TheIncrementalOptimisationAfterAMergeLandsWhereABatchOneDoes) {
  Backend backend;
  const auto step = [&](std::int64_t k) {
    const SE3 odometry = pose(0.11, 0.002, 0, 0, 0, 0.001);
    odometry::LocalGraph g(2);
    g.add_node({static_cast<std::uint64_t>(k), 0.1 * k, pose(0.11 * k, 0, 0, 0, 0, 0)});
    g.add_node({static_cast<std::uint64_t>(k + 1), 0.1 * (k + 1), pose(0.11 * (k + 1), 0, 0, 0, 0, 0)});
    g.add_edge({static_cast<std::uint64_t>(k), static_cast<std::uint64_t>(k + 1), odometry, information(100)});
    backend.add_local_graph(k, g);
  };
  for (std::int64_t k = 0; k < 6; ++k) step(k);
  backend.optimise_keyframes();  // the optimiser holds node 6 and its edge now
  backend.merge_keyframe(6, 2, pose(0.4, 0, 0, 0, 0, 0), information(1e4));
  for (std::int64_t k = 6; k < 10; ++k) step(k);
  loop_closure::LoopClosure loop;
  loop.from = 3;
  loop.to = 9;
  loop.measurement = pose(0.3, 0, 0, 0, 0, 0);  // 9 is 6 + 3 steps, 6 is 2 + 0.4 m
  loop.information = information(1e3);
  ASSERT_TRUE(backend.add_loop(loop));
  backend.optimise_keyframes();
  backend.optimise_keyframes();

  posegraph::PoseGraph batch = backend.keyframe_graph();
  posegraph::OptimizerOptions options;
  options.pose_graph = backend.parameters();
  options.pose_graph.max_iterations = 100;
  posegraph::optimize(batch, options);
  for (const auto& [id, node] : batch.nodes()) {
    const SE3 incremental = backend.keyframe_graph().node(id).pose;
    EXPECT_LT((incremental.translation() - node.pose.translation()).norm(), 1e-3) << "keyframe " << id;
    EXPECT_LT(incremental.rotation().angularDistance(node.pose.rotation()), 1e-3) << "keyframe " << id;
  }
}

}  // namespace
}  // namespace cvo::slam
