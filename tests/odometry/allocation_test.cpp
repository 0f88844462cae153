// After warm-up, FrameToFrameOdometry::track() must not touch the heap: the tracker runs it in a
// realtime thread. This binary links program/allocation_counter.cpp (counts operator new);
// the frames are rendered before counting starts.
#include <new>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/odometry/frame_to_frame.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"
#include "program/allocation_counter.hpp"
#include "tests/odometry/odometry_fixtures.hpp"

using cvo::program::process_allocations;

namespace cvo::odometry {
namespace {

TEST(OdometryAllocation, CountingWorks) {
  const auto before = process_allocations();
  void* p = ::operator new(16);  // an explicit call: a new-expression pair may be elided
  ::operator delete(p);
  EXPECT_EQ(process_allocations() - before, 1);
}

TEST(OdometryAllocation, TrackAllocatesNothingAfterWarmUp) {
  auto s = testing::render_path(sim::PathKind::orbit, 7);
  core::RgbdFrame empty;  // a selection failure
  empty.index = 4;
  FrameToFrameParameters parameters;
  parameters.initial_pose = s.truth[0].pose;
  FrameToFrameOdometry odometry(s.frames[0].intrinsics.width, s.frames[0].intrinsics.height, parameters);
  odometry.track(s.frames[0]);  // warm-up: first calls may touch lazily initialised library state
  odometry.track(s.frames[1]);

  // Normal frames, a frame without images, and an index gap (frame 5 after the empty frame 4).
  long allocations = 0;
  int tracked = 0;
  for (const core::RgbdFrame* frame : {&s.frames[2], &s.frames[3], &empty, &s.frames[5], &s.frames[6]}) {
    const auto before = process_allocations();
    const TrackResult r = odometry.track(*frame);
    allocations += process_allocations() - before;
    tracked += r.status == TrackStatus::kOk;
  }
  EXPECT_EQ(tracked, 4);
  EXPECT_EQ(allocations, 0) << "heap allocations in track()";
}

TEST(OdometryAllocation, KeyframeTrackAllocatesNothingAfterWarmUp) {
  // Keyframes are made (t_thres 2 cm), local graphs close and a failure restarts tracking: every
  // path of KF-CVO, none of which may touch the heap.
  auto s = testing::render_path(sim::PathKind::orbit, 9);
  core::RgbdFrame empty;
  empty.index = 5;
  KeyframeOdometryParameters parameters;
  parameters.initial_pose = s.truth[0].pose;
  parameters.keyframe.translation_threshold_m = 0.02;
  KeyframeOdometry odometry(s.frames[0].intrinsics.width, s.frames[0].intrinsics.height, parameters);
  odometry.track(s.frames[0]);  // warm-up
  odometry.track(s.frames[1]);
  odometry.track(s.frames[2]);

  long allocations = 0;
  int keyframes = 0, closed = 0;
  for (const core::RgbdFrame* frame : {&s.frames[3], &s.frames[4], &empty, &s.frames[6], &s.frames[7], &s.frames[8]}) {
    const auto before = process_allocations();
    const TrackStep r = odometry.track(*frame);
    allocations += process_allocations() - before;
    keyframes += r.keyframe;
    closed += r.closed_graph.has_value();
  }
  EXPECT_GE(keyframes, 2);
  EXPECT_GE(closed, 1);
  EXPECT_EQ(allocations, 0) << "heap allocations in KeyframeOdometry::track()";
}

// A camera re-initialisation starts a new session: after reset() the tracker behaves exactly as a
// new one on the same frames (first frame at the initial pose, same poses bit for bit), and
// neither reset() nor the new session's frames touch the heap.
TEST(OdometryAllocation, KeyframeResetStartsOverWithoutAllocating) {
  auto s = testing::render_path(sim::PathKind::orbit, 6);
  KeyframeOdometryParameters parameters;
  parameters.initial_pose = s.truth[0].pose;
  parameters.keyframe.translation_threshold_m = 0.02;
  KeyframeOdometry odometry(s.frames[0].intrinsics.width, s.frames[0].intrinsics.height, parameters);
  std::vector<core::SE3> first;
  int keyframes = 0;
  for (const auto& frame : s.frames) {
    const TrackResult r = odometry.track(frame);
    first.push_back(r.pose);
    keyframes += r.keyframe;
  }
  ASSERT_GE(keyframes, 2) << "the first session moved past its first keyframe";

  const auto before = process_allocations();
  odometry.reset();
  auto allocations = process_allocations() - before;
  for (std::size_t i = 0; i < s.frames.size(); ++i) {
    const auto start = process_allocations();
    const TrackStep r = odometry.track(s.frames[i]);
    allocations += process_allocations() - start;
    if (i == 0) {
      EXPECT_EQ(r.status, TrackStatus::kFirstFrame);
      EXPECT_TRUE(r.keyframe);
      EXPECT_EQ(r.reason, KeyframeReason::kFirst);
      EXPECT_FALSE(r.closed_graph) << "the old session's graph is not handed out again";
      ASSERT_TRUE(r.new_keyframe);
      EXPECT_EQ(r.new_keyframe->id, 0) << "keyframe ids count from 0 again";
    }
    EXPECT_TRUE((r.pose.matrix().array() == first[i].matrix().array()).all()) << "frame " << i;
  }
  EXPECT_EQ(allocations, 0) << "heap allocations in reset() and the new session's track()";
}

}  // namespace
}  // namespace cvo::odometry
