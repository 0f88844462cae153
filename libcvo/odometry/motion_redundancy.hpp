#pragma once
// The published relative pose's covariance, completed with what a frame's registrations share.
//
// variance_factor.hpp's redundancy (keyframe edge against chain) cannot see an error that moves
// both registrations of a frame alike: the sensor's timing (colour-depth offset, rolling-shutter
// readout), anything that displaces a whole image. The camera's motion can. At 30 Hz it is smooth
// to third order (a shaken hand's jerk moves a pose by a fraction of a millimetre over three
// intervals), so the third difference of the published increments ξ_k = log(T_{k-1}^k),
//   δ_n = ξ_n − 3 ξ_{n-1} + 3 ξ_{n-2} − ξ_{n-3},
// is their errors' alone. With errors independent from frame to frame and covariances Σ_k that
// are right, δ_n ~ N(0, C), C = Σ_n + 9 Σ_{n-1} + 9 Σ_{n-2} + Σ_{n-3} (the increments' tangent
// frames differ by one frame's motion: first order), so χ² = δᵀ C⁻¹ δ averages 6, and the ratio
// seen is a second variance factor, estimated as variance_factor.hpp's (mean with a prior, each
// frame capped). A frame's own offset enters two increments with opposite signs; such errors make
// δ larger than C says, so the factor errs toward more uncertainty, not less.
//
// The stamps. An increment between stamps that err by ε_{n-1}, ε_n is the motion of another
// interval: its error ξ̇ (ε_n − ε_{n-1}), covariance 2 σ_τ² ξ̇ ξ̇ᵀ with ξ̇ = ξ_n / Δt_n (rank one,
// along the motion). σ_τ comes from the stamps themselves: a camera's frame clock is periodic, so
// the second difference of the stamps t_n − 2 t_{n-1} + t_{n-2} = ε_n − 2 ε_{n-1} + ε_{n-2} has
// variance 6 σ_τ² whatever the period; one beyond half an interval (a dropped frame) is not
// counted. Before the stamps say otherwise (a session's first frames, when a fast first motion
// would be published as certain to the microsecond) σ_τ is a host-stamped USB camera's
// millisecond, a prior of kPriorStamps stamps (motion_redundancy.cpp); exact stamps (rendered,
// hardware-timed) take it towards 0 within a second.
//
// Published: Σ_rel' = k (Σ_rel + 2 σ_τ² ξ̇ ξ̇ᵀ). Only the relative pose's covariance (what an EKF
// fuses as visual odometry): the odometry pose's and the edges the back end weighs keep the
// registrations' one calibration (a frame's offset does not accumulate along the chain, and the
// local graph and loop edges must share one calibration: bench/odometry-tuning.md, "Covariance").
#include <array>
#include <optional>

#include "libcvo/core/se3.hpp"
#include "libcvo/odometry/variance_factor.hpp"

namespace cvo::odometry {

/// The stamps' jitter σ_τ from their second differences, within one session.
struct StampJitter {
  double squares = 0;  // Σ (t_n − 2 t_{n-1} + t_{n-2})² over the counted frames
  double counted = 0;
  std::array<double, 2> previous{};  // t_{n-1}, t_{n-2}
  int stamps = 0;                    // how many of `previous` are set

  /// σ_τ², the prior's until second differences are counted.
  [[nodiscard]] double variance() const;
};

/// The state of one session's motion redundancy: the last three published increments and their
/// covariances (stamps included), the factor and the stamps' jitter.
struct MotionRedundancy {
  std::array<core::Vector6d, 3> increments{};  // ξ_{n-1}, ξ_{n-2}, ξ_{n-3}
  std::array<core::Matrix6d, 3> covariances{};
  int history = 0;  // how many of them follow one another without a gap
  VarianceFactor factor;
  StampJitter jitter;
};

/// Counts one frame's colour stamp (every frame, measured or not).
void add_stamp(StampJitter& jitter, double timestamp);

/// Frame n's published relative covariance from the registrations' `relative` (pose_covariance.hpp)
/// for the increment T_{n-1}^n over `dt` seconds; none stays none and breaks the history. Advances
/// `state` (its stamps are counted by add_stamp, before).
std::optional<core::Matrix6d> publish_relative(MotionRedundancy& state, const core::SE3& increment, double dt,
                                               const std::optional<core::Matrix6d>& relative);

}  // namespace cvo::odometry
