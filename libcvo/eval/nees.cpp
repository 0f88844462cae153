#include "libcvo/eval/nees.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>

#include <Eigen/Cholesky>

namespace cvo::eval {
namespace {

// ξᵀ Σ⁻¹ ξ for a symmetric positive-definite Σ (nullopt otherwise).
template <int N>
std::optional<double> mahalanobis(const Eigen::Matrix<double, N, 1>& e, const Eigen::Matrix<double, N, N>& sigma) {
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(sigma);
  if (llt.info() != Eigen::Success) return std::nullopt;
  const double v = e.dot(llt.solve(e));
  return std::isfinite(v) ? std::optional<double>(v) : std::nullopt;
}

// The ground truth at t, interpolated between the poses around it, both within max_difference.
std::optional<core::SE3> groundtruth_at(const core::Trajectory& gt, double t, double max_difference) {
  const auto after =
      std::lower_bound(gt.begin(), gt.end(), t, [](const core::StampedPose& p, double s) { return p.timestamp < s; });
  if (after != gt.end() && after->timestamp == t) return after->pose;
  if (after == gt.begin() || after == gt.end()) return std::nullopt;
  const auto before = std::prev(after);
  if (t - before->timestamp >= max_difference || after->timestamp - t >= max_difference) return std::nullopt;
  const double s = (t - before->timestamp) / (after->timestamp - before->timestamp);
  return core::interpolate(before->pose, after->pose, s);
}

}  // namespace

std::optional<NeesValue> nees(const core::Vector6d& error, const core::Matrix6d& covariance) {
  const auto all = mahalanobis<6>(error, covariance);
  const auto t = mahalanobis<3>(error.head<3>(), covariance.topLeftCorner<3, 3>());
  const auto r = mahalanobis<3>(error.tail<3>(), covariance.bottomRightCorner<3, 3>());
  if (!all || !t || !r) return std::nullopt;
  return NeesValue{*all, *t, *r};
}

NeesResult relative_pose_nees(const core::Trajectory& groundtruth, const core::Trajectory& estimate,
                              const std::vector<io::StampedCovariance>& covariances, const NeesOptions& options) {
  NeesResult result;
  std::vector<double> all, translation, rotation;
  for (const auto& c : covariances) {
    const auto at = std::lower_bound(estimate.begin(), estimate.end(), c.timestamp,
                                     [](const core::StampedPose& p, double s) { return p.timestamp < s; });
    if (at == estimate.begin() || at == estimate.end() || at->timestamp != c.timestamp) continue;
    const auto& previous = *std::prev(at);
    const auto g0 = groundtruth_at(groundtruth, previous.timestamp, options.max_difference);
    const auto g1 = groundtruth_at(groundtruth, at->timestamp, options.max_difference);
    if (!g0 || !g1) continue;
    const core::SE3 estimated = previous.pose.inverse() * at->pose, truth = g0->inverse() * *g1;
    const auto v = nees((estimated.inverse() * truth).log(), c.covariance);
    if (!v) continue;
    result.pairs.push_back({c.timestamp, v->nees, v->translation, v->rotation});
    all.push_back(v->nees);
    translation.push_back(v->translation);
    rotation.push_back(v->rotation);
  }
  if (all.empty())
    throw std::invalid_argument("no relative pose has a covariance, its previous pose and ground truth around both");
  result.nees = summarize(all);
  result.translation = summarize(translation);
  result.rotation = summarize(rotation);
  return result;
}

}  // namespace cvo::eval
