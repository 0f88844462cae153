#pragma once
// The messages cvo-trackerd publishes about itself, built from plain values without LCM or threads,
// so that the daemon's threads only move data and what goes on the wire is unit-tested:
// CVO_POSE from a tracked frame, CVO_STATUS from the process's counters (and the state they
// mean). CVO_MAP is map_conversion.hpp's to_message (cvo::lcm_map); what a received CVO_MAP does is
// map_decision.hpp's.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "cvo_lcm/pose_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "libcvo/core/bad_kind.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/odometry/track_result.hpp"

namespace cvo::lcm {

/// One tracked frame, as CVO_POSE carries it (map_pose = T_map_odom · odom_pose when placed;
/// proto/pose_t.lcm says what each field means).
struct TrackedPose {
  std::int64_t frame_index = 0;  // in its session
  std::int64_t keyframe_id = -1;
  double timestamp = 0;  // the frame's colour stamp
  core::SE3 odom_pose, map_pose;
  bool map_placed = false;                         // map_pose is in the map frame (CVO_MAP placed the session)
  bool has_map_pose = true;                        // false: map_pose not given
  std::int64_t map_epoch = -1, map_revision = -1;  // of the CVO_MAP applied (-1: none)
  core::LocalizationState state = core::LocalizationState::kLocalizing;
  double since_match_s = -1;                               // LOCALIZED: sensor time since the last verified match
  core::Matrix6d covariance = core::Matrix6d::Identity();  // of map_pose
  std::optional<core::Matrix6d> relative_covariance;       // of odom_pose_{n-1}^-1 · odom_pose_n
  odometry::TrackStatus status = odometry::TrackStatus::kOk;
  bool is_keyframe = false;
  double inner_product = 0, gamma_keyframe = 0;
  int iterations = 0, points = 0;
};

/// pose_t's STATUS_* for a tracking outcome.
std::int8_t to_pose_status(odometry::TrackStatus status);

/// CVO_POSE of `pose` in `session` of `robot`, latency_ms from the frame's arrival to now.
cvo_lcm::pose_t pose_message(std::int64_t session, std::string_view robot, const TrackedPose& pose, double latency_ms);

/// What a tracker's state in CVO_STATUS is made of.
struct TrackerActivity {
  std::int64_t published = 0;  // poses published so far
  bool source_connected = false;
  bool idle = false;                 // no pose for a while
  bool failures_since_last = false;  // frames failed since the previous status
};
/// STATE_STARTING until the first pose (STATE_WAITING_FOR_INPUT while no source), then
/// WAITING_FOR_INPUT (source away or idle), DEGRADED (failures since the last status) or RUNNING.
std::int8_t tracker_state(const TrackerActivity& activity);

/// The fields of a CVO_STATUS (status_t's comments say what each means).
struct ProcessStatus {
  std::string process;
  std::int64_t session = 0;
  std::int64_t utime = 0;
  std::int32_t pid = 0;
  std::int8_t state = cvo_lcm::status_t::STATE_STARTING;
  double rate_hz = 0, latency_median_ms = 0, latency_p99_ms = 0;
  std::int64_t deadline_misses = 0, dropped_frames = 0, failed_frames = 0, source_gaps = 0;
  std::int64_t allocations_after_warmup = 0;
  std::int32_t queue_depth = 0;
  std::int64_t rss_bytes = 0;
  std::array<std::int64_t, core::kNumBadKinds> bad_messages{};  // by core::BadKind
  std::int64_t unsaved_records = 0, queue_drops = 0;
  std::int64_t keyframes_requested = 0, keyframes_recovered = 0, keyframes_lost = 0;
  std::int8_t bus = cvo_lcm::status_t::BUS_OPEN;  // BUS_AUTHENTICATED when it signs and verifies
  std::int64_t sender = 0;                        // its auth_t sender id
  std::string detail;
  std::string robot;  // the tracker's robot, the back end's host
};

cvo_lcm::status_t status_message(const ProcessStatus& status);

}  // namespace cvo::lcm
