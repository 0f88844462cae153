#include "libcvo/odometry/motion_redundancy.hpp"

#include <cmath>

namespace cvo::odometry {
namespace {

constexpr double kPriorJitterS = 0.001;  // σ_τ before the stamps say otherwise
constexpr double kPriorStamps = 2;       // its weight, in second differences

}  // namespace

double StampJitter::variance() const {
  return (squares / 6 + kPriorStamps * kPriorJitterS * kPriorJitterS) / (counted + kPriorStamps);
}

void add_stamp(StampJitter& jitter, double timestamp) {
  if (!std::isfinite(timestamp)) return;
  if (jitter.stamps == 2) {
    const double interval = timestamp - jitter.previous[0];
    const double second = interval - (jitter.previous[0] - jitter.previous[1]);
    if (interval > 0 && std::abs(second) < 0.5 * interval) {  // not across a dropped frame
      jitter.squares += second * second;
      jitter.counted += 1;
    }
  }
  jitter.previous[1] = jitter.previous[0];
  jitter.previous[0] = timestamp;
  if (jitter.stamps < 2) ++jitter.stamps;
}

std::optional<core::Matrix6d> publish_relative(MotionRedundancy& state, const core::SE3& increment, double dt,
                                               const std::optional<core::Matrix6d>& relative) {
  const core::Vector6d xi = increment.log();
  if (!relative || !(dt > 0) || !xi.allFinite()) {
    state.history = 0;
    return relative;
  }
  const core::Vector6d rate = xi / dt;
  const core::Matrix6d sigma = *relative + 2 * state.jitter.variance() * rate * rate.transpose();
  if (state.history == 3) {
    const auto& x = state.increments;
    const auto& s = state.covariances;
    const core::Vector6d delta = xi - 3 * x[0] + 3 * x[1] - x[2];
    add_disagreement(state.factor, disagreement_chi2(delta, sigma + 9 * s[0] + 9 * s[1] + s[2]));
  }
  for (int k = 2; k > 0; --k) {
    state.increments[k] = state.increments[k - 1];
    state.covariances[k] = state.covariances[k - 1];
  }
  state.increments[0] = xi;
  state.covariances[0] = sigma;
  if (state.history < 3) ++state.history;
  return state.factor.value() * sigma;
}

}  // namespace cvo::odometry
