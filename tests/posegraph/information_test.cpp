// The information-matrix invariant (finite, symmetric, positive semi-definite) and its repair.
#include "libcvo/core/information.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "libcvo/posegraph/pose_graph.hpp"

namespace cvo::posegraph {
namespace {

using core::check_information;
using core::InformationDefect;
using core::kInformationRepairFloor;
using core::Matrix6d;
using core::nearest_information;

// Identity but for the translation x-y block [[1, b], [b, 1]]: eigenvalues 1 + b and 1 - b.
Matrix6d coupled_xy(double b) {
  Matrix6d m = Matrix6d::Identity();
  m(0, 1) = m(1, 0) = b;
  return m;
}

TEST(Information, DefiniteAndSemiDefiniteMatricesPass) {
  EXPECT_TRUE(check_information(Matrix6d::Identity()).ok());
  EXPECT_TRUE(check_information(coupled_xy(0.99)).ok());
  EXPECT_TRUE(check_information(Matrix6d::Zero()).ok());
  // Rank 3 at a CVO Hessian's scale, as a registration on a flat wall gives: its zero eigenvalues
  // come out of round-off slightly negative and must still pass.
  const Eigen::Matrix<double, 6, 3> A = 1e4 * Eigen::Matrix<double, 6, 3>::Random();
  const Matrix6d semi = A * A.transpose();
  const auto check = check_information(semi);
  EXPECT_TRUE(check.ok()) << check.why();
  EXPECT_NEAR(check.smallest_eigenvalue, 0.0, 1e-12 * check.largest_eigenvalue);
  EXPECT_TRUE(check.why().empty());
}

TEST(Information, IndefiniteAsymmetricAndNonFiniteMatricesAreRefused) {
  const auto indefinite = check_information(coupled_xy(1.2));
  EXPECT_EQ(indefinite.defect, InformationDefect::kIndefinite);
  EXPECT_NEAR(indefinite.smallest_eigenvalue, -0.2, 1e-12);
  EXPECT_NEAR(indefinite.largest_eigenvalue, 2.2, 1e-12);
  EXPECT_NE(indefinite.why().find("not positive semi-definite (eigenvalues -0.2 .. 2.2)"), std::string::npos)
      << indefinite.why();
  // Tolerances are relative: the same shape at any scale is refused.
  EXPECT_EQ(check_information(1e-8 * coupled_xy(1.2)).defect, InformationDefect::kIndefinite);
  EXPECT_EQ(check_information(1e8 * coupled_xy(1.2)).defect, InformationDefect::kIndefinite);

  Matrix6d asymmetric = Matrix6d::Identity();
  asymmetric(2, 4) = 0.1;
  EXPECT_EQ(check_information(asymmetric).defect, InformationDefect::kNotSymmetric);

  Matrix6d nan = Matrix6d::Identity();
  nan(3, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(check_information(nan).defect, InformationDefect::kNotFinite);
  EXPECT_NE(check_information(nan).why().find("not finite"), std::string::npos);
}

// The nearest symmetric positive semi-definite matrix keeps the eigenvectors and clamps the
// eigenvalues: 2.2 along (1, 1)/sqrt2 stays, -0.2 along (1, -1)/sqrt2 becomes the floor.
TEST(Information, RepairClampsTheNegativeEigenvalueToTheFloor) {
  const double floor = kInformationRepairFloor * 2.2;
  Matrix6d expected = Matrix6d::Identity();
  expected.topLeftCorner<2, 2>() << 1.1 + floor / 2, 1.1 - floor / 2, 1.1 - floor / 2, 1.1 + floor / 2;
  const Matrix6d repaired = nearest_information(coupled_xy(1.2));
  EXPECT_LT((repaired - expected).cwiseAbs().maxCoeff(), 1e-12) << repaired;
  EXPECT_EQ(repaired, repaired.transpose());
  EXPECT_TRUE(check_information(repaired).ok());
  EXPECT_GT(check_information(repaired).smallest_eigenvalue, 0.0);  // definite: Cholesky exists
  EXPECT_EQ(repaired.llt().info(), Eigen::Success);
}

TEST(Information, RepairKeepsAGoodMatrixAndSymmetrises) {
  const Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Random();
  const Matrix6d good = A * A.transpose() + Matrix6d::Identity();
  EXPECT_LT((nearest_information(good) - good).cwiseAbs().maxCoeff(), 1e-12 * good.cwiseAbs().maxCoeff());
  Matrix6d lopsided = good;
  lopsided(0, 5) += 0.5;  // the nearest symmetric matrix is the mean of the two triangles
  Matrix6d mean = good;
  mean(0, 5) += 0.25;
  mean(5, 0) += 0.25;
  EXPECT_LT((nearest_information(lopsided) - mean).cwiseAbs().maxCoeff(), 1e-12 * good.cwiseAbs().maxCoeff());
  Matrix6d nan = good;
  nan(1, 1) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(nearest_information(nan), std::invalid_argument);
}

TEST(Information, PoseGraphRefusesAnEdgeWithIndefiniteInformation) {
  PoseGraph graph;
  graph.add_node(0, {});
  graph.add_node(1, core::SE3::from_translation({1, 0, 0}));
  Edge e{0, 1, core::SE3::from_translation({1, 0, 0}), coupled_xy(1.2), false};
  try {
    graph.add_edge(e);
    FAIL() << "an indefinite information matrix was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("edge 0 -> 1: information is not positive semi-definite"),
              std::string::npos)
        << error.what();
  }
  EXPECT_TRUE(graph.edges().empty());
  e.information = coupled_xy(0.5);
  graph.add_edge(e);
  EXPECT_EQ(graph.edges().size(), 1u);
}

}  // namespace
}  // namespace cvo::posegraph
