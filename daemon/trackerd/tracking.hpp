#pragma once
// cvo-track: FrameRing -> KF-CVO (odometry::KeyframeOdometry) -> Outbox, one event per frame: its
// pose (the map pose once the back end places the session), and the local graph it closed and the
// keyframe it made, copied into the outbox's preallocated slots. SCHED_FIFO and pinned when
// configured; after warm-up it does not allocate (counted: allocations_after_warmup).
//
// A keyframe made at frame n is frame n-1: the tracker shares that frame's images with the ring
// slot it came in, so the slot goes back one frame later (FrameRing::end_read), and only a
// keyframe's images are copied, once, into the outbox.
//
// Sessions: a new connection of the source (a camera back after a disconnection) or another
// camera for trackerd.camera_change_frames frames in a row starts a new session: the old one's
// open local graph goes out first (KeyframeOdometry::finish), then frame indices and keyframe ids
// count from 0. A lone frame of another camera is refused as bad content and changes nothing.
#include <cstddef>
#include <cstdint>
#include <memory>

#include "daemon/trackerd/shared.hpp"
#include "libcvo/odometry/keyframe_covariances.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"

namespace cvo::daemon::trackerd {

class Tracking {
 public:
  explicit Tracking(Shared& shared)
      : shared_(shared), odometry_until_localized_(shared.config.trackerd.map_pose_until_localized == "odometry") {}
  void run();  // the thread's body: until the ring is closed and drained

 private:
  bool start(const core::RgbdFrame& first);
  bool accept_camera(const core::RgbdFrame& frame);
  void change_camera(const core::RgbdFrame& first);
  void follow_connection(const RingSlot& slot);
  void track(const RingSlot& slot, Event& event);
  void hand_over(const odometry::TrackStep& step, Event& event);
  core::Matrix6d map_pose_covariance(const core::RgbdFrame& frame, const odometry::TrackStep& step,
                                     const MapPlacement& placement);
  void end_session();
  void start_new_session();
  void count_allocations();

  Shared& shared_;
  const bool odometry_until_localized_;                  // trackerd.map_pose_until_localized, read once
  core::Intrinsics camera_;                              // of the frames tracked
  std::unique_ptr<odometry::KeyframeOdometry> tracker_;  // sized by the camera
  Outbox* outbox_ = nullptr;                             // shared_.out's, once made
  std::int64_t session_frames_ = 0;                      // frames tracked in the running session
  std::uint64_t connection_ = 0;                         // the source connection they came from (RingSlot::connection)
  std::uint64_t first_index_ = 0;                        // acquisition's index of the session's first frame
  core::Intrinsics other_camera_;                        // another camera's frames, in a row: other_frames_ of them
  std::size_t other_frames_ = 0;
  // Warm-up, again after a camera change: allocations are defects from warmup_frames frames on.
  std::int64_t warm_frames_ = 0, allocations_at_warmup_ = 0, defects_before_ = 0;
  // The running session's recent keyframes (pose, covariance) and the last frame's covariance, for
  // the map pose's covariance.
  odometry::KeyframeCovariances keyframe_covariances_;
  core::Matrix6d previous_odometry_covariance_ = core::Matrix6d::Zero();
};

}  // namespace cvo::daemon::trackerd
