#pragma once
// CVO registration (paper section 3): find the T in SE(3) that maximises the RKHS inner product
//
//   F(T) = <f_X, T.f_Z> = Σ_ij c_ij k(x_i, T z_j)          (see kernel.hpp for k and c)
//
// of a fixed cloud X and a moving cloud Z; T maps Z's frame into X's frame.
//
// The solver. With w_j = T z_j, d_ij = x_i - w_j and a_ij = c_ij k(x_i, w_j), a left perturbation
// T <- exp(ξ) T moves w_j by J_j ξ, J_j = [I, -ŵ_j], and
//   ∇F = (1/ℓ²) Σ_j J_jᵀ D_j,     D_j = Σ_i a_ij d_ij.
// Each iteration takes the step ξ = H⁻¹ b with b = Σ_j J_jᵀ D_j and H = Σ_j A_j J_jᵀ J_j,
// A_j = Σ_i a_ij: the Gauss-Newton step of the weighted least-squares problem whose weights are
// the current a_ij (an EM / majorise-minimise step for a sum of Gaussians; it is a positive-
// definite rescaling of the gradient, so it always ascends for small enough steps). It converges
// in far fewer iterations than the original CVO's first-order gradient flow.
// The length-scale ℓ starts at ℓ_init and shrinks by `ell_decay` each time the step falls below
// 1 % of ℓ, down to ℓ_min, where the iteration stops once |ξ| < min_step (coarse-to-fine: a wide
// kernel gives a wide basin, a narrow one precision).
// Convergence. The points' depth noise and the pairs that cross the sparsification threshold from
// one iteration to the next make F rough at the scale of the estimate's own uncertainty: where the
// scene constrains T weakly (white walls, geometry alone) the steps then wander within it for tens
// of iterations without converging further. A step below that uncertainty is noise: with the
// sandwich covariance Σ = H⁻¹ B H⁻¹ (below, "The gradient scatter") the step's Mahalanobis length
// is ξᵀ Σ⁻¹ ξ = bᵀ B⁻¹ b, the gradient's length against its own scatter, and once it is below 1
// (the step within one standard deviation) the length-scale shrinks, or at ℓ_min the iteration
// stops, as when the step falls below the fixed thresholds above (whichever comes first). In six
// dimensions that is strict: at the optimum bᵀB⁻¹b follows χ²₆ (mean 6), so where this test
// decides (texture-less scenes) the iteration runs until a draw falls below 1
// (bench/odometry-tuning.md, "The convergence test in six dimensions").
// The reported Hessian is H / ℓ² at the final ℓ, the Gauss-Newton approximation of -∇²F, used as
// the information of the estimate (pose-graph edges).
//
// The gradient scatter. H is not a likelihood's information: F is a kernel correlation, and H
// scales with the kernel amplitudes σ², σ_c², the density of the fixed cloud and 1/ℓ² (a tuning
// length, not the sensor's noise), none of which is the measurement's noise. The estimate is an
// M-estimator, the root of Σ_j g_j(T) = 0 with per-point terms g_j = J_jᵀ D_j / ℓ², so its
// covariance is the sandwich (Huber-White) H⁻¹ B H⁻¹ with B = Cov(Σ_j g_j), which every amplitude
// cancels out of and which measures the scatter of what this pair of clouds really shows. The
// g_j of neighbouring moving points are correlated (they share fixed points within r_max, and a
// depth sensor's errors are correlated over neighbouring pixels), so B is the cluster-robust sum
// B = Σ_c G_c G_cᵀ, G_c = Σ_{j∈c} g_j over runs of kScatterCluster consecutive moving points (image
// order: a short run of one row). `gradient_scatter` is B at the final iteration.
//
// Mutual visibility (CvoParameters::mutual_visibility; align() only). Each cloud covers its own
// camera's view; where the views differ, a moving point near the edge of X's view finds partners on
// one side only, and a fixed point the moving camera no longer sees has none: both pull T towards
// less motion (the kernel correlation of two truncated clouds peaks short of the truth; KF-CVO
// under-rotated on real fast turns: libcvo/odometry/README.md, "Rotation"). So align() sums only what both cameras see:
// moving points whose T z_j falls outside X's view (the extent of X's image coordinates x/z, y/z) are skipped each
// iteration, and fixed points outside Z's view, seen through T⁻¹, are hidden once per length-scale. Then both clouds
// are cut at the same place at the truth, where the correlation of the cut clouds peaks. γ and α (inner_product())
// measure overlap and keep every point.
//
// Neighbour search: X is hashed once per length-scale into cells of side r_max (see kernel.hpp);
// each moving point visits the 27 cells around it.
//
// Candidate pairs (align() only). A pair's colour term does not depend on T, and a pair counts
// only where k_c alone reaches the threshold; so once per length-scale each moving point keeps
// the fixed points whose colour lets them count and that lie within the reach r_max + s of it
// (the cells are then that wide), with their colour terms. While the point has moved less than
// reach - r_max since, no other fixed point can reach the threshold: the iteration sums its
// candidates alone, which is exact and far cheaper than searching 27 cells again. A point that
// moved farther collects again. When ℓ shrinks, r_max does: the grid and candidates stay, and
// last longer.
//
// The pair budget. Where colours differ, the colour term leaves a point a few candidates; where
// they are alike (white walls, a texture-less room) it leaves every fixed point within reach, and
// the cost of a sum would follow the scene's colours (registration/README.md has the figures). So a point sums at most
// `candidates_per_point` candidates: when it has n > B of them it keeps every m-th, m = ⌈n/B⌉, from the phase j mod m
// (neighbouring moving points keep different ones), and each kept pair is weighted n / kept. Then
//   - a point with n ≤ B is summed exactly (the pairs of a search every iteration);
//   - otherwise A_j and D_j are a systematic sample's estimates of the full sums, unbiased over
//     the phase; the pairs they stand for lie on one surface of one colour within reach, where
//     neighbouring fixed points repeat each other (the spatial kernel is smooth at ℓ);
//   - the pairs summed per point and iteration are at most B whatever the colours.
// `tests/registration` checks the exact case against a search every iteration and the budgeted
// one against it on a texture-less frame.
//
// Reuse. A second align() of the same fixed cloud with the moving points moved a little (the
// frame selected again at its own motion) needs no new grid and no new candidates: a candidate
// list depends on the point's label and on where it was collected, and the validity test above
// already catches a point that moved beyond its margin. So with Reuse::kCandidates align() keeps
// the grid (when it is at least as wide as the start's reach) and every candidate list whose
// point still has its label. The lists follow the labels, not the indices: a frame selected again
// keeps its pixels' order but may drop a point or keep one it had dropped, which shifts every later
// index (matching by index kept 50 lists of ~2 900 on fr1/rpy). Where no point's candidates exceed
// the budget, the same pairs count as in a fresh align().
//
// Fixed memory: every buffer is sized at construction from the capacities; after construction
// align() and inner_product() do not allocate. Threads (optional) split the moving cloud into
// fixed chunks reduced in a fixed order, so the result does not depend on the thread count.
#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/registration/kernel.hpp"
#include "libcvo/registration/point_cloud.hpp"

