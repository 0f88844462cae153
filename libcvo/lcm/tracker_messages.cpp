#include "libcvo/lcm/tracker_messages.hpp"

#include <algorithm>

#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {

std::int8_t to_pose_status(odometry::TrackStatus status) {
  switch (status) {
    case odometry::TrackStatus::kOk: return cvo_lcm::pose_t::STATUS_OK;
    case odometry::TrackStatus::kFirstFrame: return cvo_lcm::pose_t::STATUS_FIRST_FRAME;
    case odometry::TrackStatus::kSelectionFailed: return cvo_lcm::pose_t::STATUS_SELECTION_FAILED;
    case odometry::TrackStatus::kRegistrationFailed: return cvo_lcm::pose_t::STATUS_REGISTRATION_FAILED;
  }
  return cvo_lcm::pose_t::STATUS_LOST;
}

cvo_lcm::pose_t pose_message(std::int64_t session, std::string_view robot, const TrackedPose& pose, double latency_ms) {
  cvo_lcm::pose_t m{};
  m.version = cvo_lcm::pose_t::SCHEMA_VERSION;
  m.session = session;
  m.robot = robot;
  m.utime = to_utime(pose.timestamp);
  m.frame_index = pose.frame_index;
  m.keyframe_id = pose.keyframe_id;
  m.odom_pose = to_message(pose.odom_pose);
  m.map_pose = to_message(pose.has_map_pose ? pose.map_pose : core::SE3());
  m.map_placed = pose.map_placed;
  m.has_map_pose = pose.has_map_pose;
  m.map_epoch = pose.map_epoch;
  m.map_revision = pose.map_revision;
  m.state = static_cast<std::int8_t>(pose.state);
  m.since_match_s = pose.state == core::LocalizationState::kLocalized ? pose.since_match_s : -1;
  matrix6_to_message(pose.covariance, m.covariance);
  m.has_relative_covariance = pose.relative_covariance.has_value();
  matrix6_to_message(pose.relative_covariance.value_or(core::Matrix6d::Zero()), m.relative_covariance);
  m.status = to_pose_status(pose.status);
  m.is_keyframe = pose.is_keyframe;
  m.inner_product = pose.inner_product;
  m.gamma_frame = 0;  // KF-CVO adapts only the keyframe's kernel
  m.gamma_keyframe = pose.gamma_keyframe;
  m.iterations = pose.iterations;
  m.points = pose.points;
  m.latency_ms = latency_ms;
  return m;
}

std::int8_t tracker_state(const TrackerActivity& a) {
  using S = cvo_lcm::status_t;
  if (a.published == 0) return a.source_connected ? S::STATE_STARTING : S::STATE_WAITING_FOR_INPUT;
  if (!a.source_connected || a.idle) return S::STATE_WAITING_FOR_INPUT;
  if (a.failures_since_last) return S::STATE_DEGRADED;
  return S::STATE_RUNNING;
}

cvo_lcm::status_t status_message(const ProcessStatus& s) {
  cvo_lcm::status_t m{};
  m.version = cvo_lcm::status_t::SCHEMA_VERSION;
  m.session = s.session;
  m.utime = s.utime;
  m.pid = s.pid;
  m.state = s.state;
  m.rate_hz = s.rate_hz;
  m.latency_median_ms = s.latency_median_ms;
  m.latency_p99_ms = s.latency_p99_ms;
  m.deadline_misses = s.deadline_misses;
  m.dropped_frames = s.dropped_frames;
  m.failed_frames = s.failed_frames;
  m.source_gaps = s.source_gaps;
  m.allocations_after_warmup = s.allocations_after_warmup;
  m.queue_depth = s.queue_depth;
  m.rss_bytes = s.rss_bytes;
  std::copy(s.bad_messages.begin(), s.bad_messages.end(), m.bad_messages);  // same length (bad_kind_indices.cpp)
  m.unsaved_records = s.unsaved_records;
  m.queue_drops = s.queue_drops;
  m.keyframes_requested = s.keyframes_requested;
  m.keyframes_recovered = s.keyframes_recovered;
  m.keyframes_lost = s.keyframes_lost;
  m.bus = s.bus;
  m.sender = s.sender;
  m.process = s.process;
  m.detail = s.detail;
  m.robot = s.robot;
  return m;
}

}  // namespace cvo::lcm
