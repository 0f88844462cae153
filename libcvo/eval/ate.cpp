#include "libcvo/eval/ate.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "libcvo/eval/alignment.hpp"
#include "libcvo/eval/trajectory_checks.hpp"

namespace cvo::eval {

AteResult absolute_trajectory_error(const core::Trajectory& groundtruth, const core::Trajectory& estimate,
                                    const AteOptions& options) {
  if (!std::isfinite(options.max_difference) || options.max_difference <= 0 || !std::isfinite(options.offset))
    throw std::invalid_argument("ATE needs a finite max time difference > 0 and a finite time offset");
  const core::Trajectory gt = sorted_unique(groundtruth, "ground truth");
  const core::Trajectory est = sorted_unique(estimate, "estimate");

  const auto matches =
      core::associate(core::timestamps(gt), core::timestamps(est), options.max_difference, options.offset);
  if (matches.size() < 3) {
    std::ostringstream msg;
    msg << "ATE needs at least 3 pose pairs whose timestamps differ by less than " << options.max_difference
        << " s, found " << matches.size() << " (ground truth: " << gt.size() << " poses";
    if (!gt.empty()) msg << std::fixed << " from " << gt.front().timestamp << " to " << gt.back().timestamp << " s";
    msg << std::defaultfloat << "; estimate: " << est.size() << " poses";
    if (!est.empty()) msg << std::fixed << " from " << est.front().timestamp << " to " << est.back().timestamp << " s";
    msg << ")";
    throw std::invalid_argument(msg.str());
  }

  std::vector<Eigen::Vector3d> est_points, gt_points;
  for (const auto& [i, j] : matches) {
    gt_points.push_back(gt[i].pose.translation());
    est_points.push_back(est[j].pose.translation());
  }
  AteResult result;
  result.alignment = align_rigid(est_points, gt_points);

  std::vector<double> errors;
  for (std::size_t k = 0; k < matches.size(); ++k) {
    AtePair p;
    p.gt_timestamp = gt[matches[k].first].timestamp;
    p.est_timestamp = est[matches[k].second].timestamp;
    p.gt_position = gt_points[k];
    p.aligned_position = result.alignment * est_points[k];
    p.error = (p.aligned_position - p.gt_position).norm();
    errors.push_back(p.error);
    result.pairs.push_back(p);
  }
  result.error = summarize(errors);
  return result;
}

}  // namespace cvo::eval
