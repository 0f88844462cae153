#include "libcvo/slam/edge_information.hpp"

namespace cvo::slam {

core::Matrix6d edge_information(const core::SE3& measurement, const core::Matrix6d& cvo_hessian) {
  const core::Matrix6d Ad = measurement.adjoint();
  const core::Matrix6d omega = Ad.transpose() * cvo_hessian * Ad;
  return 0.5 * (omega + omega.transpose());
}

}  // namespace cvo::slam
