#include "libcvo/eval/rpe.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

#include "libcvo/core/units.hpp"
#include "libcvo/eval/trajectory_checks.hpp"

namespace cvo::eval {

core::SE3 relative_pose_error_transform(const core::SE3& est_i, const core::SE3& est_j, const core::SE3& gt_i,
                                        const core::SE3& gt_j) {
  const core::SE3 est_motion = est_i.inverse() * est_j;
  const core::SE3 gt_motion = gt_i.inverse() * gt_j;
  return est_motion * gt_motion.inverse();
}

double rotation_angle_from_trace(const core::SE3& transform) {
  const double c = (transform.rotation_matrix().trace() - 1.0) / 2.0;
  return std::acos(std::clamp(c, -1.0, 1.0));
}

namespace {

double median_interval(const std::vector<double>& sorted_stamps) {
  std::vector<double> d;
  for (std::size_t k = 1; k < sorted_stamps.size(); ++k) d.push_back(sorted_stamps[k] - sorted_stamps[k - 1]);
  return summarize(d).median;
}

}  // namespace

RpeResult relative_pose_error(const core::Trajectory& groundtruth, const core::Trajectory& estimate,
                              const RpeOptions& options) {
  if (!std::isfinite(options.delta) || options.delta <= 0 || !std::isfinite(options.offset))
    throw std::invalid_argument("RPE needs a finite delta > 0 and a finite time offset");
  const core::Trajectory gt = sorted_unique(groundtruth, "ground truth");
  const core::Trajectory est = sorted_unique(estimate, "estimate");
  if (gt.size() < 2 || est.size() < 2)
    throw std::invalid_argument("RPE needs at least 2 poses in each trajectory, got " + std::to_string(gt.size()) +
                                " in the ground truth and " + std::to_string(est.size()) + " in the estimate");
  const std::vector<double> gt_stamps = core::timestamps(gt);
  const std::vector<double> est_stamps = core::timestamps(est);

  // The script's overlap test: map each estimate stamp to the nearest ground truth and back; when
  // fewer than 2 distinct estimate stamps come back, the two files do not overlap in time.
  std::set<std::size_t> returned;
  for (const double t : est_stamps) {
    const double t_gt = gt_stamps[core::find_closest_index(gt_stamps, t + options.offset)];
    returned.insert(core::find_closest_index(est_stamps, t_gt - options.offset));
  }
  if (returned.size() < 2) throw std::invalid_argument("RPE: the estimate and the ground truth hardly overlap in time");

  const double max_gt_gap = 2.0 * median_interval(gt_stamps);
  RpeResult result;
  result.delta = options.delta;
  std::vector<double> trans, rot;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const std::size_t j = core::find_closest_index(est_stamps, est_stamps[i] + options.delta);
    if (j == est.size() - 1) continue;  // the script's quirk, kept on purpose (see header)
    const std::size_t gi = core::find_closest_index(gt_stamps, est_stamps[i] + options.offset);
    const std::size_t gj = core::find_closest_index(gt_stamps, est_stamps[j] + options.offset);
    if (std::abs(gt_stamps[gi] - (est_stamps[i] + options.offset)) > max_gt_gap ||
        std::abs(gt_stamps[gj] - (est_stamps[j] + options.offset)) > max_gt_gap)
      continue;
    const core::SE3 e = relative_pose_error_transform(est[i].pose, est[j].pose, gt[gi].pose, gt[gj].pose);
    RpePair p;
    p.est_timestamp_0 = est_stamps[i];
    p.est_timestamp_1 = est_stamps[j];
    p.gt_timestamp_0 = gt_stamps[gi];
    p.gt_timestamp_1 = gt_stamps[gj];
    p.translation = e.translation().norm();
    p.rotation_deg = core::degrees(rotation_angle_from_trace(e));
    trans.push_back(p.translation);
    rot.push_back(p.rotation_deg);
    result.pairs.push_back(p);
  }
  if (result.pairs.size() < 2) {
    std::ostringstream msg;
    msg << "RPE needs at least 2 pose pairs " << options.delta << " s apart with ground truth nearby, found "
        << result.pairs.size() << " (estimate spans " << est_stamps.back() - est_stamps.front() << " s)";
    throw std::invalid_argument(msg.str());
  }
  result.translation = summarize(trans);
  result.rotation_deg = summarize(rot);
  return result;
}

}  // namespace cvo::eval
