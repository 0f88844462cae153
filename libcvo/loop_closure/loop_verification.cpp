#include "libcvo/loop_closure/loop_verification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "libcvo/loop_closure/feature_matching.hpp"
#include "libcvo/loop_closure/rigid_ransac.hpp"
#include "libcvo/registration/edge_covariance.hpp"

namespace cvo::loop_closure {
namespace {

registration::PointCloud copy_cloud(const registration::PointCloud& cloud, std::size_t max_points) {
  const std::size_t n = std::min(cloud.size(), max_points);
  registration::PointCloud copy(n);  // sized to the points, not to max_points: keyframes add up
  for (std::size_t k = 0; k < n; ++k) copy.push_back(cloud.position(k), cloud.feature(k));
  return copy;
}

// χ²₆ at 0.95: the 95 % confidence region of a 6-dof Gaussian estimate.
constexpr double kChi2_6_95 = 12.592;

// Whether `t` lies in the confidence region of `estimate` whose information (left perturbation,
// [translation; rotation]) is Ω: ξᵀ Ω ξ < χ²₆(0.95), ξ = log(t estimate⁻¹).
bool within_confidence(const core::Matrix6d& information, const core::SE3& t, const core::SE3& estimate) {
  const core::Vector6d xi = (t * estimate.inverse()).log();
  return xi.dot(information * xi) < kChi2_6_95;
}

bool converged(const registration::RegistrationResult& r) {
  return r.converged && (r.status == registration::RegistrationStatus::kOk ||
                         r.status == registration::RegistrationStatus::kCapacityExceeded);
}

}  // namespace

LoopKeyframe make_loop_keyframe(std::int64_t id, const OrbFeatures& features, const core::RgbdFrame& frame,
                                const registration::PointCloud& cloud, const core::SE3& pose,
                                const LoopDetectorParameters& p) {
  return {id, keypoints_with_depth(features, frame, p.selection.min_depth_m, p.selection.max_depth_m),
          copy_cloud(cloud, p.odometry.max_points), pose};
}

double AlphaInnerProducts::alpha() const {
  constexpr double kNone = -std::numeric_limits<double>::infinity();
  if (rivals() == 0) return cvo - std::max({identity, initial, estimate});
  return cvo - std::max({identity_rival ? identity : kNone, initial_rival ? initial : kNone,
                         estimate_rival ? estimate : kNone});
}

int AlphaInnerProducts::rivals() const {
  return int{identity_rival} + int{initial_rival} + int{estimate_rival && std::isfinite(estimate)};
}

bool AlphaInnerProducts::accepts() const { return rivals() == 0 || alpha() > 0; }

LoopVerification verify_loop(const LoopKeyframe& i, const LoopKeyframe& j, const LoopDetectorParameters& p,
                             registration::Registration& registration) {
  LoopVerification v;
  v.attempt.candidate = j.id;

  // 1. Matches of i's keypoints (query) to j's (train), as 3-D correspondences p_i -> p_j.
  const auto matches = ratio_matches(i.keypoints.descriptors, j.keypoints.descriptors, p.loop.match_ratio);
  v.attempt.matches = static_cast<int>(matches.size());
  if (v.attempt.matches < std::max(3, p.loop.min_matches)) {
    v.attempt.verdict = "too few matches";
    return v;
  }
  std::vector<Eigen::Vector3d> src, dst;
  src.reserve(matches.size());
  dst.reserve(matches.size());
  for (const auto& m : matches) {
    src.push_back(i.keypoints.points[static_cast<std::size_t>(m.query)]);
    dst.push_back(j.keypoints.points[static_cast<std::size_t>(m.train)]);
  }

  // 2. Initial pose T_ji^0: p_j ≈ T_ji^0 p_i.
  const RigidFit fit = ransac_rigid(src, dst, p.verification);
  v.attempt.inliers = static_cast<int>(fit.inliers.size());
  if (!fit.found) {
    v.attempt.verdict = "RANSAC failed";
    return v;
  }
  v.initial = fit.transform;

  // 3. Eq. 11: X_i fixed, X_j moving, from h_0 = (T_ji^0)^-1; the result maps j into i.
  v.refinement = registration.align(i.cloud, j.cloud, v.initial.inverse());
  if (!converged(v.refinement)) {
    v.attempt.verdict = "CVO failed";
    return v;
  }

  // 3b. The refined pose must still explain the matches RANSAC found: CVO started inside the
  // basin of the right pose, and one that slid out of it (to a wrong local optimum of similar
  // inner product) moves the inliers far off. α alone cannot tell, see the header.
  const core::SE3 refined_ji = v.refinement.transform.inverse();
  for (const std::size_t k : fit.inliers)
    if ((dst[k] - refined_ji * src[k]).norm() < p.verification.ransac_inlier_m) ++v.attempt.inliers_kept;
  if (v.attempt.inliers_kept < p.verification.min_inlier_retention * static_cast<double>(fit.inliers.size())) {
    v.attempt.verdict = "CVO left the matches";
    return v;
  }

  // 4. Eq. 12, all four at ℓ_min (where align() converged): comparable numbers.
  const auto& cvo = registration.parameters();
  auto& ip = v.inner_products;
  ip.ell = std::min(cvo.ell_min, cvo.ell_init);
  ip.cvo = registration.inner_product(i.cloud, j.cloud, v.refinement.transform, ip.ell);
  ip.identity = registration.inner_product(i.cloud, j.cloud, core::SE3(), ip.ell);
  ip.initial = registration.inner_product(i.cloud, j.cloud, v.initial.inverse(), ip.ell);
  // Keyframes of two pieces of map (sessions not joined yet) have no relative estimate: that term
  // drops out of the max.
  ip.estimate = i.piece == j.piece ? registration.inner_product(i.cloud, j.cloud, i.pose.inverse() * j.pose, ip.ell)
                                   : -std::numeric_limits<double>::infinity();
  // Ω = Σ⁻¹ of the solver's result, calibrated as every CVO edge (registration/edge_covariance.hpp);
  // see the header for why no adjoint is needed. It also tells which of α's rivals are the CVO pose.
  const auto information =
      registration::information_of(registration::edge_covariance(v.refinement), v.refinement.hessian);
  const auto rival = [&](const core::SE3& t) { return !within_confidence(information, t, v.refinement.transform); };
  ip.identity_rival = rival(core::SE3());
  ip.initial_rival = rival(v.initial.inverse());
  ip.estimate_rival = i.piece == j.piece && rival(i.pose.inverse() * j.pose);
  v.attempt.alpha = ip.alpha();
  v.attempt.rivals = ip.rivals();
  if (!ip.accepts()) {
    v.attempt.verdict = "alpha <= 0";
    if (std::isfinite(ip.estimate) && ip.estimate >= ip.cvo)
      v.confirmation =
          LoopClosure{j.id, i.id, j.pose.inverse() * i.pose, information, 0.0, v.attempt.alpha, v.attempt.inliers};
    return v;
  }

  v.attempt.accepted = true;
  v.attempt.verdict = "accepted";
  v.closure =
      LoopClosure{j.id, i.id, v.refinement.transform.inverse(), information, 0.0, v.attempt.alpha, v.attempt.inliers};
  return v;
}

}  // namespace cvo::loop_closure
