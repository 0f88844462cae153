#include "libcvo/odometry/smooth_position.hpp"

#include <cmath>

#include <Eigen/Cholesky>

namespace cvo::odometry {
namespace {

// The window over which σ_a² is averaged. It only has to span several frames and stay short next
// to a change of gait; 0.5 s and 2 s give the same one-frame figures (bench/odometry-tuning.md).
constexpr double kAccelerationWindow_s = 1.0;

using Matrix3d = Eigen::Matrix3d;
using Vector3d = Eigen::Vector3d;

// Starts the filter at frame n (the tracked pose published as it is).
SmoothStep restart(SmoothPosition& state, double timestamp, const core::SE3& tracked,
                   const std::optional<core::Matrix6d>& relative) {
  state = SmoothPosition{};
  state.last_position = tracked.translation();
  state.last_time = timestamp;
  state.measured = 1;
  return {tracked, relative};
}

// F and the white-acceleration Q of one interval Δt.
core::Matrix6d transition(double dt) {
  core::Matrix6d F = core::Matrix6d::Identity();
  F.topRightCorner<3, 3>() = dt * Matrix3d::Identity();
  return F;
}

core::Matrix6d process_noise(double acceleration_variance, double dt) {
  core::Matrix6d Q;
  const Matrix3d I = Matrix3d::Identity();
  Q << dt * dt * dt * dt / 4 * I, dt * dt * dt / 2 * I, dt * dt * dt / 2 * I, dt * dt * I;
  return acceleration_variance * Q;
}

}  // namespace

SmoothStep smooth(SmoothPosition& state, double timestamp, const core::SE3& tracked,
                  const std::optional<core::Matrix6d>& relative) {
  const double dt = timestamp - state.last_time;
  if (!relative || state.measured == 0 || !(dt > 0)) return restart(state, timestamp, tracked, relative);
  const Vector3d p = tracked.translation();
  const Matrix3d Rn = tracked.rotation_matrix();
  const Matrix3d R = Rn * relative->topLeftCorner<3, 3>() * Rn.transpose();  // measurement noise, odometry frame
  const Vector3d v = (p - state.last_position) / dt;
  if (state.measured == 1) {  // the second frame: position and velocity from the two measurements
    state.x << p, v;
    state.P << R, R / dt, R / dt, 2 * R / (dt * dt);
  } else {
    const Vector3d a = (v - state.last_velocity) / (0.5 * (dt + state.last_dt));
    const double sample = a.squaredNorm() / 3;
    state.acceleration_variance = state.measured == 2
                                      ? sample
                                      : state.acceleration_variance + (1 - std::exp(-dt / kAccelerationWindow_s)) *
                                                                          (sample - state.acceleration_variance);
    const core::Matrix6d F = transition(dt);
    const core::Matrix6d P_last = state.P;
    const core::Matrix6d P_prior = F * P_last * F.transpose() + process_noise(state.acceleration_variance, dt);
    const Eigen::Matrix<double, 6, 1> x_prior = F * state.x;
    const Matrix3d S = P_prior.topLeftCorner<3, 3>() + R;
    const Eigen::Matrix<double, 6, 3> K = S.ldlt().solve(P_prior.leftCols<3>().transpose()).transpose();
    core::Matrix6d I_KH = core::Matrix6d::Identity();
    I_KH.leftCols<3>() -= K;
    const Eigen::Matrix<double, 6, 1> x = x_prior + K * (p - x_prior.head<3>());
    core::Matrix6d P = I_KH * P_prior;
    P = 0.5 * (P + P.transpose()).eval();
    if (!x.allFinite() || !P.allFinite()) return restart(state, timestamp, tracked, relative);
    // The smooth increment's covariance (see the header), in frame n's axes.
    const Matrix3d C = (I_KH * F * P_last).topLeftCorner<3, 3>();
    const Matrix3d increment = P.topLeftCorner<3, 3>() + P_last.topLeftCorner<3, 3>() - C - C.transpose();
    state.x = x;
    state.P = P;
    core::Matrix6d published = *relative;
    const Matrix3d in_frame_n = Rn.transpose() * increment * Rn;
    published.topLeftCorner<3, 3>() = 0.5 * (in_frame_n + in_frame_n.transpose());
    published.topRightCorner<3, 3>().setZero();
    published.bottomLeftCorner<3, 3>().setZero();
    state.last_velocity = v, state.last_dt = dt, state.last_position = p, state.last_time = timestamp;
    state.measured = 3;  // filtering: only 0, 1, 2 and more are told apart
    return {core::SE3(tracked.rotation(), x.head<3>()), published};
  }
  state.last_velocity = v, state.last_dt = dt, state.last_position = p, state.last_time = timestamp;
  ++state.measured;
  return {tracked, relative};
}

}  // namespace cvo::odometry
