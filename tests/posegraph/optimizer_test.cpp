#include "libcvo/posegraph/optimizer.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include <gtest/gtest.h>

#include "libcvo/posegraph/cost.hpp"

namespace cvo::posegraph {
namespace {

using core::Matrix6d;
using core::SE3;
using core::Vector6d;

SE3 pose(double x, double y, double z, double rx, double ry, double rz) {
  return SE3::exp((Vector6d() << x, y, z, rx, ry, rz).finished());
}

Edge edge_between(const SE3& Ti, const SE3& Tj, NodeId i, NodeId j) {
  Edge e;
  e.from = i;
  e.to = j;
  e.measurement = Ti.inverse() * Tj;
  return e;
}

double pose_error(const SE3& a, const SE3& b) { return (a.inverse() * b).log().norm(); }

TEST(Optimizer, ChainWithConsistentEdgesConvergesToTheTruth) {
  const std::vector<SE3> truth = {pose(0, 0, 0, 0, 0, 0), pose(1, 0.2, 0, 0.1, 0.3, 0.5),
                                  pose(2, 1, -0.5, 0.4, -0.2, 1.2), pose(2.5, 2, 0.3, -0.6, 0.1, 2.0)};
  PoseGraph graph;
  for (std::size_t k = 0; k < truth.size(); ++k)
    graph.add_node(static_cast<NodeId>(k), truth[k] * pose(0.3, -0.2, 0.1, 0.2, -0.3, 0.25 * k), k == 0);
  graph.set_pose(0, truth[0]);
  for (NodeId k = 0; k + 1 < 4; ++k) graph.add_edge(edge_between(truth[k], truth[k + 1], k, k + 1));
  graph.add_edge(edge_between(truth[0], truth[3], 0, 3));

  const auto report = optimize(graph);
  EXPECT_TRUE(report.converged) << report.stop_reason;
  EXPECT_GT(report.initial_cost, 0.1);
  EXPECT_LT(report.final_cost, 1e-16);
  EXPECT_EQ(static_cast<int>(report.log.size()), report.iterations);
  for (NodeId k = 0; k < 4; ++k) EXPECT_LT(pose_error(graph.node(k).pose, truth[k]), 1e-9) << k;
}

// Translation along x only, rotations identity: log is then the plain difference, so the optimum
// is an ordinary weighted least-squares problem solved by hand.
TEST(Optimizer, InconsistentLoopGivesTheWeightedAverage) {
  PoseGraph graph;
  graph.add_node(0, SE3(), /*fixed=*/true);
  graph.add_node(1, SE3::from_translation({0.5, 0, 0}));
  graph.add_node(2, SE3::from_translation({3, 0, 0}));
  const auto along_x = [](NodeId i, NodeId j, double x, double w) {
    Edge e;
    e.from = i;
    e.to = j;
    e.measurement = SE3::from_translation({x, 0, 0});
    e.information = w * Matrix6d::Identity();
    return e;
  };
  // Equal weights: min (x1 - 1)^2 + (x2 - x1 - 1)^2 + (x2 - 2.5)^2 -> x1 = 3.5/3, x2 = 7/3.
  graph.add_edge(along_x(0, 1, 1.0, 1.0));
  graph.add_edge(along_x(1, 2, 1.0, 1.0));
  graph.add_edge(along_x(0, 2, 2.5, 1.0));
  auto report = optimize(graph);
  EXPECT_TRUE(report.converged) << report.stop_reason;
  EXPECT_NEAR(graph.node(1).pose.translation().x(), 3.5 / 3.0, 1e-9);
  EXPECT_NEAR(graph.node(2).pose.translation().x(), 7.0 / 3.0, 1e-9);
  EXPECT_NEAR(graph.node(1).pose.translation().norm(), std::abs(graph.node(1).pose.translation().x()), 1e-12);
  // cost = 1/2 * 3 * (0.5/3)^2
  EXPECT_NEAR(report.final_cost, 0.5 * 3.0 * std::pow(0.5 / 3.0, 2), 1e-12);

  // A second, heavier measurement of 0 -> 1 (1.3, weight 2) moves the optimum:
  graph.add_edge(along_x(0, 1, 1.3, 2.0));
  // Normal equations: x1: (x1-1) - (x2-x1-1) + 2 (x1-1.3) = 0 -> 4 x1 - x2 = 2.6
  //                   x2: (x2-x1-1) + (x2-2.5) = 0            -> -x1 + 2 x2 = 3.5
  //   x1 = (2 * 2.6 + 3.5) / 7, x2 = (3.5 + x1) / 2.
  report = optimize(graph);
  const double x1 = (2 * 2.6 + 3.5) / 7.0;
  EXPECT_NEAR(graph.node(1).pose.translation().x(), x1, 1e-9);
  EXPECT_NEAR(graph.node(2).pose.translation().x(), (3.5 + x1) / 2.0, 1e-9);
}

TEST(Optimizer, CauchyKernelDownWeightsAWrongLoopEdge) {
  const std::vector<SE3> truth = {pose(0, 0, 0, 0, 0, 0), pose(1, 0, 0, 0, 0, 0.5), pose(1, 1, 0, 0, 0.1, 1.6),
                                  pose(0, 1, 0, 0.1, 0, 3.0)};
  // Measurements good to ~0.1 (information 100): the wrong edge's chi^2 is then in the
  // thousands, where the Cauchy weight 1 / (1 + chi^2 / 4) all but removes it.
  const Matrix6d information = 100.0 * Matrix6d::Identity();
  const auto build = [&](bool robust) {
    PoseGraph graph;
    for (std::size_t k = 0; k < truth.size(); ++k)
      graph.add_node(static_cast<NodeId>(k), truth[k] * pose(0.05, -0.05, 0.02, 0.02, 0.01, -0.03), k == 0);
    graph.set_pose(0, truth[0]);
    for (NodeId i = 0; i < 4; ++i)  // the square and its diagonals, all consistent
      for (NodeId j = i + 1; j < 4; ++j) {
        Edge e = edge_between(truth[i], truth[j], i, j);
        e.information = information;
        e.robust = robust;
        graph.add_edge(e);
      }
    Edge wrong = edge_between(truth[1], truth[3] * pose(2.0, -1.5, 0.5, 0.4, -0.3, 0.8), 1, 3);
    wrong.information = information;
    wrong.robust = robust;
    graph.add_edge(wrong);
    return graph;
  };
  const auto worst_error = [&](const PoseGraph& graph) {
    double worst = 0;
    for (NodeId k = 0; k < 4; ++k) worst = std::max(worst, pose_error(graph.node(k).pose, truth[k]));
    return worst;
  };
  PoseGraph plain = build(false);
  PoseGraph robust = build(true);
  const auto plain_report = optimize(plain);
  const auto robust_report = optimize(robust);
  EXPECT_TRUE(plain_report.converged) << plain_report.stop_reason;
  EXPECT_TRUE(robust_report.converged) << robust_report.stop_reason;
  EXPECT_GT(worst_error(plain), 0.3) << worst_error(plain);
  EXPECT_LT(worst_error(robust), 0.05 * worst_error(plain)) << worst_error(robust) << " vs " << worst_error(plain);
  EXPECT_NEAR(robust_report.final_cost, cost(robust, RobustKernel{2.0}), 1e-12);
}

TEST(Optimizer, FixedNodesStayAndTheGaugeHoldsTheFirstNode) {
  const std::vector<SE3> truth = {pose(0, 0, 0, 0, 0, 0), pose(1, 0, 0, 0, 0, 0.3), pose(2, 0.5, 0, 0, 0.2, 0.6)};
  for (const bool fix_middle : {false, true}) {
    PoseGraph graph;
    for (std::size_t k = 0; k < truth.size(); ++k)
      graph.add_node(static_cast<NodeId>(k), truth[k] * pose(0.1, 0.1, 0.1, 0.1, 0.1, 0.1));
    if (fix_middle) graph.set_fixed(1, true);
    graph.add_edge(edge_between(truth[0], truth[1], 0, 1));
    graph.add_edge(edge_between(truth[1], truth[2], 1, 2));
    const PoseGraph before = graph;
    optimize(graph);
    const NodeId held = fix_middle ? 1 : 0;
    EXPECT_EQ(graph.node(held).pose.translation(), before.node(held).pose.translation());
    EXPECT_EQ(graph.node(held).pose.rotation().coeffs(), before.node(held).pose.rotation().coeffs());
    // Relative poses are right whichever node holds the gauge.
    EXPECT_LT(pose_error(graph.node(0).pose.inverse() * graph.node(2).pose, truth[0].inverse() * truth[2]), 1e-9);
  }
}

TEST(Optimizer, AllFixedIsANoOp) {
  PoseGraph graph;
  graph.add_node(0, SE3(), true);
  graph.add_node(1, pose(1, 0, 0, 0, 0, 0), true);
  graph.add_edge(edge_between(SE3(), pose(2, 0, 0, 0, 0, 0), 0, 1));
  const auto report = optimize(graph);
  EXPECT_EQ(report.iterations, 0);
  EXPECT_NEAR(report.final_cost, 0.5, 1e-12);
}

TEST(Optimizer, IncrementalGrowthReanalysesOnlyWhenTheStructureChanges) {
  std::vector<SE3> truth;
  for (int k = 0; k < 6; ++k) truth.push_back(pose(k, 0.1 * k * k, 0, 0.05 * k, 0, 0.4 * k));
  PoseGraph graph;
  for (NodeId k = 0; k < 4; ++k) graph.add_node(k, truth[k] * pose(0.1, 0, -0.1, 0, 0.05, 0.1));
  for (NodeId k = 0; k + 1 < 4; ++k) graph.add_edge(edge_between(truth[k], truth[k + 1], k, k + 1));

  Optimizer optimizer;
  auto report = optimizer.optimize(graph);
  EXPECT_TRUE(report.reanalysed);
  EXPECT_EQ(optimizer.symbolic_analyses(), 1);

  graph.add_edge(edge_between(truth[1], truth[2], 1, 2));  // a second edge on an existing block
  report = optimizer.optimize(graph);
  EXPECT_FALSE(report.reanalysed);
  EXPECT_EQ(optimizer.symbolic_analyses(), 1);

  graph.add_node(4, truth[3] * pose(1, 0, 0, 0, 0, 0));  // poor initial guess
  graph.add_node(5, truth[3]);
  graph.add_edge(edge_between(truth[3], truth[4], 3, 4));
  graph.add_edge(edge_between(truth[4], truth[5], 4, 5));
  graph.add_edge(edge_between(truth[0], truth[5], 0, 5));  // loop closure
  report = optimizer.optimize(graph);
  EXPECT_TRUE(report.reanalysed);
  EXPECT_EQ(optimizer.symbolic_analyses(), 2);
  EXPECT_TRUE(report.converged) << report.stop_reason;
  EXPECT_LT(report.final_cost, 1e-16);
  const SE3 gauge = graph.node(0).pose * truth[0].inverse();  // node 0 held where it started
  for (NodeId k = 0; k < 6; ++k) EXPECT_LT(pose_error(graph.node(k).pose, gauge * truth[k]), 1e-8) << k;

  Optimizer moved = std::move(optimizer);  // the CHOLMOD state moves with it
  report = moved.optimize(graph);
  EXPECT_FALSE(report.reanalysed);
}

// A side x side x side lattice of poses, edges to the next node along each axis, noisy
// measurements (the minimum has a non-zero cost, so the last iterations converge linearly, where
// PCG takes over) and an initial guess well off.
PoseGraph noisy_lattice(int side) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto noise = [&](double size) {
    return pose(size * unit(random), size * unit(random), size * unit(random), size * unit(random), size * unit(random),
                size * unit(random));
  };
  std::vector<SE3> truth;
  PoseGraph graph;
  for (int k = 0; k < side * side * side; ++k) {
    const int x = k % side, y = (k / side) % side, z = k / (side * side);
    truth.push_back(pose(x, y, z, 0.1 * x, 0.2 * y, 0.3 * z));
    graph.add_node(k, truth.back() * noise(0.3));
  }
  for (int k = 0; k < side * side * side; ++k)
    for (const int step : {1, side, side * side}) {
      const int j = k + step;
      const bool along = (step == 1 && k % side + 1 < side) || (step == side && (k / side) % side + 1 < side) ||
                         (step == side * side && j < side * side * side);
      if (!along) continue;
      Edge e = edge_between(truth[k], truth[j] * noise(0.1), k, j);
      e.information = 100.0 * Matrix6d::Identity();
      graph.add_edge(e);
    }
  return graph;
}

int total_trials(const OptimizationReport& report) {
  return std::accumulate(report.log.begin(), report.log.end(), 0,
                         [](int sum, const IterationRecord& r) { return sum + r.trials; });
}

// Near the minimum the step comes by PCG on an earlier factor: the same minimum as refactorising
// every iteration (plain LM), with fewer factorisations.
TEST(Optimizer, ReusingTheFactorisationReachesTheSameMinimumWithFewerFactorisations) {
  PoseGraph plain = noisy_lattice(5);
  PoseGraph reused = plain;
  OptimizerOptions no_reuse;
  no_reuse.reuse_factorization = false;
  const auto plain_report = optimize(plain, no_reuse);
  const auto report = optimize(reused);
  ASSERT_TRUE(plain_report.converged) << plain_report.stop_reason;
  ASSERT_TRUE(report.converged) << report.stop_reason;
  EXPECT_GT(report.final_cost, 0.0);
  EXPECT_NEAR(report.final_cost, plain_report.final_cost, 1e-6 * plain_report.final_cost);
  EXPECT_LE(report.final_cost, plain_report.final_cost * (1 + 1e-9));
  EXPECT_EQ(plain_report.factorizations, total_trials(plain_report));
  EXPECT_EQ(plain_report.factorizations, plain_report.iterations) << "no rejected steps here";
  EXPECT_EQ(report.factorizations, total_trials(report));
  EXPECT_LT(report.factorizations, plain_report.factorizations);
  const auto reused_steps = std::count_if(report.log.begin(), report.log.end(), [](const IterationRecord& r) {
    return r.reused_factorization && r.trials == 0;
  });
  EXPECT_GE(reused_steps, 2);
  for (const auto& [id, node] : plain.nodes()) EXPECT_LT(pose_error(node.pose, reused.node(id).pose), 1e-4) << id;
}

// A second optimise of the same structure keeps the symbolic analysis, the matrix and the factor:
// after a small disturbance, PCG on the previous call's factor finds the minimum again without a
// factorisation.
TEST(Optimizer, ASecondCallOnTheSameStructureNeedsNoAnalysisNorFactorisation) {
  PoseGraph graph = noisy_lattice(5);
  Optimizer optimizer;
  const auto first = optimizer.optimize(graph);
  ASSERT_TRUE(first.converged) << first.stop_reason;
  EXPECT_TRUE(first.reanalysed);
  EXPECT_GT(first.factorizations, 0);

  for (NodeId id : {10, 50, 90}) graph.set_pose(id, graph.node(id).pose * pose(0.002, 0, -0.002, 0.002, 0, 0));
  PoseGraph fresh = graph;
  const auto second = optimizer.optimize(graph);
  EXPECT_FALSE(second.reanalysed);
  EXPECT_EQ(optimizer.symbolic_analyses(), 1);
  EXPECT_TRUE(second.converged) << second.stop_reason;
  EXPECT_EQ(second.factorizations, 0);
  EXPECT_NEAR(second.final_cost, first.final_cost, 1e-6 * first.final_cost);
  const auto reference = Optimizer(OptimizerOptions{.reuse_factorization = false}).optimize(fresh);
  EXPECT_NEAR(second.final_cost, reference.final_cost, 1e-6 * reference.final_cost);
}

// cvo-backendd's stop within its unit's TimeoutStopSec: an optimisation out of time stops before its
// next iteration and keeps the poses of its last accepted step, never worse than where it began.
TEST(Optimizer, AnOptimisationOutOfTimeKeepsItsPosesAndSaysSo) {
  PoseGraph untouched = noisy_lattice(5);
  PoseGraph graph = untouched;
  const auto report = optimize(graph, OptimizerOptions{.max_seconds = 0.0});
  EXPECT_EQ(report.stop_reason, "time limit");
  EXPECT_FALSE(report.converged);
  EXPECT_EQ(report.iterations, 0);
  EXPECT_EQ(report.final_cost, report.initial_cost);
  for (const auto& [id, node] : untouched.nodes()) EXPECT_LT(pose_error(node.pose, graph.node(id).pose), 1e-12) << id;

  const auto unbounded = optimize(graph);  // the default: no limit
  EXPECT_TRUE(unbounded.converged) << unbounded.stop_reason;
  EXPECT_LT(unbounded.final_cost, report.final_cost);
}

}  // namespace
}  // namespace cvo::posegraph
