#include "libcvo/odometry/pose_covariance.hpp"

#include <Eigen/Cholesky>

#include "libcvo/core/information.hpp"

namespace cvo::odometry {
namespace {

core::Matrix6d symmetric(const core::Matrix6d& m) { return 0.5 * (m + m.transpose()); }

// What frame n publishes from T_m^n and its left covariances (relative pose's, fused edge's), and
// the chain advanced to it.
PoseCovariances publish(PoseCovarianceChain& chain, const core::SE3& T_mn, const core::Matrix6d& relative,
                        const core::Matrix6d& fused) {
  PoseCovariances out;
  out.relative = left_to_right(T_mn, relative);
  out.odometry = left_to_right(T_mn, chain.keyframe_odometry + fused);
  chain.previous_fused = symmetric(fused);
  chain.previous_odometry = out.odometry;
  return out;
}

}  // namespace

core::Matrix6d left_to_right(const core::SE3& T, const core::Matrix6d& left) {
  const core::Matrix6d Ad_inv = T.inverse().adjoint();
  return symmetric(Ad_inv * left * Ad_inv.transpose());
}

PoseCovariances track_against_keyframe(PoseCovarianceChain& chain, const core::SE3& T_mn,
                                       const core::Matrix6d& keyframe_covariance,
                                       const core::Matrix6d& keyframe_information,
                                       const std::optional<ChainTerm>& chain_term) {
  core::Matrix6d K_c = core::Matrix6d::Zero(), chain_part = core::Matrix6d::Zero();
  if (chain_term) {
    const core::Matrix6d H = keyframe_information + chain_term->information;
    const core::Matrix6d gain = H.ldlt().solve(chain_term->information);
    if (gain.allFinite()) K_c = gain;
    const core::Matrix6d Ad = chain_term->T_m_previous.adjoint();
    chain_part = K_c * (Ad * chain_term->covariance * Ad.transpose()) * K_c.transpose();
  }
  const core::Matrix6d K_kf = core::Matrix6d::Identity() - K_c;
  const core::Matrix6d fused =
      K_kf * keyframe_covariance * K_kf.transpose() + K_c * chain.previous_fused * K_c.transpose() + chain_part;
  const core::Matrix6d innovation = K_kf * (keyframe_covariance + chain.previous_fused) * K_kf.transpose() + chain_part;
  return publish(chain, T_mn, innovation, fused);
}

PoseCovariances track_from_new_keyframe(PoseCovarianceChain& chain, const core::SE3& T_f,
                                        const core::Matrix6d& frame_covariance) {
  chain.keyframe_odometry = chain.previous_odometry;
  return publish(chain, T_f, frame_covariance, frame_covariance);
}

PoseCovariances track_unmeasured(PoseCovarianceChain& chain, bool first, bool starts_keyframe) {
  if (first) chain = PoseCovarianceChain{};
  if (starts_keyframe) {
    chain.keyframe_odometry = chain.previous_odometry;
    chain.previous_fused.setZero();
  }
  PoseCovariances out;
  out.odometry = chain.previous_odometry;
  return out;
}

core::Matrix6d map_pose_covariance(const core::Matrix6d& keyframe_map_cov, const core::Matrix6d& keyframe_odometry_cov,
                                   const core::Matrix6d& frame_odometry_cov, const core::SE3& keyframe_T_frame) {
  const core::Matrix6d since = frame_odometry_cov - left_to_right(keyframe_T_frame, keyframe_odometry_cov);
  const core::Matrix6d odometry_since = since.isZero(0) ? since : core::nearest_information(symmetric(since));
  return symmetric(left_to_right(keyframe_T_frame, keyframe_map_cov) + odometry_since);
}

}  // namespace cvo::odometry
