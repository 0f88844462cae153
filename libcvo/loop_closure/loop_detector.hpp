#pragma once
// Loop closure between keyframes (paper section 5), end to end:
//   1. detection: the keyframe's ORB bag-of-words vector against every earlier keyframe but the
//      previous one; candidates with η = s(v_i, v_j) / s(v_i, v_{i-1}) > η_thres (0.3);
//   2. initial pose: ORB matches (ratio test 0.7, at least min_matches), their 3-D points from
//      depth, RANSAC over minimal sets with the SVD (Umeyama) rigid fit, refit on the inliers:
//      T_i^j, keyframe i's camera in keyframe j's frame;
//   3. refinement: CVO from h_0 = T_i^j (eq. 11), giving T_CVO and its Hessian;
//   4. the α test (eq. 12): accept only if
//        α = <f_Xi, T_CVO^-1.f_Xj> - max(<f_Xi, f_Xj>, <f_Xi, T_i^j.f_Xj>, <f_Xi, T_rel^-1.f_Xj>) > 0
//      with T_rel from the current global estimates of the two keyframes (h.f is the paper's
//      action, h.f_Z = f_{h^-1 Z}).
// At most max_refinements candidates (best η first) reach step 3 per new keyframe: CVO is the
// back end's main cost, and with keyframes coming several times a second, each with tens of
// candidates past η, verifying all of them would cost far more than the recording lasts while
// the best few find the same loops (the figures: bench/odometry-tuning.md).
// Candidates refused at steps 1-2 are cheap and do not count.
// What bounds a query: step 1 visits only the inverted-file postings of the new keyframe's words
// (keyframe_database.hpp), and step 2 runs on the candidates past η, so both grow with the keyframes
// the database holds; revisits merge their keyframes into those that cover them (slam/mapper.hpp),
// which leave the database, so it holds the area explored rather than the time spent, and step 3,
// CVO, the cost that matters, runs at most max_refinements times whatever the database holds. No
// cap on steps 1-2 beyond that is set (one would be a new tunable).
// Steps 2-4, the exact directions of the transforms, the length-scale of the α inner products and
// why the CVO Hessian is the edge's information as it comes: loop_verification.hpp.
//
// Several tracker sessions (slam/mapper.hpp): each keyframe names its predecessor in its own
// session (η's normaliser; the first keyframe of a session has none, so it proposes no candidates)
// and the piece of map its pose is in. Candidates come from every earlier keyframe of every session;
// the α test's trajectory term only compares keyframes of the same piece (loop_verification.hpp).
//
// The BoW vector uses all of a keyframe's ORB descriptors (appearance); matching uses only the
// keypoints with depth in the selection's range (only they give 3-D correspondences).
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/loop_closure/keyframe_database.hpp"
#include "libcvo/loop_closure/loop_verification.hpp"
#include "libcvo/loop_closure/orb_features.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/registration/point_cloud.hpp"
#include "libcvo/registration/registration.hpp"

namespace cvo::loop_closure {

// LoopDetectorParameters, LoopClosure and LoopAttempt: loop_verification.hpp.

/// Where a new keyframe sits: its id (unique), its predecessor in its session (none for the first),
/// its current global estimate T_piece_keyframe and the piece of map that pose is in.
/// `candidates_below`: only keyframes with a smaller id are loop candidates (a session localized in
/// a read-only map looks for loops to the map's keyframes only, not to its own window).
struct KeyframePlacement {
  std::int64_t id = 0;
  std::optional<std::int64_t> previous;
  core::SE3 pose;
  std::int64_t piece = 0;
  std::optional<std::int64_t> candidates_below = std::nullopt;
  // `previous` is the keyframe the predecessor was merged into (slam/mapper.hpp): it normalises η
  // in the predecessor's place, and is a candidate like any other (no odometry edge links it).
  bool previous_is_candidate = false;
};

/// A keyframe's current estimate after an optimisation or a join of pieces.
struct PlacedPose {
  core::SE3 pose;
  std::int64_t piece = 0;
};

class LoopDetector {
 public:
  LoopDetector(Vocabulary vocabulary, const LoopDetectorParameters& parameters);

