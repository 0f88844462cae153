#pragma once
// What a KF-CVO run hands to a back end after each frame, worked out in one place for every caller
// (cvo-trackerd, cvo-run --mode slam): the local graph that just closed, named by its keyframe's
// id, and the new keyframe with its id, images and odometry pose.
//
// The paper's rule: a keyframe made at frame n is frame n-1 (the last frame that still matched the
// old keyframe); the first frame and a tracking restart make frame n itself. So the previous frame
// is kept, copied into images allocated once (copyTo into a same-sized image allocates nothing:
// fit for the tracker's realtime thread). Keyframe ids count from 0 in every session (reset()).
#include <cstdint>
#include <optional>

#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"
#include "libcvo/odometry/local_graph.hpp"
#include "libcvo/odometry/track_result.hpp"

namespace cvo::odometry {

struct KeyframeStep {
  const LocalGraph* closed_graph = nullptr;  // the tracker's, valid until its next track()
  std::int64_t closed_graph_keyframe = -1;   // its keyframe's id
  const core::RgbdFrame* keyframe = nullptr; // the new keyframe's frame: `frame` or the kept previous one
  std::int64_t keyframe_id = -1;
  core::SE3 keyframe_pose;                   // T_odom_keyframe (the new local graph's anchor)
};

class KeyframeOutput {
 public:
  KeyframeOutput(int width, int height);

  /// Call right after `result = tracker.track(frame)`. The step's pointers are valid until the
  /// next keep() (the previous frame) or track() (the graph).
  [[nodiscard]] KeyframeStep after_track(const KeyframeOdometry& tracker, const TrackResult& result,
                                         const core::RgbdFrame& frame);
  /// Keeps `frame` as the previous one (after the step has been used).
  void keep(const core::RgbdFrame& frame);
  /// A new session: ids from 0 again, no previous frame.
  void reset();

  /// The current keyframe's id (-1 before the first).
  [[nodiscard]] std::int64_t keyframe_id() const { return keyframe_id_; }

 private:
  core::RgbdFrame previous_;
  bool have_previous_ = false;
  std::int64_t keyframe_id_ = -1;
};

}  // namespace cvo::odometry
