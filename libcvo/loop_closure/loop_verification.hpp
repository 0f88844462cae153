#pragma once
// Verifying one loop candidate: keyframe i (the new one) against an earlier keyframe j that the
// bag-of-words test proposed (paper section 5, steps 2-4 of loop_detector.hpp).
//
//   1. matches: ratio-test ORB matches of i's keypoints with depth to j's (feature_matching.hpp);
//      fewer than max(3, min_matches): "too few matches".
//   2. initial pose: RANSAC + Umeyama on the matched 3-D points p_i -> p_j (rigid_ransac.hpp),
//      T_ji^0 = T_i^j with p_j ≈ T_ji^0 p_i, keyframe i's camera in j's frame; fewer than
//      min_inliers inliers: "RANSAC failed".
//   3. refinement, eq. 11 in the paper's direction: CVO with X_i fixed and X_j moving. Here
//      (registration.hpp) T maps the moving cloud into the fixed one, the inverse of the paper's
//      h (h.f_Z = f_{h^-1 Z}), so the start h_0 = T_ji^0 becomes (T_ji^0)^-1 and the result is
//      T_ij, j's points into i's frame. The measurement is Z = T_ij^-1 = T_j^-1 T_i. Not converged
//      (or no overlap): "CVO failed".
//   3b. not in the paper: the CVO pose must keep min_inlier_retention of RANSAC's inliers within
//      ransac_inlier_m, else "CVO left the matches". CVO can slide from a RANSAC pose near the
//      truth to a wrong one that overlaps the clouds about as well, α above 0 all the same; a
//      wrong pose moves the matched keypoints far, a right one keeps them (what was seen on
//      fr1/rpy: bench/odometry-tuning.md, "loop_closure.min_inlier_retention").
//   4. α (eq. 12), every inner product <f_Xi, T.f_Xj> with X_i fixed, X_j moving, T mapping j's
//      frame into i's, and all at ONE length-scale: ℓ_min (min(ell_min, ell_init) of the CVO
//      parameters, where align() converges), so the four numbers are comparable:
//        α = <X_i, T_ij X_j> - max(<X_i, X_j>, <X_i, (T_ji^0)^-1 X_j>, <X_i, T_rel X_j>),
//      T_rel = T_i^-1 T_j from the current global estimates of the two keyframes (a term only
//      when both are in the same piece of map: two sessions not joined yet have no T_rel). α <= 0:
//      "alpha <= 0" (the CVO pose aligns no better than identity, the RANSAC pose, or what the
//      trajectory already says: such a loop would add nothing or harm).
//      A rival that IS the CVO pose, within the CVO pose's own uncertainty, is no rival: with
//      ξ = log(T_rival T_ij⁻¹) (the left perturbation of the edge's information Ω below),
//      ξᵀ Ω ξ < χ²₆(0.95) = 12.59 puts it inside the 95 % confidence region of T_ij, and it drops
//      out of the max. Without that, α cannot accept the commonest revisit: a robot started again
//      at its dock sees what it saw, RANSAC's pose and the identity are already the optimum, CVO
//      can only tie with them, and α sits at the noise level of the sparsified kernel
//      (bench/odometry-tuning.md, "α at the optimum"), refused although right; the one-session
//      trajectory term has the same blind spot when the trajectory already agrees. A rival the
//      CVO pose cannot be told from supports the loop rather than contradicting it; when every
//      rival is the CVO pose, the loop is accepted (α then compares with no rival: +∞ is not
//      reported, α is that of the nearest rival, flagged by `rivals` = 0). An over-confident Ω
//      (real sequences: bench/odometry-tuning.md, "Covariance") only keeps rivals in: the test
//      stays as strict as the paper's.
//
// Information of the loop edge. The solver's calibrated information H = Σ⁻¹
// (registration/edge_covariance.hpp, the sandwich of its Hessian; order [translation, rotation])
// is the information of a LEFT perturbation T_ij <- exp(ξ) T_ij, ξ in
// i's frame. Then Z = T_ij^-1 <- T_ij^-1 exp(-ξ) = Z exp(-ξ): a RIGHT perturbation of Z, which is
// the pose graph's residual e ≈ log(Z^-1 T_j^-1 T_i) (posegraph/residual.hpp, right perturbation
// in the `to` node's frame) up to sign. So Ω = H as it comes, because CVO runs with the new
// keyframe i, the edge's `to`, fixed. (Run the other way, X_j fixed, the solver's H' would be for
// a left perturbation of Z in j's frame, and Ω = Ad(Z)ᵀ H' Ad(Z); the tests check the two agree.)
#include <cstddef>
#include <cstdint>
#include <optional>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/loop_closure/keypoints_3d.hpp"
#include "libcvo/loop_closure/orb_features.hpp"
#include "libcvo/registration/point_cloud.hpp"
#include "libcvo/registration/registration.hpp"

