#include "libcvo/posegraph/marginals.hpp"

#include <stdexcept>

#include <gtest/gtest.h>
#include <Eigen/LU>

#include "libcvo/posegraph/residual.hpp"

namespace cvo::posegraph {
namespace {

core::SE3 pose(double x, double yaw) {
  return {core::so3_exp({0.1 * yaw, 0.05, yaw}), Eigen::Vector3d(x, 0.3 * x, 0.1)};
}

core::Matrix6d information(double scale) {
  core::Matrix6d A = core::Matrix6d::Identity();
  A(0, 4) = A(4, 0) = 0.3;
  A(1, 5) = A(5, 1) = -0.2;
  return scale * A;
}

// A chain of `n` nodes, the first fixed, every edge measuring exactly what the poses say.
PoseGraph chain(int n, const core::Matrix6d& omega) {
  PoseGraph g;
  for (int k = 0; k < n; ++k) g.add_node(k, pose(0.5 * k, 0.2 * k), k == 0);
  for (int k = 1; k < n; ++k) g.add_edge({k - 1, k, g.node(k - 1).pose.inverse() * g.node(k).pose, omega, false});
  return g;
}

// At zero residuals de/dd_j = I and de/dd_i = -Ad(T_ij⁻¹): the chain's closed form is
//   Σ_k = Ad(T_{k-1,k})⁻¹ Σ_{k-1} Ad(T_{k-1,k})⁻ᵀ + Ω⁻¹,  Σ_0 = 0.
TEST(MarginalCovariances, AChainOfExactEdgesHasTheClosedFormOfComposedIncrements) {
  const core::Matrix6d omega = information(1e4);
  const PoseGraph g = chain(6, omega);
  const auto marginals = marginal_covariances(g, {0, 1, 3, 5});
  core::Matrix6d sigma = core::Matrix6d::Zero();
  for (int k = 1; k <= 5; ++k) {
    const core::Matrix6d Ad_inv = g.edges()[static_cast<std::size_t>(k - 1)].measurement.inverse().adjoint();
    sigma = Ad_inv * sigma * Ad_inv.transpose() + omega.inverse();
    if (k == 1 || k == 3 || k == 5) {
      EXPECT_LT((marginals.at(k) - sigma).norm(), 1e-9 * sigma.norm()) << "node " << k;
    }
  }
  EXPECT_TRUE(marginals.at(0).isZero()) << "a fixed node is a constant";
}

// A loop closes the chain: the marginals are the blocks of the dense inverse of H = Σ w Jᵀ Ω J,
// with the robust loop edge at its Cauchy weight.
TEST(MarginalCovariances, AreTheBlocksOfTheDenseInverseWithRobustEdgesAtTheirWeights) {
  PoseGraph g = chain(5, information(1e3));
  const core::SE3 loop = g.node(0).pose.inverse() * g.node(4).pose * core::SE3::exp(core::Vector6d::Constant(0.02));
  g.add_edge({0, 4, loop, information(1e4), true});
  OptimizerOptions options;
  options.pose_graph.cauchy_delta = 1.0;
  const RobustKernel kernel{1.0};
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(24, 24);
  for (const Edge& e : g.edges()) {
    const auto lin = linearise_edge(g.node(e.from).pose, g.node(e.to).pose, e.measurement);
    const core::Matrix6d W = kernel.weight(lin.residual.dot(e.information * lin.residual), e.robust) * e.information;
    const int a = static_cast<int>(e.from) - 1, b = static_cast<int>(e.to) - 1;  // node 0 is fixed
    if (a >= 0) H.block<6, 6>(6 * a, 6 * a) += lin.jacobian_i.transpose() * W * lin.jacobian_i;
    H.block<6, 6>(6 * b, 6 * b) += lin.jacobian_j.transpose() * W * lin.jacobian_j;
    if (a >= 0) {
      H.block<6, 6>(6 * a, 6 * b) += lin.jacobian_i.transpose() * W * lin.jacobian_j;
      H.block<6, 6>(6 * b, 6 * a) += lin.jacobian_j.transpose() * W * lin.jacobian_i;
    }
  }
  const Eigen::MatrixXd dense = H.inverse();
  const auto marginals = marginal_covariances(g, {1, 2, 3, 4}, options);
  for (int k = 1; k <= 4; ++k) {
    const core::Matrix6d expected = dense.block<6, 6>(6 * (k - 1), 6 * (k - 1));
    EXPECT_LT((marginals.at(k) - expected).norm(), 1e-9 * expected.norm()) << "node " << k;
  }
  // The loop makes the far end more certain than the open chain's.
  const auto open = marginal_covariances(chain(5, information(1e3)), {4});
  EXPECT_LT(marginals.at(4).trace(), open.at(4).trace());
}

TEST(MarginalCovariances, WithoutAFixedNodeTheFirstIsHeldAsTheOptimiserHoldsIt) {
  PoseGraph g = chain(3, information(1e2));
  g.set_fixed(0, false);
  const auto marginals = marginal_covariances(g, {0, 2});
  EXPECT_TRUE(marginals.at(0).isZero());
  EXPECT_GT(marginals.at(2).trace(), 0);
}

TEST(MarginalCovariances, AnUnknownNodeOrAnUnconstrainedOneThrows) {
  PoseGraph g = chain(3, information(1e2));
  EXPECT_THROW(marginal_covariances(g, {7}), std::out_of_range);
  g.add_node(9, core::SE3());
  EXPECT_THROW(marginal_covariances(g, {9}), std::runtime_error);
}

}  // namespace
}  // namespace cvo::posegraph
