#include "libcvo/odometry/keyframe_covariances.hpp"

#include "libcvo/odometry/pose_covariance.hpp"

namespace cvo::odometry {

void KeyframeCovariances::add(std::int64_t id, const core::SE3& pose, const core::Matrix6d& covariance) {
  if (id < 0) return;
  entries_[static_cast<std::size_t>(id) % kCapacity] = {id, pose, covariance};
}

std::optional<core::Matrix6d> KeyframeCovariances::map_pose_covariance(std::int64_t id,
                                                                       const core::Matrix6d& keyframe_map_covariance,
                                                                       const core::SE3& frame_pose,
                                                                       const core::Matrix6d& frame_covariance) const {
  if (id < 0) return std::nullopt;
  const Entry& k = entries_[static_cast<std::size_t>(id) % kCapacity];
  if (k.id != id) return std::nullopt;
  return odometry::map_pose_covariance(keyframe_map_covariance, k.covariance, frame_covariance,
                                       k.pose.inverse() * frame_pose);
}

}  // namespace cvo::odometry
