#pragma once
// The back end's newest word on this tracker's session: whether it places it in the map, and its
// correction T_map_odom, so that a frame's map pose is T_map_odom · T_odom_camera. The publisher
// thread sets it from each CVO_MAP_CORRECTION or CVO_MAP it applies (the entry of the session the
// tracker runs); the
// tracking thread reads it for every frame. It is keyed by session: a map that was decoded for a
// session the tracker has just left (a camera re-initialisation) never places the new one. A plain
// mutex: the critical sections are a copy of a few words, and the reader never waits for a
// computation.
#include <cstdint>
#include <mutex>
#include <optional>

#include "libcvo/core/se3.hpp"

namespace cvo::daemon::trackerd {

struct MapPlacement {
  core::SE3 T_map_odom;  // identity while not placed: map pose = odometry pose
  bool placed = false;
  std::int64_t epoch = -1, revision = -1;             // of the map it came from (-1: none)
  double last_match_time = -1;                        // sensor time of the newest verified match (-1: none)
  std::optional<core::Matrix6d> keyframe_covariance;  // of keyframe covariance_keyframe's map pose
  std::int64_t covariance_keyframe = -1;
};

class MapCorrection {
 public:
  void set(std::int64_t session, const MapPlacement& placement) {
    const std::lock_guard lock(mutex_);
    session_ = session;
    placement_ = placement;
  }
  /// The placement of `session`: not placed until a map placed it.
  [[nodiscard]] MapPlacement get(std::int64_t session) const {
    const std::lock_guard lock(mutex_);
    return session_ == session ? placement_ : MapPlacement{};
  }

 private:
  mutable std::mutex mutex_;
  std::int64_t session_ = 0;  // 0 is never a session
  MapPlacement placement_;
};

}  // namespace cvo::daemon::trackerd