  /// Stores a keyframe placed as `placement` says (any order of ids across sessions) and returns
  /// the loops accepted between it and earlier keyframes, best η first; every candidate tried is in
  /// last_attempts(). Throws std::invalid_argument when the id is stored already, and as
  /// extract_orb and keypoints_with_depth do on a bad frame.
  std::vector<LoopClosure> add_keyframe(const KeyframePlacement& placement, const core::RgbdFrame& frame,
                                        const registration::PointCloud& cloud);

  /// One session, one piece: keyframe `id` follows the last one added (ids increase; `pose` is its current global
  /// estimate T_world_keyframe, `cloud` its CVO points in its camera frame) and returns the loops accepted between it
  /// and earlier keyframes, best η first. Every candidate tried is recorded in last_attempts(). Throws
  /// std::invalid_argument when id is not above every earlier id, and as extract_orb and keypoints_with_depth do on a
  /// bad frame (wrong image types or sizes, bad intrinsics).
  std::vector<LoopClosure> add_keyframe(std::int64_t id, const core::RgbdFrame& frame,
                                        const registration::PointCloud& cloud, const core::SE3& pose);

  /// A session's first keyframe proposes no candidates when it comes (no predecessor normalises η).
  /// Once its successor `next` is stored, this is its detection: η normalised by the successor (its
  /// one neighbour in the session), the candidates those stored before it, verified as add_keyframe
  /// verifies (last_attempts() says how). Throws std::out_of_range for an id not stored.
  std::vector<LoopClosure> detect_first(std::int64_t first, std::int64_t next);

  /// Forgets a keyframe: it is no candidate and no η normaliser any more, and its features and
  /// cloud are freed. Throws std::out_of_range when it is not stored.
  void remove_keyframe(std::int64_t id);

  /// How well stored keyframe `covering` would serve as the keyframe of stored keyframe `covered`
  /// seen from it at `T` (T_covering^covered, a verified loop's measurement): the tracker's γ
  /// (eq. 9) with its kernel (keyframe_tracking's γ ℓ, σ, stride), the inner product
  /// <f_Xc, T.f_Xk> normalised by the RKHS norms, √(<f_Xc, f_Xc> <f_Xk, f_Xk>), instead of by the
  /// tracker's reference (the keyframe against its next frame, which the back end never sees).
  /// By Cauchy-Schwarz it is at most 1, and 1 only for the same view; against the frame after it a
  /// keyframe scores below its self product, so this γ is the stricter of the two: a keyframe it
  /// calls covered, the tracker would have kept tracking from c. Throws std::out_of_range for an
  /// id not stored.
  double coverage(std::int64_t covering, std::int64_t covered, const core::SE3& T);

  /// New global estimates after an optimisation (used for T_rel in the α test). Ids that are not
  /// stored keyframes (e.g. ordinary frames of the graph) are ignored.
  void update_poses(const std::map<std::int64_t, core::SE3>& poses);
  void update_poses(const std::map<std::int64_t, PlacedPose>& poses);

  [[nodiscard]] const std::vector<LoopAttempt>& last_attempts() const { return attempts_; }
  /// Of the last search's candidates, those the current estimate already explains
  /// (LoopVerification::confirmation), best η first: no loops, but evidence of coverage.
  [[nodiscard]] const std::vector<LoopClosure>& last_confirmations() const { return confirmations_; }
  [[nodiscard]] std::size_t size() const { return keyframes_.size(); }
  [[nodiscard]] bool contains(std::int64_t id) const { return keyframes_.contains(id); }
  [[nodiscard]] const LoopDetectorParameters& parameters() const { return parameters_; }

 private:
  Vocabulary vocabulary_;
  LoopDetectorParameters parameters_;
  KeyframeDatabase database_;
  registration::Registration registration_;
  registration::Registration gamma_registration_;   // γ's kernel (coverage)
  std::map<std::int64_t, LoopKeyframe> keyframes_;  // features, 3-D keypoints, cloud, pose
  std::optional<std::int64_t> previous_;            // the last keyframe added
  std::vector<LoopAttempt> attempts_;
  std::vector<LoopClosure> confirmations_;

  // Steps 2-4 for `keyframe` against `candidates` (best η first), at most max_refinements CVO runs:
  // the loops accepted; each attempt into attempts_, each confirmation into confirmations_.
  std::vector<LoopClosure> verify(const LoopKeyframe& keyframe, const std::vector<LoopCandidate>& candidates,
                                  std::optional<std::int64_t> candidates_below);
};

}  // namespace cvo::loop_closure
