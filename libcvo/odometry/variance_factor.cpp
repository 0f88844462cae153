#include "libcvo/odometry/variance_factor.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

namespace cvo::odometry {
namespace {

constexpr double kPriorFrames = 10;   // the factor's prior weight, in frames at 1
constexpr double kMaxChi2Ratio = 20;  // a frame's χ²/6 counts at most this times the current factor

}  // namespace

double VarianceFactor::value() const { return (kPriorFrames + chi2_sum) / (kPriorFrames + frames); }

double disagreement_chi2(const core::Vector6d& d, const core::Matrix6d& S) {
  const Eigen::LLT<core::Matrix6d> llt(S);
  if (llt.info() != Eigen::Success) return -1;
  const double chi2 = d.dot(llt.solve(d));
  return std::isfinite(chi2) ? chi2 : -1;
}

void add_disagreement(VarianceFactor& factor, double chi2) {
  if (!(chi2 >= 0) || !std::isfinite(chi2)) return;
  factor.chi2_sum += std::min(chi2 / 6.0, kMaxChi2Ratio * factor.value());
  factor.frames += 1;
}

}  // namespace cvo::odometry