namespace cvo::registration {

enum class RegistrationStatus {
  kOk,
  kEmptyCloud,        // one cloud has fewer than min_points points
  kNonFinite,         // a NaN/Inf position or label, or a non-finite initial guess
  kCapacityExceeded,  // a cloud is larger than the capacity; only the first `capacity` points used
  kNoOverlap,         // too few contributing pairs to estimate a step
  kNotConverged,      // stopped at max_iterations
  kBadParameters      // the kernel amplitude is below the sparsification threshold, or similar
};
const char* to_string(RegistrationStatus status);

/// r_max at length-scale ℓ: no pair farther apart than this can reach the sparsification threshold,
/// even of identical colours, r_max = ℓ √(2 ln(σ² σ_c² / threshold)) (0.61 ℓ at Table 1's values).
/// 0 when the kernel amplitude is not above the threshold (no pair ever counts).
double kernel_reach(const core::CvoParameters& parameters, double ell);

struct RegistrationResult {
  core::SE3 transform;  // T: Z's frame -> X's frame
  int iterations = 0;
  bool converged = false;
  RegistrationStatus status = RegistrationStatus::kOk;
  double inner_product = 0;  // F(T) at the final length-scale (over what both views see: see above)
  double final_ell = 0;
  std::size_t pairs = 0;                                     // contributing pairs at the last iteration
  core::Matrix6d hessian = core::Matrix6d::Zero();           // H / ℓ², ordered [translation, rotation]
  core::Matrix6d gradient_scatter = core::Matrix6d::Zero();  // B (see above), the same order
};

/// What align() may keep of the last align() (see "Reuse" above).
enum class Reuse {
  kNothing,
  // `fixed` is the last align()'s fixed cloud, unchanged, and `moving` holds (some of) the last
  // moving cloud's points in their order with their labels, moved a little (some dropped, some
  // added): a frame selected again with another motion (odometry/keyframe_odometry.hpp). The grid
  // and the candidates of every point found again by its label stay; the rest collect as usual.
  kCandidates
};

struct Capacities {
  std::size_t max_points;  // per cloud: the caller's core::OdometryParameters::max_points
  // B, the pair budget: candidate pairs kept per moving point (align(); see above); 0: none,
  // every iteration searches the cells in full (exact, at any cost).
  std::size_t candidates_per_point = 32;
};

class Registration {
 public:
  Registration(const Capacities& capacities, const core::CvoParameters& parameters,
               kernel::Isa isa = kernel::best_isa());

