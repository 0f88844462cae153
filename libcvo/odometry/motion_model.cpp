#include "libcvo/odometry/motion_model.hpp"

namespace cvo::odometry {
namespace {

// V^s = exp(s log V); s = 1 is returned as is, so the usual case is exact eq. 7.
core::SE3 power(const core::SE3& v, double s) { return s == 1.0 ? v : core::SE3::exp(s * v.log()); }

// Frames between two stream indices; 1 when the indices do not increase (frames built by hand
// often all carry index 0), so the guess is then plain eq. 7.
std::uint64_t frames_between(std::uint64_t from, std::uint64_t to) { return to > from ? to - from : 1; }

}  // namespace

core::SE3 MotionModel::predict(std::uint64_t index) const {
  if (!have_frame_) return last_pose_;  // the initial pose
  return last_pose_ * power(velocity_, static_cast<double>(frames_between(last_index_, index)));
}

void MotionModel::update(std::uint64_t index, const core::SE3& predicted, const core::SE3& measured,
                         TrackResult& result) {
  bool becomes_reference = false;
  switch (result.status) {
    case TrackStatus::kSelectionFailed: result.pose = predicted; break;
    case TrackStatus::kFirstFrame:
      result.pose = predicted;  // the initial pose, or a prediction when earlier frames were unusable
      becomes_reference = true;
      break;
    case TrackStatus::kOk:
      result.pose = reference_pose_ * measured;
      velocity_ = power(measured, 1.0 / static_cast<double>(frames_between(reference_index_, index)));
      becomes_reference = true;
      break;
    case TrackStatus::kRegistrationFailed:
      result.pose = predicted;  // V is kept: the constant-velocity guess carries on
      becomes_reference = ++failures_on_reference_ >= restart_after_failures_;
      break;
  }
  if (becomes_reference) {
    reference_ = current_slot();
    reference_pose_ = result.pose;
    reference_index_ = index;
    have_reference_ = true;
    failures_on_reference_ = 0;
  }
  result.motion = last_pose_.inverse() * result.pose;
  last_pose_ = result.pose;
  last_index_ = index;
  have_frame_ = true;
}

}  // namespace cvo::odometry
