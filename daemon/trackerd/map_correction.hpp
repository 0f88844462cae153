#pragma once
// The back end's newest correction of the odometry: T_map_odom, so that a frame's map pose is
// T_map_odom · T_odom_camera. The publisher thread computes it from each CVO_MAP (the newest
// keyframe the map and this tracker both know: T_map_odom = P_map(k) · P_odom(k)^-1); the
// tracking thread reads it for every frame. A plain mutex: the critical sections are a copy of
// 7 doubles, and the reader never waits for a computation.
#include <mutex>

#include "libcvo/core/se3.hpp"

namespace cvo::daemon::trackerd {

class MapCorrection {
 public:
  void set(const core::SE3& T_map_odom) {
    const std::lock_guard lock(mutex_);
    T_map_odom_ = T_map_odom;
  }
  [[nodiscard]] core::SE3 get() const {
    const std::lock_guard lock(mutex_);
    return T_map_odom_;
  }

 private:
  mutable std::mutex mutex_;
  core::SE3 T_map_odom_;  // identity until the first map
};

}  // namespace cvo::daemon::trackerd