  /// Maximises <f_X, T.f_Z> from `initial`, the length-scale going from `ell_start` (0: ℓ_init)
  /// to ℓ_min. A guess already within a few millimetres (another registration's result) needs no
  /// wide basin: starting at ℓ_min saves the coarse iterations; a guess with no motion model
  /// behind it may need a wider one than ℓ_init.
  RegistrationResult align(const PointCloud& fixed, const PointCloud& moving, const core::SE3& initial,
                           double ell_start = 0, Reuse reuse = Reuse::kNothing);

  /// <f_X, T.f_Z> at length-scale `ell` (the keyframe test γ and the loop test α use it). With
  /// `stride` > 1 only every stride-th moving point is summed: about 1/stride of the whole, for a
  /// ratio of two sums over the same moving cloud at a fraction of the cost.
  double inner_product(const PointCloud& fixed, const PointCloud& moving, const core::SE3& T, double ell,
                       std::size_t stride = 1);
  /// ... at ℓ_min, the length-scale align() finishes at.
  double inner_product(const PointCloud& fixed, const PointCloud& moving, const core::SE3& T) {
    return inner_product(fixed, moving, T, parameters_.ell_min);
  }

  [[nodiscard]] const core::CvoParameters& parameters() const { return parameters_; }
  [[nodiscard]] kernel::Isa isa() const { return isa_; }
  /// Contributing pairs of each iteration of the last align() (diagnostics, no allocation).
  [[nodiscard]] const std::vector<std::size_t>& pairs_per_iteration() const { return pairs_log_; }
  [[nodiscard]] std::size_t pairs_logged() const { return pairs_logged_; }
  /// How often the last align() collected a moving point's candidates (diagnostics): once per
  /// point, and again for those that moved beyond their reach.
  [[nodiscard]] std::size_t collections() const { return collections_; }
  /// How often the last align() searched a moving point's cells in full (diagnostics): a point
  /// whose candidates outnumbered its slots.
  [[nodiscard]] std::size_t full_searches() const { return full_searches_; }

