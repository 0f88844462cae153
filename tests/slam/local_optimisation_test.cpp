#include "libcvo/slam/local_optimisation.hpp"

#include <stdexcept>

#include <gtest/gtest.h>

#include "tests/slam/synthetic_run.hpp"

namespace cvo::slam {
namespace {

using testing::make_run;
using testing::square;

double pose_error(const core::SE3& a, const core::SE3& b) { return (a.inverse() * b).log().norm(); }

// Exact measurements, the tracker's poses off by a few cm and degrees, the keyframe anywhere in the
// world: the solution is the true relative poses, with the keyframe untouched at the identity.
TEST(LocalOptimisation, ExactEdgesGiveTheTrueRelativePosesWithTheKeyframeFixed) {
  const auto truth = square();
  auto run = make_run(truth, 6, core::Vector6d::Zero(), 1e3);
  const odometry::LocalGraph& exact = run.graphs[1];  // keyframe 6, frames 7..12
  odometry::LocalGraph graph(exact.nodes().size());
  const core::SE3 offset = core::SE3::exp((core::Vector6d() << 5, -3, 1, 0.3, 0.2, -1.0).finished());
  for (std::size_t k = 0; k < exact.nodes().size(); ++k) {
    auto node = exact.nodes()[k];
    const core::SE3 noise =
        core::SE3::exp((core::Vector6d() << 0.03, -0.02, 0.01, 0.02, -0.03, 0.04).finished() * static_cast<double>(k));
    node.pose = offset * node.pose * noise;
    graph.add_node(node);
  }
  for (const auto& e : exact.edges()) graph.add_edge(e);

  const LocalSolution s = optimise_local_graph(graph);
  ASSERT_EQ(s.frames.size(), 7u);
  EXPECT_EQ(s.edges.size(), 11u);  // 6 keyframe→frame, 5 chain
  EXPECT_TRUE(s.report.converged) << s.report.stop_reason;
  EXPECT_EQ(s.frames.front().id, 6);
  EXPECT_LT(pose_error(s.frames.front().relative, core::SE3()), 1e-12);
  for (const auto& f : s.frames) {
    EXPECT_LT(pose_error(f.relative, truth[6].inverse() * truth[static_cast<std::size_t>(f.id)]), 1e-8) << f.id;
    EXPECT_EQ(f.timestamp, static_cast<double>(f.id));
  }
  EXPECT_LT(pose_error(s.frames[3].odometry, graph.nodes()[3].pose), 1e-12);  // the tracker's pose, kept
}

// Two edges into one frame that disagree along x: the optimum is their information-weighted mean
// (the keyframe edge 4x heavier than the chain).
TEST(LocalOptimisation, DisagreeingEdgesAreWeightedByTheirInformation) {
  odometry::LocalGraph graph(3);
  graph.add_node({10, 1.0, core::SE3()});
  graph.add_node({11, 1.1, core::SE3::from_translation({0.1, 0, 0})});
  graph.add_node({12, 1.2, core::SE3::from_translation({0.2, 0, 0})});
  const core::Matrix6d I = core::Matrix6d::Identity();
  graph.add_edge({10, 11, core::SE3::from_translation({0.1, 0, 0}), 1e6 * I});
  graph.add_edge({10, 12, core::SE3::from_translation({0.20, 0, 0}), 4e3 * I});
  graph.add_edge({11, 12, core::SE3::from_translation({0.15, 0, 0}), 1e3 * I});
  const LocalSolution s = optimise_local_graph(graph);
  // x_11 ≈ 0.1 (held by its heavy edge); x_12 = (4 * 0.20 + 1 * 0.25) / 5 = 0.21.
  EXPECT_NEAR(s.frames[2].relative.translation().x(), 0.21, 1e-4);
  EXPECT_NEAR(s.frames[1].relative.translation().x(), 0.1, 1e-4);
}

TEST(LocalOptimisation, MalformedGraphsAreRefused) {
  EXPECT_THROW(optimise_local_graph(odometry::LocalGraph(2)), std::invalid_argument);
  odometry::LocalGraph graph(2);
  graph.add_node({0, 0.0, core::SE3()});
  graph.add_node({1, 0.1, core::SE3()});
  graph.add_edge({0, 7, core::SE3(), core::Matrix6d::Identity()});
  EXPECT_THROW(optimise_local_graph(graph), std::invalid_argument);

  // A keyframe alone is fine: nothing to optimise.
  odometry::LocalGraph alone(1);
  alone.add_node({3, 0.3, core::SE3::from_translation({1, 2, 3})});
  const LocalSolution s = optimise_local_graph(alone);
  ASSERT_EQ(s.frames.size(), 1u);
  EXPECT_EQ(s.frames[0].relative.translation().norm(), 0.0);
}

}  // namespace
}  // namespace cvo::slam