namespace cvo::loop_closure {

/// The core structs whole (libcvo/core/parameters.hpp). From the configuration:
/// config::loop_detector_parameters (libcvo/config/module_parameters.hpp).
struct LoopDetectorParameters {
  core::LoopClosureParameters loop;               // η_thres, ratio, min_matches (Table 1)
  core::LoopVerificationParameters verification;  // refinements, RANSAC, step 3b, ORB
  core::CvoParameters cvo;                        // of the refinement
  core::SelectionParameters selection;            // min_depth_m / max_depth_m: the keypoints' depth range
  core::OdometryParameters odometry;              // max_points: capacity of the stored clouds
  // The tracker's keyframe test, for a revisit's coverage (loop_detector.hpp: coverage()):
  // γ_thres, and γ's kernel (its length-scale, signal, stride).
  core::KeyframeParameters keyframe;
  core::KeyframeTrackingParameters keyframe_tracking;
};

/// An accepted loop: an edge of the keyframe pose graph, in posegraph::Edge's convention.
struct LoopClosure {
  std::int64_t from = 0;  // j, the earlier keyframe
  std::int64_t to = 0;    // i, the new keyframe
  core::SE3 measurement;  // T_from_to = T_j^-1 T_i (keyframe i's camera in keyframe j's frame)
  core::Matrix6d information = core::Matrix6d::Identity();  // calibrated CVO information (above)
  double eta = 0;                                           // normalised bag-of-words score of the candidate
  double alpha = 0;                                         // eq. 12, > 0
  int inliers = 0;                                          // RANSAC inliers of the initial pose
};

/// Why each candidate was refused, for logs and tests.
struct LoopAttempt {
  std::int64_t candidate = 0;
  double eta = 0;
  int matches = 0, inliers = 0;
  int inliers_kept = 0;  // RANSAC inliers still within ransac_inlier_m under the CVO pose
  double alpha = 0;
  int rivals = 3;  // of α's three comparisons, those with a pose other than the CVO pose's
  bool accepted = false;
  const char* verdict = "";  // "accepted", "too few matches", "RANSAC failed", "CVO failed",
                             // "CVO left the matches", "alpha <= 0"
};

/// What verification needs of a keyframe. Copies share the descriptor matrix (cv::Mat), which
/// nothing modifies.
struct LoopKeyframe {
  std::int64_t id = 0;
  Keypoints3d keypoints;           // ORB keypoints with depth, camera frame
  registration::PointCloud cloud;  // CVO points, camera frame (a copy)
  core::SE3 pose;                  // current global estimate T_piece_keyframe
  std::int64_t piece = 0;          // the piece of map `pose` is in (mapper.hpp): poses of two
                                   // pieces are not comparable
};

/// The keyframe's keypoints with depth (selection's depth range) and a copy of the first
/// max_points points of `cloud`.
LoopKeyframe make_loop_keyframe(std::int64_t id, const OrbFeatures& features, const core::RgbdFrame& frame,
                                const registration::PointCloud& cloud, const core::SE3& pose,
                                const LoopDetectorParameters& parameters);

/// The inner products of the α test (step 4), at length-scale ell.
struct AlphaInnerProducts {
  double cvo = 0, identity = 0, initial = 0, estimate = 0;
  double ell = 0;
  // Whether each rival is a pose other than the CVO pose (step 4: outside its confidence region).
  bool identity_rival = true, initial_rival = true, estimate_rival = true;
  /// cvo - max over the rivals (identity, initial, estimate); with none, cvo - max over all three.
  [[nodiscard]] double alpha() const;
  /// How many of the three are rivals.
  [[nodiscard]] int rivals() const;
  /// Step 4's verdict: α over the rivals > 0, or no rival at all.
  [[nodiscard]] bool accepts() const;
};

struct LoopVerification {
  LoopAttempt attempt;                 // eta is the caller's (0 here)
  std::optional<LoopClosure> closure;  // when accepted (eta 0 here too)
  // Refused at step 4 only because the current estimate explains the view at least as well as CVO
  // (<f_Xi, T_rel^-1.f_Xj> >= <f_Xi, T_CVO^-1.f_Xj>, the two in one piece): no loop, as it adds
  // nothing, but a view the map already holds where it is, with 3a-3b's evidence. Its measurement is
  // the estimate's T_j^i, its information CVO's: what a revisit is merged by (slam/mapper.hpp).
  std::optional<LoopClosure> confirmation;
  core::SE3 initial;                            // T_ji^0, RANSAC (identity when it failed)
  registration::RegistrationResult refinement;  // CVO's T_ij and Hessian (default when not run)
  AlphaInnerProducts inner_products;            // when CVO converged
};

/// Steps 1-4 for new keyframe i and earlier keyframe j. `registration` must have been built with
/// parameters.cvo and capacity max_points (LoopDetector owns one).
LoopVerification verify_loop(const LoopKeyframe& i, const LoopKeyframe& j, const LoopDetectorParameters& parameters,
                             registration::Registration& registration);

}  // namespace cvo::loop_closure
