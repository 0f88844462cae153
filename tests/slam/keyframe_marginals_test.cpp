// The covariances CVO_MAP and CVO_MAP_CORRECTION report, kept by slam::KeyframeMarginals without a
// factorisation per update: a graph that grows by leaves carries them along exactly (what one
// factorisation of the grown graph gives), and any other growth, or moved poses, makes the next
// one asked for factorise again.
#include "libcvo/slam/keyframe_marginals.hpp"

#include <gtest/gtest.h>

#include "libcvo/posegraph/marginals.hpp"

namespace cvo::slam {
namespace {

using posegraph::NodeId;
using posegraph::PoseGraph;

core::SE3 step(int k) { return {core::so3_exp({0.02 * k, -0.01, 0.15}), Eigen::Vector3d(0.3, 0.05 * k, 0.01)}; }

core::Matrix6d information(double scale) {
  core::Matrix6d A = core::Matrix6d::Identity();
  A(0, 4) = A(4, 0) = 0.3;
  A(2, 3) = A(3, 2) = -0.2;
  return scale * A;
}

// A leaf as the back end hangs a local graph's last frame: at the parent's pose times the edge.
void add_leaf(PoseGraph& g, NodeId parent, NodeId leaf, int k) {
  g.add_node(leaf, g.node(parent).pose * step(k));
  g.add_edge({parent, leaf, step(k), information(1e3 * (1 + k)), false});
}

// A chain from a fixed anchor, with a loop between its second and fourth node so the marginals
// are not a chain's alone.
PoseGraph start() {
  PoseGraph g;
  g.add_node(0, core::SE3(), true);
  for (NodeId n = 1; n <= 4; ++n) add_leaf(g, n - 1, n, static_cast<int>(n));
  g.add_edge({1, 3, g.node(1).pose.inverse() * g.node(3).pose * core::SE3::exp(core::Vector6d::Constant(0.01)),
              information(5e2), true});
  return g;
}

void expect_factorised_marginal(const PoseGraph& g, const KeyframeMarginals& m, NodeId n) {
  const core::Matrix6d expected = posegraph::marginal_covariances(g, {n}).at(n);
  const auto held = m.find(n);
  ASSERT_TRUE(held) << "node " << n;
  EXPECT_LT((*held - expected).norm(), 1e-9 * expected.norm()) << "node " << n;
}

TEST(KeyframeMarginals, LeavesCarryTheMarginalsAlongAsOneFactorisationWould) {
  PoseGraph g = start();
  KeyframeMarginals m;
  m.compute(g, {4}, {});
  ASSERT_EQ(m.factorisations(), 1u);
  for (NodeId n = 5; n <= 40; ++n) {  // 36 local graphs, each a leaf on the last
    add_leaf(g, n - 1, n, static_cast<int>(n));
    m.follow(g);
    m.keep({n});
    expect_factorised_marginal(g, m, n);
  }
  EXPECT_EQ(m.factorisations(), 1u) << "no factorisation after the first";
  // A leaf hung the other way round (the new node at the edge's `from` end) is one too.
  g.add_node(100, g.node(40).pose * step(3).inverse());
  g.add_edge({100, 40, step(3), information(2e3), false});
  m.follow(g);
  expect_factorised_marginal(g, m, 100);
  expect_factorised_marginal(g, m, 40);
}

TEST(KeyframeMarginals, ANewPiecesAnchorAndItsLeavesAreCarriedToo) {
  PoseGraph g = start();
  KeyframeMarginals m;
  m.compute(g, {4}, {});
  g.add_node(1000, core::SE3::from_translation({5, 0, 0}), true);  // a new session's first keyframe
  add_leaf(g, 1000, 1001, 2);
  add_leaf(g, 4, 5, 5);  // and the first session goes on
  m.follow(g);
  expect_factorised_marginal(g, m, 1001);
  expect_factorised_marginal(g, m, 5);
  EXPECT_TRUE(m.find(1000)->isZero()) << "a fixed anchor is a constant";
  EXPECT_EQ(m.factorisations(), 1u);
}

TEST(KeyframeMarginals, ALoopANodeWithoutAnEdgeOrMovedPosesMakeItFactoriseAgain) {
  PoseGraph g = start();
  KeyframeMarginals m;
  m.compute(g, {4}, {});
  add_leaf(g, 4, 5, 5);
  g.add_edge({2, 5, g.node(2).pose.inverse() * g.node(5).pose, information(1e2), true});  // a loop
  m.follow(g);
  EXPECT_FALSE(m.find(5)) << "a loop changes every marginal";
  m.compute(g, {5}, {});
  EXPECT_EQ(m.factorisations(), 2u);
  expect_factorised_marginal(g, m, 5);

  g.add_node(6, core::SE3());  // held by no edge
  m.follow(g);
  EXPECT_FALSE(m.find(5));
  g.add_edge({5, 6, g.node(5).pose.inverse() * g.node(6).pose, information(1e3), false});
  m.compute(g, {5, 6}, {});
  g.set_pose(6, g.node(6).pose * step(1));  // an optimisation moved it
  m.invalidate();
  EXPECT_FALSE(m.find(6));
}

TEST(KeyframeMarginals, AFailedFactorisationIsNotTriedAgainUntilTheGraphChanges) {
  PoseGraph g = start();
  g.add_node(50, core::SE3());  // free, held by nothing: H is singular
  KeyframeMarginals m;
  m.compute(g, {4}, {});
  EXPECT_FALSE(m.find(4));
  EXPECT_FALSE(m.worth_computing());
  m.follow(g);
  EXPECT_FALSE(m.worth_computing()) << "nothing changed";
  g.add_edge({4, 50, g.node(4).pose.inverse() * g.node(50).pose, information(1e3), false});
  m.follow(g);
  EXPECT_TRUE(m.worth_computing());
  m.compute(g, {50}, {});
  expect_factorised_marginal(g, m, 50);
}

}  // namespace
}  // namespace cvo::slam
