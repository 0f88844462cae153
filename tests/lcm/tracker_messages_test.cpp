// The messages cvo-trackerd builds about itself (lcm/tracker_messages.hpp), without LCM: CVO_POSE
// from a tracked frame, CVO_STATUS from counters, and the state those counters mean.
#include <gtest/gtest.h>

#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "libcvo/lcm/tracker_messages.hpp"
#include "tests/lcm/sample_messages.hpp"

namespace cvo::lcm {
namespace {

TEST(TrackerMessages, PoseMessageCarriesTheTrackedFrame) {
  TrackedPose p;
  p.frame_index = 41;
  p.keyframe_id = 3;
  p.timestamp = 1305031102.175304;
  p.odom_pose = core::SE3::from_translation({0.5, -0.25, 2});
  p.map_pose = core::SE3::from_translation({1.5, -0.25, 2});
  p.map_placed = true;
  p.covariance(2, 3) = 0.125;
  p.status = odometry::TrackStatus::kRegistrationFailed;
  p.is_keyframe = true;
  p.inner_product = 0.75;
  p.gamma_keyframe = 0.5;
  p.iterations = 17;
  p.points = 4321;
  const cvo_lcm::pose_t m = pose_message(0x5e55, "hall-a", p, 12.5);
  EXPECT_EQ(m.version, cvo_lcm::pose_t::SCHEMA_VERSION);
  EXPECT_EQ(m.session, 0x5e55);
  EXPECT_EQ(m.utime, 1305031102175304);
  EXPECT_EQ(m.frame_index, 41);
  EXPECT_EQ(m.keyframe_id, 3);
  EXPECT_EQ(m.odom_pose.position[2], 2);
  EXPECT_EQ(m.map_pose.position[0], 1.5);
  EXPECT_TRUE(m.map_placed);
  EXPECT_EQ(m.covariance[2 * 6 + 3], 0.125);
  EXPECT_EQ(m.status, +cvo_lcm::pose_t::STATUS_REGISTRATION_FAILED);
  EXPECT_TRUE(m.is_keyframe);
  EXPECT_EQ(m.inner_product, 0.75);
  EXPECT_EQ(m.gamma_keyframe, 0.5);
  EXPECT_EQ(m.iterations, 17);
  EXPECT_EQ(m.points, 4321);
  EXPECT_EQ(m.latency_ms, 12.5);
  EXPECT_EQ(m.robot, "hall-a");
  // What goes on the wire decodes with the checking decoder.
  const auto bytes = encode(m);
  std::string error;
  EXPECT_TRUE(decode<cvo_lcm::pose_t>(bytes.data(), static_cast<int>(bytes.size()), &error)) << error;

  EXPECT_EQ(to_pose_status(odometry::TrackStatus::kOk), +cvo_lcm::pose_t::STATUS_OK);
  EXPECT_EQ(to_pose_status(odometry::TrackStatus::kFirstFrame), +cvo_lcm::pose_t::STATUS_FIRST_FRAME);
  EXPECT_EQ(to_pose_status(odometry::TrackStatus::kSelectionFailed), +cvo_lcm::pose_t::STATUS_SELECTION_FAILED);
}

TEST(TrackerMessages, PoseMessageSaysTheSessionsStateItsMapAndBothCovariances) {
  TrackedPose p;
  p.state = core::LocalizationState::kLocalized;
  p.since_match_s = 0.75;
  p.map_epoch = 1000;
  p.map_revision = 12;
  p.relative_covariance = core::Matrix6d::Identity() * 1e-6;
  cvo_lcm::pose_t m = pose_message(1, "r", p, 0);
  EXPECT_EQ(m.state, +cvo_lcm::pose_t::STATE_LOCALIZED);
  EXPECT_EQ(m.since_match_s, 0.75);
  EXPECT_EQ(m.map_epoch, 1000);
  EXPECT_EQ(m.map_revision, 12);
  EXPECT_TRUE(m.has_map_pose);
  EXPECT_TRUE(m.has_relative_covariance);
  EXPECT_EQ(m.relative_covariance[5 * 6 + 5], 1e-6);
  // Before it is localized: no time since a match; without a map pose when the tracker is told so.
  p.state = core::LocalizationState::kLocalizing;
  p.has_map_pose = false;
  p.map_pose = core::SE3::from_translation({3, 0, 0});
  p.relative_covariance.reset();
  m = pose_message(1, "r", p, 0);
  EXPECT_EQ(m.since_match_s, -1);
  EXPECT_FALSE(m.has_map_pose);
  EXPECT_EQ(m.map_pose.position[0], 0) << "no map pose is given";
  EXPECT_FALSE(m.has_relative_covariance);
  p.state = core::LocalizationState::kLost;
  EXPECT_EQ(pose_message(1, "r", p, 0).state, +cvo_lcm::pose_t::STATE_LOST);
}

TEST(TrackerMessages, StatusMessageHoldsEveryCounter) {
  const cvo_lcm::status_t expected = test::sample_status();
  ProcessStatus s;
  s.process = expected.process;
  s.session = expected.session;
  s.utime = expected.utime;
  s.pid = expected.pid;
  s.state = expected.state;
  s.rate_hz = expected.rate_hz;
  s.latency_median_ms = expected.latency_median_ms;
  s.latency_p99_ms = expected.latency_p99_ms;
  s.deadline_misses = expected.deadline_misses;
  s.dropped_frames = expected.dropped_frames;
  s.failed_frames = expected.failed_frames;
  s.source_gaps = expected.source_gaps;
  s.allocations_after_warmup = expected.allocations_after_warmup;
  s.queue_depth = expected.queue_depth;
  s.rss_bytes = expected.rss_bytes;
  for (int k = 0; k < core::kNumBadKinds; ++k) s.bad_messages[static_cast<std::size_t>(k)] = expected.bad_messages[k];
  s.unsaved_records = expected.unsaved_records;
  s.queue_drops = expected.queue_drops;
  s.keyframes_requested = expected.keyframes_requested;
  s.keyframes_recovered = expected.keyframes_recovered;
  s.keyframes_lost = expected.keyframes_lost;
  s.detail = expected.detail;
  s.robot = expected.robot;
  EXPECT_EQ(encode(status_message(s)), encode(expected)) << "every field, the last bad kind included";
}

TEST(TrackerMessages, StateFollowsTheActivity) {
  using S = cvo_lcm::status_t;
  EXPECT_EQ(tracker_state({0, true, false, false}), +S::STATE_STARTING);
  EXPECT_EQ(tracker_state({0, false, false, false}), +S::STATE_WAITING_FOR_INPUT);
  EXPECT_EQ(tracker_state({10, false, false, false}), +S::STATE_WAITING_FOR_INPUT) << "source away";
  EXPECT_EQ(tracker_state({10, true, true, false}), +S::STATE_WAITING_FOR_INPUT) << "no frame for a while";
  EXPECT_EQ(tracker_state({10, true, false, true}), +S::STATE_DEGRADED);
  EXPECT_EQ(tracker_state({10, true, false, false}), +S::STATE_RUNNING);
}

}  // namespace
}  // namespace cvo::lcm
