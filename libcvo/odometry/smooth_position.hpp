#pragma once
// The published pose's position through a causal constant-velocity Kalman filter: a pose a
// controller can differentiate (issue 25, item 7).
//
// Each frame's registrations err afresh (which pixels the frame keeps, their depth noise), so the
// tracked position moves by about √2 times that error from frame to frame, while a camera's
// position changes smoothly at 30 Hz. The filter's state is position and velocity in the odometry
// frame, x = [p; v], driven by white acceleration of variance σ_a² per axis:
//
//   predict  x⁻ = F x,  F = [I, Δt I; 0, I],  P⁻ = F P Fᵀ + σ_a² [Δt⁴/4, Δt³/2; Δt³/2, Δt²] ⊗ I
//   update   z = p_n, the tracked position, with noise R = R_n Σ_ρρ R_nᵀ: the tracked relative
//            pose's translation covariance (right perturbation: ρ is in frame n's axes), in the
//            odometry frame.
//
// σ_a² is measured, not tuned: the mean over about a second (an exponential window of
// kAccelerationWindow_s) of |a|²/3, a = (v_n − v_{n-1}) / ((Δt_n + Δt_{n-1}) / 2) from the
// tracked positions' differences. It holds the noise as well as the motion, an upper bound of
// the acceleration, so the filter never assumes a smoother motion than the one it sees: a shaken
// camera gets a filter that follows it, a robot's smooth drive one that smooths.
//
// Rotation is passed through: a hand-held camera's angular velocity changes within a frame by as
// much as one frame's rotation error, and a causal filter of it lags where it does not help
// (bench/odometry-tuning.md, "A smooth published pose").
//
// The published relative covariance is the smooth increment's. Its translation block: the
// errors e_n of consecutive estimates are correlated, Cov(e_n, e_{n-1}) = C = (I − K H) F P_{n-1},
// so Cov(e_n − e_{n-1}) = P_n + P_{n-1} − C − Cᵀ (position blocks), in frame n's axes R_nᵀ (·) R_n;
// its rotation block is the tracked relative pose's, the cross terms 0 (the filter's position no
// longer moves with the registration's rotation error; what is left is below a tenth of a
// millimetre a frame).
//
// Only the published pose is filtered: keyframes, local graphs and the compensations' velocity
// keep the tracked pose (a filter inside the loop would feed its lag back into the registrations).
// A frame without a measured motion (a session's first frame, a restart, a failure) starts the
// filter again at the tracked pose; the published pose then moves to it by the filter's last
// correction (millimetres). The filter follows from the third measured frame on (one acceleration
// is needed); before that it publishes the tracked position.
#include <optional>

#include "libcvo/core/se3.hpp"

namespace cvo::odometry {

/// One session's filter state (value type; zero-initialised means "no frame yet").
struct SmoothPosition {
  Eigen::Matrix<double, 6, 1> x = Eigen::Matrix<double, 6, 1>::Zero();  // [p; v], odometry frame
  core::Matrix6d P = core::Matrix6d::Zero();
  double acceleration_variance = 0;  // σ_a², per axis
  double last_time = 0;
  Eigen::Vector3d last_position = Eigen::Vector3d::Zero();  // tracked p_{n-1}
  Eigen::Vector3d last_velocity = Eigen::Vector3d::Zero();  // tracked (p_{n-1} − p_{n-2}) / Δt_{n-1}
  double last_dt = 0;
  int measured = 0;  // frames since the filter started: 0 not started, 1, 2, 3 filtering
};

/// What the filter publishes for one frame.
struct SmoothStep {
  core::SE3 pose;                          // the tracked rotation, the filtered position
  std::optional<core::Matrix6d> relative;  // covariance of the smooth relative pose T_{n-1}^n
};

/// Frame n (colour stamp `timestamp`, tracked pose `tracked`, the tracked relative pose's
/// covariance `relative`, none for a frame without a measured motion) through the filter.
SmoothStep smooth(SmoothPosition& state, double timestamp, const core::SE3& tracked,
                  const std::optional<core::Matrix6d>& relative);

}  // namespace cvo::odometry
