#include "libcvo/loop_closure/rigid_ransac.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include <Eigen/Geometry>

namespace cvo::loop_closure {
namespace {

// Twice the triangle area below this (m²) is a degenerate minimal set: nearly collinear points
// leave the rotation about their line undetermined.
constexpr double kMinDoubleArea = 1e-4;

bool degenerate(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return (b - a).cross(c - a).norm() < kMinDoubleArea;
}

std::vector<std::size_t> inliers_of(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                                    const core::SE3& T, double threshold) {
  std::vector<std::size_t> inliers;
  const double t2 = threshold * threshold;
  for (std::size_t k = 0; k < src.size(); ++k)
    if ((dst[k] - T * src[k]).squaredNorm() < t2) inliers.push_back(k);
  return inliers;
}

double rms(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst, const core::SE3& T,
           const std::vector<std::size_t>& subset) {
  if (subset.empty()) return 0;
  double sum = 0;
  for (const auto k : subset) sum += (dst[k] - T * src[k]).squaredNorm();
  return std::sqrt(sum / static_cast<double>(subset.size()));
}

}  // namespace

std::optional<core::SE3> fit_rigid(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                                   const std::vector<std::size_t>& subset) {
  if (src.size() != dst.size()) return std::nullopt;
  const std::size_t n = subset.empty() ? src.size() : subset.size();
  if (n < 3) return std::nullopt;
  Eigen::Matrix3Xd s(3, n), d(3, n);
  for (std::size_t c = 0; c < n; ++c) {
    const std::size_t k = subset.empty() ? c : subset[c];
    s.col(static_cast<Eigen::Index>(c)) = src[k];
    d.col(static_cast<Eigen::Index>(c)) = dst[k];
  }
  const Eigen::Matrix4d T = Eigen::umeyama(s, d, false);
  if (!T.allFinite()) return std::nullopt;
  return core::SE3(T);
}

RigidFit ransac_rigid(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                      const core::LoopVerificationParameters& p) {
  RigidFit best;
  const std::size_t n = src.size();
  if (dst.size() != n || n < 3) return best;
  const std::size_t needed = std::max<std::size_t>(3, static_cast<std::size_t>(std::max(p.min_inliers, 0)));
  const double consistency = 2.0 * p.ransac_inlier_m;

  // rng() % n rather than std::uniform_int_distribution: the latter's algorithm is left to the
  // standard library, mt19937's output is not, so the draws are the same everywhere.
  std::mt19937 rng(p.ransac_seed);
  std::vector<std::size_t> sample(3);
  for (int it = 0; it < p.ransac_iterations; ++it) {
    sample[0] = rng() % n;
    do sample[1] = rng() % n;
    while (sample[1] == sample[0]);
    do sample[2] = rng() % n;
    while (sample[2] == sample[0] || sample[2] == sample[1]);

    const std::array<Eigen::Vector3d, 3> a{src[sample[0]], src[sample[1]], src[sample[2]]};
    const std::array<Eigen::Vector3d, 3> b{dst[sample[0]], dst[sample[1]], dst[sample[2]]};
    if (degenerate(a[0], a[1], a[2]) || degenerate(b[0], b[1], b[2])) continue;
    bool consistent = true;
    for (int u = 0; u < 3 && consistent; ++u)
      for (int v = u + 1; v < 3 && consistent; ++v)
        consistent = std::abs((a[u] - a[v]).norm() - (b[u] - b[v]).norm()) < consistency;
    if (!consistent) continue;

    const auto T = fit_rigid(src, dst, sample);
    if (!T) continue;
    auto inliers = inliers_of(src, dst, *T, p.ransac_inlier_m);
    if (inliers.size() > best.inliers.size()) {
      best.transform = *T;
      best.inliers = std::move(inliers);
    }
  }
  if (best.inliers.size() < needed) return RigidFit{};

  // Refit on the inliers, recount, refit: the final estimate uses every inlier of a good model.
  for (int round = 0; round < 2; ++round) {
    const auto T = fit_rigid(src, dst, best.inliers);
    if (!T) return RigidFit{};
    best.transform = *T;
    if (round == 0) {
      auto inliers = inliers_of(src, dst, best.transform, p.ransac_inlier_m);
      if (inliers.size() < needed) return RigidFit{};
      best.inliers = std::move(inliers);
    }
  }
  best.found = true;
  best.rms_m = rms(src, dst, best.transform, best.inliers);
  return best;
}

}  // namespace cvo::loop_closure
