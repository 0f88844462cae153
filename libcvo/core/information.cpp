#include "libcvo/core/information.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <Eigen/Eigenvalues>

namespace cvo::core {
namespace {

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

std::string InformationCheck::why() const {
  switch (defect) {
    case InformationDefect::kNone: return {};
    case InformationDefect::kNotFinite: return "information is not finite";
    case InformationDefect::kNotSymmetric: return "information is not symmetric";
    case InformationDefect::kIndefinite:
      return "information is not positive semi-definite (eigenvalues " + number(smallest_eigenvalue) + " .. " +
             number(largest_eigenvalue) + ")";
  }
  return "information is invalid";
}

InformationCheck check_information(const core::Matrix6d& omega) {
  InformationCheck check;
  if (!omega.allFinite()) {
    check.defect = InformationDefect::kNotFinite;
    return check;
  }
  const Eigen::SelfAdjointEigenSolver<core::Matrix6d> eigen(0.5 * (omega + omega.transpose()), Eigen::EigenvaluesOnly);
  check.smallest_eigenvalue = eigen.eigenvalues()(0);  // ascending
  check.largest_eigenvalue = eigen.eigenvalues()(5);
  const double scale = omega.cwiseAbs().maxCoeff();
  const double magnitude = std::max(std::abs(check.smallest_eigenvalue), std::abs(check.largest_eigenvalue));
  if ((omega - omega.transpose()).cwiseAbs().maxCoeff() > kInformationTolerance * scale)
    check.defect = InformationDefect::kNotSymmetric;
  else if (check.smallest_eigenvalue < -kInformationTolerance * magnitude)
    check.defect = InformationDefect::kIndefinite;
  return check;
}

core::Matrix6d nearest_information(const core::Matrix6d& omega) {
  if (!omega.allFinite()) throw std::invalid_argument("nearest_information: the matrix is not finite");
  const Eigen::SelfAdjointEigenSolver<core::Matrix6d> eigen(0.5 * (omega + omega.transpose()));
  const core::Vector6d& lambda = eigen.eigenvalues();
  const double floor = kInformationRepairFloor * lambda.cwiseAbs().maxCoeff();
  const core::Matrix6d& V = eigen.eigenvectors();
  const core::Matrix6d repaired = V * lambda.cwiseMax(floor).asDiagonal() * V.transpose();
  return 0.5 * (repaired + repaired.transpose());  // exactly symmetric, as add_edge checks
}

}  // namespace cvo::core
