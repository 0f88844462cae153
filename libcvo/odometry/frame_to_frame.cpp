#include "libcvo/odometry/frame_to_frame.hpp"

#include <chrono>

#include "libcvo/core/units.hpp"

namespace cvo::odometry {

namespace {

using Clock = core::SteadyClock;
using core::ms_since;

bool selection_usable(registration::SelectionStatus s) {
  // A clamped selection still holds a full cloud; only its surplus points were dropped.
  return s == registration::SelectionStatus::kOk || s == registration::SelectionStatus::kCapacityClamped;
}

}  // namespace

FrameToFrameOdometry::FrameToFrameOdometry(int width, int height, const FrameToFrameParameters& parameters)
    : parameters_(parameters),
      selector_(width, height, parameters.selection),
      registration_(registration::Capacities{parameters.odometry.max_points}, parameters.cvo),
      clouds_{registration::PointCloud(parameters.odometry.max_points),
              registration::PointCloud(parameters.odometry.max_points)},
      motion_(parameters.initial_pose, parameters.odometry.restart_after_failures) {}

TrackResult FrameToFrameOdometry::track(const core::RgbdFrame& frame) {
  TrackResult result;
  const core::SE3 predicted = motion_.predict(frame.index);
  registration::PointCloud& cloud = clouds_[static_cast<std::size_t>(motion_.current_slot())];
  const auto selection_start = Clock::now();
  const registration::SelectionResult selection = selector_.select(frame, cloud);
  result.selection_ms = ms_since(selection_start);
  result.selection_status = selection.status;
  result.points = cloud.size();

  core::SE3 measured;
  if (!selection_usable(selection.status) || cloud.empty()) {
    result.status = TrackStatus::kSelectionFailed;
  } else if (!motion_.has_reference()) {
    result.status = TrackStatus::kFirstFrame;
  } else {
    const auto registration_start = Clock::now();
    const registration::RegistrationResult r = registration_.align(
        clouds_[static_cast<std::size_t>(motion_.reference_slot())], cloud, motion_.guess(predicted));
    result.registration_ms = ms_since(registration_start);
    result.registration_status = r.status;
    result.iterations = r.iterations;
    result.inner_product = r.inner_product;
    const bool ok = r.converged && r.status == registration::RegistrationStatus::kOk && r.transform.is_finite();
    result.status = ok ? TrackStatus::kOk : TrackStatus::kRegistrationFailed;
    measured = r.transform;
  }
  motion_.update(frame.index, predicted, measured, result);
  return result;
}

}  // namespace cvo::odometry
