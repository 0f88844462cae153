#include "libcvo/odometry/frame_to_frame.hpp"

#include <chrono>

namespace cvo::odometry {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// V^s = exp(s log V); s = 1 is returned as is, so the usual case is exact eq. 7.
core::SE3 power(const core::SE3& v, double s) { return s == 1.0 ? v : core::SE3::exp(s * v.log()); }

// Frames between two stream indices; 1 when the indices do not increase (frames built by hand
// often all carry index 0), so the guess is then plain eq. 7.
std::uint64_t frames_between(std::uint64_t from, std::uint64_t to) { return to > from ? to - from : 1; }

bool selection_usable(registration::SelectionStatus s) {
  // A clamped selection still holds a full cloud; only its surplus points were dropped.
  return s == registration::SelectionStatus::kOk || s == registration::SelectionStatus::kCapacityClamped;
}

}  // namespace

FrameToFrameOdometry::FrameToFrameOdometry(int width, int height, const FrameToFrameParameters& parameters)
    : parameters_(parameters),
      selector_(width, height, parameters.selection),
      registration_(registration::Capacities{parameters.max_points}, parameters.cvo),
      clouds_{registration::PointCloud(parameters.max_points), registration::PointCloud(parameters.max_points)},
      last_pose_(parameters.initial_pose) {}

TrackResult FrameToFrameOdometry::track(const core::RgbdFrame& frame) {
  TrackResult result;
  const std::uint64_t gap = have_frame_ ? frames_between(last_index_, frame.index) : 0;
  const core::SE3 predicted = have_frame_ ? last_pose_ * power(velocity_, static_cast<double>(gap)) : last_pose_;

  const int current = have_reference_ ? 1 - reference_ : reference_;
  registration::PointCloud& cloud = clouds_[static_cast<std::size_t>(current)];
  const auto selection_start = Clock::now();
  const registration::SelectionResult selection = selector_.select(frame, cloud);
  result.selection_ms = ms_since(selection_start);
  result.selection_status = selection.status;
  result.points = cloud.size();

  bool becomes_reference = false;
  if (!selection_usable(selection.status) || cloud.empty()) {
    result.status = TrackStatus::kSelectionFailed;
    result.pose = predicted;
  } else if (!have_reference_) {
    result.status = TrackStatus::kFirstFrame;
    result.pose = predicted;  // the initial pose, or a prediction when earlier frames had no points
    becomes_reference = true;
  } else {
    const core::SE3 initial = reference_pose_.inverse() * predicted;
    const auto registration_start = Clock::now();
    const registration::RegistrationResult r =
        registration_.align(clouds_[static_cast<std::size_t>(reference_)], cloud, initial);
    result.registration_ms = ms_since(registration_start);
    result.registration_status = r.status;
    result.iterations = r.iterations;
    result.inner_product = r.inner_product;
    if (r.converged && r.status == registration::RegistrationStatus::kOk && r.transform.is_finite()) {
      result.status = TrackStatus::kOk;
      result.pose = reference_pose_ * r.transform;
      const std::uint64_t span = frames_between(reference_index_, frame.index);
      velocity_ = power(r.transform, 1.0 / static_cast<double>(span));
      becomes_reference = true;
    } else {
      result.status = TrackStatus::kRegistrationFailed;
      result.pose = predicted;  // V is kept: the constant-velocity guess carries on
      becomes_reference = ++failures_on_reference_ >= parameters_.restart_after_failures;
    }
  }

  if (becomes_reference) {
    reference_ = current;
    reference_pose_ = result.pose;
    reference_index_ = frame.index;
    have_reference_ = true;
    failures_on_reference_ = 0;
  }
  result.motion = last_pose_.inverse() * result.pose;
  last_pose_ = result.pose;
  last_index_ = frame.index;
  have_frame_ = true;
  return result;
}

}  // namespace cvo::odometry
