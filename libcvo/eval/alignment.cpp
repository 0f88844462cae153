#include "libcvo/eval/alignment.hpp"

#include <stdexcept>
#include <string>

#include <Eigen/SVD>

namespace cvo::eval {

core::SE3 align_rigid(std::span<const Eigen::Vector3d> model, std::span<const Eigen::Vector3d> data) {
  if (model.empty() || model.size() != data.size())
    throw std::invalid_argument("rigid alignment needs two non-empty point lists of equal length, got " +
                                std::to_string(model.size()) + " and " + std::to_string(data.size()));
  Eigen::Vector3d model_mean = Eigen::Vector3d::Zero(), data_mean = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < model.size(); ++i) {
    model_mean += model[i];
    data_mean += data[i];
  }
  model_mean /= static_cast<double>(model.size());
  data_mean /= static_cast<double>(data.size());

  // Centre before accumulating: trajectories may sit far from the origin.
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < model.size(); ++i) h += (data[i] - data_mean) * (model[i] - model_mean).transpose();

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d s = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) s(2, 2) = -1;
  const Eigen::Matrix3d r = svd.matrixU() * s * svd.matrixV().transpose();
  return {r, data_mean - r * model_mean};
}

}  // namespace cvo::eval