 private:
  // Σ over moving points of what the step needs:
  //   s0 = Σ A_j, s1 = Σ A_j w_j, s2 = Σ A_j w_j w_jᵀ, bt = Σ D_j, br = Σ w_j × D_j,
  // from which H = [[s0 I, -ŝ1], [ŝ1, tr(s2) I - s2]] and b = [bt; br].
  struct Sums {
    double s0 = 0;
    Eigen::Vector3d s1 = Eigen::Vector3d::Zero();
    Eigen::Matrix3d s2 = Eigen::Matrix3d::Zero();
    Eigen::Vector3d bt = Eigen::Vector3d::Zero(), br = Eigen::Vector3d::Zero();
    core::Matrix6d scatter = core::Matrix6d::Zero();  // Σ_c G_c G_cᵀ of the raw terms [D_j; w_j × D_j]
    std::size_t pairs = 0;
    std::size_t collections = 0;    // candidate collections
    std::size_t full_searches = 0;  // points summed by searching their cells (align())
    void add(const Sums& o);
    [[nodiscard]] core::Matrix6d hessian() const;
  };
  // The occupied cells among the 27 around a point; the last lookup is kept, since consecutive
  // moving points (image order) often share a cell.
  struct Cells {
    kernel::Range ranges[27];
    int count = 0;
    std::int64_t cx = 0, cy = 0, cz = 0;
    bool valid = false;
  };
  bool set_length_scale(double ell, double slack_fraction);
  bool build_grid(const PointCloud& fixed, std::size_t n, double ell, double slack_fraction);
  bool keep_grid(const PointCloud& fixed, std::size_t n, double ell, const PointCloud& moving, std::size_t nm);
  void match_moving_points(const PointCloud& moving, std::size_t nm);
  void move_candidates(std::size_t from, std::size_t to);
  void record_labels(const PointCloud& moving, std::size_t nm);
  void find_cells(const Eigen::Vector3f& w, Cells& cells) const;
  void accumulate(const PointCloud& moving, std::size_t n, const core::SE3& T, Sums& total, std::size_t stride = 1,
                  bool candidates = false);
  kernel::PointSums point_sums(std::size_t j, const Eigen::Vector3f& w, const float* feature, Cells& cells,
                               bool candidates, Sums& counts);
  void collect_candidates(std::size_t j, const Eigen::Vector3f& w, const float* feature, const Cells& cells);
  [[nodiscard]] kernel::PointSums candidate_sums(std::size_t j, const Eigen::Vector3f& w) const;
  RegistrationStatus check(const PointCloud& fixed, const PointCloud& moving) const;
  // What a camera saw: the extent of its points' image coordinates x/z, y/z.
  struct View {
    float x0 = 0, x1 = 0, y0 = 0, y1 = 0;
    [[nodiscard]] bool sees(const Eigen::Vector3f& p) const;
  };
  static View view_of(const PointCloud& cloud, std::size_t n);
  void hide_fixed_unseen(std::size_t n, const core::SE3& T);

  core::CvoParameters parameters_;
  kernel::Isa isa_;
  kernel::PointFunction point_;
  kernel::CollectFunction collect_;
  kernel::CandidateFunction candidates_;
  std::size_t capacity_;
  // Hash grid over the fixed cloud, SoA in bucket order.
  std::size_t bucket_mask_;  // slots - 1; slots = power of two ≥ 2 × max_points, so probing stays short
  double cell_ = 1, inv_cell_ = 1;
  double grid_ell_ = 0;                     // the length-scale the grid was built for (0: none)
  const PointCloud* grid_cloud_ = nullptr;  // the fixed cloud it was built from
  std::size_t grid_points_ = 0;
  std::vector<std::uint64_t> slot_key_;      // cell key of each slot, or empty
  std::vector<std::uint32_t> bucket_start_;  // size slots + 1
  std::vector<std::uint32_t> bucket_of_;     // per input point
  std::vector<float> px_, py_, pz_;          // the fixed cloud where it is (candidates are collected here)
  std::vector<float> sx_, sy_, sz_;  // ... as summed: a point the moving camera does not see is put out of reach
  bool visibility_ = false;          // align() with mutual visibility: moving points X's view does not see skipped
  View fixed_view_, moving_view_;
  std::array<std::vector<float>, kFeatureDim> sf_;
  kernel::FixedCloudView hashed_{}, summed_{};  // the two copies with the labels, as the kernels read them
  kernel::Constants constants_;
  // Candidate pairs per moving point (see the header): slots [j * slots_, +count).
  std::size_t slots_;
  float r_max_ = 0, slack_ = 0, reach_sq_ = 0;  // at the present ℓ: r_max, s, and (r_max + s)²
  std::vector<std::uint32_t> candidate_fixed_;  // the fixed point (bucket order)
  std::vector<float> candidate_colour_;         // its colour term |Δf|² / 2ℓ_c²
  std::vector<std::uint16_t> candidate_count_;  // or kUncollected
  std::vector<float> candidate_weight_;         // fixed points each candidate stands for (the budget)
  std::vector<float> collected_label_;          // kFeatureDim per moving point: its label when collected
  std::vector<float> moving_label_;             // kFeatureDim per moving point of the last align(), in order
  std::size_t labelled_points_ = 0;
  std::vector<std::uint32_t> source_;         // per moving point: the last align()'s point whose list it takes
  std::vector<std::uint32_t> scratch_fixed_;  // per thread: every candidate of one point, before the budget
  std::vector<float> scratch_colour_;
  std::vector<float> collected_at_;  // 4 per moving point: where it was when collected, the reach then
  std::vector<Sums> chunk_sums_;
  std::vector<std::size_t> pairs_log_;
  std::size_t pairs_logged_ = 0;
  std::size_t collections_ = 0;
  std::size_t full_searches_ = 0;
};

}  // namespace cvo::registration
