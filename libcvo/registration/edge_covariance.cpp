#include "libcvo/registration/edge_covariance.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>

namespace cvo::registration {

std::optional<core::Matrix6d> edge_covariance(const RegistrationResult& result) {
  const Eigen::FullPivLU<core::Matrix6d> lu(result.hessian);
  if (!result.hessian.allFinite() || !lu.isInvertible()) return std::nullopt;
  const core::Matrix6d H_inv = lu.inverse();
  const core::Matrix6d sigma = H_inv * result.gradient_scatter * H_inv.transpose();
  const core::Matrix6d symmetric = 0.5 * (sigma + sigma.transpose());
  if (!symmetric.allFinite() || Eigen::LDLT<core::Matrix6d>(symmetric).info() != Eigen::Success) return std::nullopt;
  if (!(symmetric.diagonal().array() > 0).all()) return std::nullopt;
  return symmetric;
}

core::Matrix6d information_of(const std::optional<core::Matrix6d>& covariance, const core::Matrix6d& hessian) {
  if (!covariance) return hessian;
  const Eigen::LLT<core::Matrix6d> llt(*covariance);
  if (llt.info() != Eigen::Success) return hessian;
  const core::Matrix6d omega = llt.solve(core::Matrix6d::Identity());
  return 0.5 * (omega + omega.transpose());
}

}  // namespace cvo::registration
