#pragma once
// A session's recent keyframes as the odometry has them: each one's pose P_k and covariance
// Σ_O(k), so that a frame's map pose covariance can be composed from the back end's covariance of
// one keyframe's map pose and the odometry since it (pose_covariance.hpp, map_pose_covariance).
// Fixed capacity, no allocation: the tracking thread keeps it. The back end names the keyframe of
// its newest word, which is among the tracker's last few; an older one (no longer held) gives none.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "libcvo/core/se3.hpp"

namespace cvo::odometry {

class KeyframeCovariances {
 public:
  static constexpr std::size_t kCapacity = 64;

  void clear() { entries_.fill({}); }
  /// Keyframe `id` (of the running session) at odometry pose `pose` with covariance `covariance`.
  void add(std::int64_t id, const core::SE3& pose, const core::Matrix6d& covariance);
  /// Σ_map(n) of a frame at odometry pose `frame_pose` with covariance `frame_covariance`, from the
  /// back end's covariance of keyframe `id`'s map pose; nullopt when keyframe `id` is not held.
  [[nodiscard]] std::optional<core::Matrix6d> map_pose_covariance(std::int64_t id,
                                                                  const core::Matrix6d& keyframe_map_covariance,
                                                                  const core::SE3& frame_pose,
                                                                  const core::Matrix6d& frame_covariance) const;

 private:
  struct Entry {
    std::int64_t id = -1;
    core::SE3 pose;
    core::Matrix6d covariance = core::Matrix6d::Zero();
  };
  std::array<Entry, kCapacity> entries_{};
};

}  // namespace cvo::odometry
