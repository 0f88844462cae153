#include "libcvo/registration/registration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include <omp.h>

namespace cvo::registration {
namespace {

constexpr std::size_t kChunk = 256;    // moving points per reduction chunk (fixed: thread-count independent)
constexpr std::size_t kMinPairs = 12;  // fewer contributing pairs cannot constrain 6 DoF reliably
constexpr std::size_t kMinPoints = 3;
constexpr double kMaxRotationStep = 0.2;  // rad per iteration: a trust region against wild first steps
constexpr double kShrinkFraction = 0.01;  // shrink ℓ once the step is below this fraction of ℓ
// Candidate pairs: the slack s as a fraction of r_max. Wider cells cost each collection more;
// a narrower slack makes points collect again sooner (the first step at each ℓ moves most).
constexpr double kSlackFraction = 0.25;
// Moving points per cluster of the gradient scatter (registration.hpp): consecutive points of the
// semi-dense selection, a run along one image row about as long as the kernel's reach at depth.
constexpr std::size_t kScatterCluster = 8;
constexpr std::uint16_t kUncollected = 0xFFFF;
constexpr std::uint32_t kNoSource = 0xFFFFFFFF;
// How far ahead a reselected point's label is looked for (match_moving_points): the points the
// reselection dropped in a row. A few at the image's edge; beyond this the rest collect anew.
constexpr std::size_t kMatchWindow = 16;
constexpr float kFar = 1e15f;  // where a hidden fixed point is put: beyond every kernel's reach

std::size_t next_power_of_two(std::size_t v) {
  std::size_t p = 1;
  while (p < v) p <<= 1;
  return p;
}

// Cells are keyed by their integer coordinates packed into 63 bits (21 bits each, offset to be
// non-negative); coordinates are clamped to that range, which only merges cells tens of
// kilometres away, and the kernel's own distance test keeps the result exact.
constexpr std::int64_t kCoordinateRange = 1 << 20;
constexpr std::uint64_t kEmptySlot = ~0ULL;

inline std::int64_t cell_coordinate(float v, double inv_cell) {
  const double c = std::floor(static_cast<double>(v) * inv_cell);
  return static_cast<std::int64_t>(
      std::clamp(c, -static_cast<double>(kCoordinateRange - 2), static_cast<double>(kCoordinateRange - 2)));
}

inline std::uint64_t cell_key(std::int64_t ix, std::int64_t iy, std::int64_t iz) {
  return static_cast<std::uint64_t>(ix + kCoordinateRange) << 42 |
         static_cast<std::uint64_t>(iy + kCoordinateRange) << 21 | static_cast<std::uint64_t>(iz + kCoordinateRange);
}

inline std::size_t slot_hash(std::uint64_t key, std::size_t mask) {
  key ^= key >> 33;
  key *= 0xff51afd7ed558ccdULL;  // murmur3 finaliser: spreads neighbouring cells over the table
  key ^= key >> 33;
  return static_cast<std::size_t>(key) & mask;
}

// The product of the two kernels' signal variances: Table 1's σ and σ_c read as standard
// deviations, so the amplitude is σ² σ_c² (see core::CvoParameters for the measurements).
double kernel_amplitude(const core::CvoParameters& p) { return p.sigma * p.sigma * p.sigma_color * p.sigma_color; }

// Whether the Gauss-Newton step ξ = H⁻¹ b is within one standard deviation of the estimate
// (registration.hpp, "Convergence"): ξᵀ Σ⁻¹ ξ = bᵀ B⁻¹ b < 1 with Σ = H⁻¹ B H⁻¹. False when B
// does not say (singular: too few clusters).
// Whether `label` (kFeatureDim values) is moving point j's label.
bool same_label(const float* label, const PointCloud& moving, std::size_t j) {
  for (std::size_t c = 0; c < kFeatureDim; ++c)
    if (label[c] != moving.feature_channel(c)[j]) return false;
  return true;
}

bool within_noise(const core::Vector6d& b, const core::Matrix6d& scatter) {
  const Eigen::LDLT<core::Matrix6d> ldlt(scatter);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) return false;
  const double score = b.dot(ldlt.solve(b));
  return std::isfinite(score) && score < 1.0;
}

bool all_finite(const PointCloud& cloud, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    float s = cloud.x()[i] + cloud.y()[i] + cloud.z()[i];
    for (std::size_t c = 0; c < kFeatureDim; ++c) s += cloud.feature_channel(c)[i];
    if (!std::isfinite(s)) return false;
  }
  return true;
}

}  // namespace

double kernel_reach(const core::CvoParameters& parameters, double ell) {
  const double log_ratio = std::log(kernel_amplitude(parameters) / parameters.sparsification_threshold);
  return log_ratio > 0 ? ell * std::sqrt(2.0 * log_ratio) : 0.0;
}

const char* to_string(RegistrationStatus status) {
  switch (status) {
    case RegistrationStatus::kOk: return "ok";
    case RegistrationStatus::kEmptyCloud: return "empty or tiny cloud";
    case RegistrationStatus::kNonFinite: return "non-finite point, label or initial pose";
    case RegistrationStatus::kCapacityExceeded: return "cloud larger than capacity, truncated";
    case RegistrationStatus::kNoOverlap: return "too few contributing pairs";
    case RegistrationStatus::kNotConverged: return "not converged within max_iterations";
    case RegistrationStatus::kBadParameters: return "kernel amplitude below the sparsification threshold";
  }
  return "unknown";
}

void Registration::Sums::add(const Sums& o) {
  s0 += o.s0;
  s1 += o.s1;
  s2 += o.s2;
  bt += o.bt;
  br += o.br;
  scatter += o.scatter;
  pairs += o.pairs;
  collections += o.collections;
  full_searches += o.full_searches;
}

core::Matrix6d Registration::Sums::hessian() const {
  core::Matrix6d H;
  H.topLeftCorner<3, 3>() = s0 * Eigen::Matrix3d::Identity();
  H.topRightCorner<3, 3>() = -core::hat(s1);
  H.bottomLeftCorner<3, 3>() = core::hat(s1);
  H.bottomRightCorner<3, 3>() = s2.trace() * Eigen::Matrix3d::Identity() - s2;
  return H;
}

Registration::Registration(const Capacities& capacities, const core::CvoParameters& parameters, kernel::Isa isa)
    : parameters_(parameters),
      isa_(isa),
      point_(kernel::point_function(isa)),
      collect_(kernel::collect_function(isa)),
      candidates_(kernel::candidate_function(isa)),
      capacity_(capacities.max_points),
      bucket_mask_(next_power_of_two(std::max<std::size_t>(1024, 2 * capacities.max_points)) - 1),
      slot_key_(bucket_mask_ + 1),
      bucket_start_(bucket_mask_ + 2),
      bucket_of_(capacities.max_points),
      px_(capacities.max_points),
      py_(capacities.max_points),
      pz_(capacities.max_points),
      sx_(capacities.max_points),
      sy_(capacities.max_points),
      sz_(capacities.max_points),
      slots_(std::min<std::size_t>(capacities.candidates_per_point, kUncollected - 1)),
      candidate_fixed_(capacities.max_points * slots_),
      candidate_colour_(capacities.max_points * slots_),
      candidate_count_(capacities.max_points, kUncollected),
      candidate_weight_(capacities.max_points, 1.0f),
      collected_label_(slots_ > 0 ? capacities.max_points * kFeatureDim : 0),
      moving_label_(collected_label_.size()),
      source_(slots_ > 0 ? capacities.max_points : 0),
      scratch_fixed_(slots_ > 0 ? capacities.max_points * static_cast<std::size_t>(std::max(parameters.threads, 1))
                                : 0),
      scratch_colour_(scratch_fixed_.size()),
      collected_at_(4 * capacities.max_points),
      chunk_sums_((capacities.max_points + kChunk - 1) / kChunk + 1),
      pairs_log_(static_cast<std::size_t>(std::max(parameters.max_iterations, 0)) + 1) {
  for (auto& channel : sf_) channel.resize(capacities.max_points);
  hashed_ = {
      px_.data(), py_.data(), pz_.data(), {sf_[0].data(), sf_[1].data(), sf_[2].data(), sf_[3].data(), sf_[4].data()}};
  summed_ = {
      sx_.data(), sy_.data(), sz_.data(), {sf_[0].data(), sf_[1].data(), sf_[2].data(), sf_[3].data(), sf_[4].data()}};
  if (isa_ != kernel::Isa::kScalar && kernel::best_isa() != isa_) isa_ = kernel::Isa::kScalar;  // what really runs
}

RegistrationStatus Registration::check(const PointCloud& fixed, const PointCloud& moving) const {
  const std::size_t nf = std::min(fixed.size(), capacity_), nm = std::min(moving.size(), capacity_);
  if (nf < kMinPoints || nm < kMinPoints) return RegistrationStatus::kEmptyCloud;
  if (!all_finite(fixed, nf) || !all_finite(moving, nm)) return RegistrationStatus::kNonFinite;
  const double amplitude = kernel_amplitude(parameters_);
  if (!(amplitude > parameters_.sparsification_threshold) || !(parameters_.ell_init > 0) ||
      !(parameters_.ell_min > 0) || !(parameters_.ell_color > 0))
    return RegistrationStatus::kBadParameters;
  return (fixed.size() > capacity_ || moving.size() > capacity_) ? RegistrationStatus::kCapacityExceeded
                                                                 : RegistrationStatus::kOk;
}

// The kernel constants at length-scale ℓ, r_max, and the slack s = slack_fraction r_max.
bool Registration::set_length_scale(double ell, double slack_fraction) {
  const double amplitude = kernel_amplitude(parameters_);
  const double reach = kernel_reach(parameters_, ell);
  if (!(reach > 0)) return false;
  r_max_ = static_cast<float>(reach);
  slack_ = static_cast<float>(slack_fraction) * r_max_;
  reach_sq_ = (r_max_ + slack_) * (r_max_ + slack_);
  constants_.inv_two_ell_sq = static_cast<float>(1.0 / (2.0 * ell * ell));
  constants_.inv_two_ell_color_sq = static_cast<float>(1.0 / (2.0 * parameters_.ell_color * parameters_.ell_color));
  constants_.log_amplitude = static_cast<float>(std::log(amplitude));
  constants_.log_threshold = static_cast<float>(std::log(parameters_.sparsification_threshold));
  return true;
}

// Hashes the fixed cloud into cells as wide as the reach at the present length-scale (r_max + s):
// the 27 cells around a point hold every fixed point within that reach, and within it at any
// smaller length-scale. Candidates collected before are forgotten.
bool Registration::build_grid(const PointCloud& fixed, std::size_t n, double ell, double slack_fraction) {
  if (!set_length_scale(ell, slack_fraction)) return false;
  cell_ = static_cast<double>(r_max_) + static_cast<double>(slack_);
  inv_cell_ = 1.0 / cell_;
  grid_ell_ = ell;
  grid_cloud_ = &fixed;
  grid_points_ = n;
  std::fill(candidate_count_.begin(), candidate_count_.end(), kUncollected);

  // Each occupied cell gets a slot of an open-addressing table (linear probing on the exact
  // key, so distinct cells never share a slot); then a counting sort by slot makes every cell's
  // points one contiguous run: bucket_start_[s] .. bucket_start_[s + 1].
  std::fill(slot_key_.begin(), slot_key_.end(), kEmptySlot);
  std::fill(bucket_start_.begin(), bucket_start_.end(), 0u);
  for (std::size_t i = 0; i < n; ++i) {
    const auto key = cell_key(cell_coordinate(fixed.x()[i], inv_cell_), cell_coordinate(fixed.y()[i], inv_cell_),
                              cell_coordinate(fixed.z()[i], inv_cell_));
    std::size_t slot = slot_hash(key, bucket_mask_);
    while (slot_key_[slot] != kEmptySlot && slot_key_[slot] != key) slot = (slot + 1) & bucket_mask_;
    slot_key_[slot] = key;
    bucket_of_[i] = static_cast<std::uint32_t>(slot);
    ++bucket_start_[slot + 1];
  }
  for (std::size_t b = 1; b < bucket_start_.size(); ++b) bucket_start_[b] += bucket_start_[b - 1];
  // Scatter, using bucket_start_[b] as a cursor, then shift back so it holds the starts again.
  for (std::size_t i = 0; i < n; ++i) {
    const auto dst = bucket_start_[bucket_of_[i]]++;
    px_[dst] = sx_[dst] = fixed.x()[i];
    py_[dst] = sy_[dst] = fixed.y()[i];
    pz_[dst] = sz_[dst] = fixed.z()[i];
    for (std::size_t c = 0; c < kFeatureDim; ++c) sf_[c][dst] = fixed.feature_channel(c)[i];
  }
  for (std::size_t b = bucket_start_.size() - 1; b > 0; --b) bucket_start_[b] = bucket_start_[b - 1];
  bucket_start_[0] = 0;
  return true;
}

// Reuse::kCandidates (see the header): the grid stays when it was built from this cloud for a
// length-scale at least as wide (cells as wide as the reach); each moving point takes the
// candidates of the last align()'s point with its label (match_moving_points).
bool Registration::keep_grid(const PointCloud& fixed, std::size_t n, double ell, const PointCloud& moving,
                             std::size_t nm) {
  if (grid_cloud_ != &fixed || grid_points_ != n || !(ell <= grid_ell_) || slots_ == 0) return false;
  if (!set_length_scale(ell, kSlackFraction) || static_cast<double>(reach_sq_) > cell_ * cell_) return false;
  match_moving_points(moving, nm);
  return true;
}

// A frame selected again keeps its pixels in order but may drop one (no depth where the new motion
// looks) or keep one it had dropped, which shifts every later index. So point j takes the list of
// the first point k at or after the last match, within kMatchWindow, whose label was j's: the
// pixels' order is kept, and a label all but names a pixel. A list is valid for any point with
// its label within its margin (point_sums checks where it was collected), so a coincidence of
// labels costs nothing but a collection.
void Registration::match_moving_points(const PointCloud& moving, std::size_t nm) {
  std::size_t k = 0;
  for (std::size_t j = 0; j < nm; ++j) {
    source_[j] = kNoSource;
    for (std::size_t d = 0; d < kMatchWindow && k + d < labelled_points_; ++d) {
      if (!same_label(&moving_label_[kFeatureDim * (k + d)], moving, j)) continue;
      source_[j] = static_cast<std::uint32_t>(k + d);
      k += d + 1;
      break;
    }
  }
  // The sources increase with j, so lists moving up (source < j) are moved from the last one
  // down, and lists moving down from the first one up: no list is overwritten before it moves.
  for (std::size_t j = nm; j-- > 0;)
    if (source_[j] < j) move_candidates(source_[j], j);
  for (std::size_t j = 0; j < nm; ++j)
    if (source_[j] != kNoSource && source_[j] > j) move_candidates(source_[j], j);
  for (std::size_t j = 0; j < nm; ++j)
    if (source_[j] == kNoSource || !same_label(&collected_label_[kFeatureDim * j], moving, j))
      candidate_count_[j] = kUncollected;
}

void Registration::move_candidates(std::size_t from, std::size_t to) {
  const std::uint16_t count = candidate_count_[from];
  candidate_count_[to] = count;
  if (count == kUncollected) return;
  std::copy_n(&candidate_fixed_[from * slots_], count, &candidate_fixed_[to * slots_]);
  std::copy_n(&candidate_colour_[from * slots_], count, &candidate_colour_[to * slots_]);
  candidate_weight_[to] = candidate_weight_[from];
  std::copy_n(&collected_label_[kFeatureDim * from], kFeatureDim, &collected_label_[kFeatureDim * to]);
  std::copy_n(&collected_at_[4 * from], 4, &collected_at_[4 * to]);
}

// The moving points' labels in their order, for the next align()'s match_moving_points.
void Registration::record_labels(const PointCloud& moving, std::size_t nm) {
  for (std::size_t j = 0; j < nm; ++j)
    for (std::size_t c = 0; c < kFeatureDim; ++c) moving_label_[kFeatureDim * j + c] = moving.feature_channel(c)[j];
  labelled_points_ = nm;
}

bool Registration::View::sees(const Eigen::Vector3f& p) const {
  if (!(p.z() > 0)) return false;
  const float u = p.x() / p.z(), v = p.y() / p.z();
  return u >= x0 && u <= x1 && v >= y0 && v <= y1;
}

Registration::View Registration::view_of(const PointCloud& cloud, std::size_t n) {
  View v{std::numeric_limits<float>::max(), -std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
         -std::numeric_limits<float>::max()};
  for (std::size_t i = 0; i < n; ++i) {
    if (!(cloud.z()[i] > 0)) continue;
    const float u = cloud.x()[i] / cloud.z()[i], w = cloud.y()[i] / cloud.z()[i];
    v.x0 = std::min(v.x0, u);
    v.x1 = std::max(v.x1, u);
    v.y0 = std::min(v.y0, w);
    v.y1 = std::max(v.y1, w);
  }
  return v;
}

// Fixed points the moving camera (at T) does not see are moved out of every kernel's reach in the
// copy the sums read (a hidden point then adds nothing to any sum). Candidates are collected from
// the other copy, which keeps every point where it is: a point seen again is in the lists already.
void Registration::hide_fixed_unseen(std::size_t n, const core::SE3& T) {
  const core::SE3 T_inv = T.inverse();
  const Eigen::Matrix3f R = T_inv.rotation_matrix().cast<float>();
  const Eigen::Vector3f t = T_inv.translation().cast<float>();
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3f x(px_[k], py_[k], pz_[k]);
    const bool seen = moving_view_.sees(R * x + t);
    sx_[k] = seen ? x.x() : kFar;
    sy_[k] = seen ? x.y() : kFar;
    sz_[k] = seen ? x.z() : kFar;
  }
}

void Registration::find_cells(const Eigen::Vector3f& w, Cells& cells) const {
  const auto cx = cell_coordinate(w.x(), inv_cell_), cy = cell_coordinate(w.y(), inv_cell_),
             cz = cell_coordinate(w.z(), inv_cell_);
  if (cells.valid && cx == cells.cx && cy == cells.cy && cz == cells.cz) return;
  cells = {};
  cells.cx = cx;
  cells.cy = cy;
  cells.cz = cz;
  cells.valid = true;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const auto key = cell_key(cx + dx, cy + dy, cz + dz);
        for (std::size_t slot = slot_hash(key, bucket_mask_); slot_key_[slot] != kEmptySlot;
             slot = (slot + 1) & bucket_mask_) {
          if (slot_key_[slot] != key) continue;
          cells.ranges[cells.count++] = {bucket_start_[slot], bucket_start_[slot + 1]};
          break;
        }
      }
}

// Moving point j's candidates at w (kernel::CollectFunction, into this thread's scratch, which
// holds every fixed point): all of them when they fit its slots; else the budget (see the header):
// every m-th from phase j mod m, each weighted by how many it stands for.
void Registration::collect_candidates(std::size_t j, const Eigen::Vector3f& w, const float* feature,
                                      const Cells& cells) {
  const float wf[3] = {w.x(), w.y(), w.z()};
  const std::size_t scratch = static_cast<std::size_t>(omp_get_thread_num()) * capacity_;
  std::uint32_t* found = &scratch_fixed_[scratch];
  float* found_colour = &scratch_colour_[scratch];
  const std::size_t count =
      collect_(hashed_, cells.ranges, cells.count, wf, feature, constants_, reach_sq_, found, found_colour, capacity_);
  const std::size_t m = std::max<std::size_t>(1, (count + slots_ - 1) / slots_);
  const std::size_t base = j * slots_;
  std::size_t kept = 0;
  for (std::size_t k = m > 1 ? j % m : 0; k < count; k += m, ++kept) {
    candidate_fixed_[base + kept] = found[k];
    candidate_colour_[base + kept] = found_colour[k];
  }
  candidate_count_[j] = static_cast<std::uint16_t>(kept);
  for (std::size_t c = 0; c < kFeatureDim; ++c) collected_label_[kFeatureDim * j + c] = feature[c];
  candidate_weight_[j] = kept > 0 ? static_cast<float>(count) / static_cast<float>(kept) : 1.0f;
  collected_at_[4 * j] = w.x();
  collected_at_[4 * j + 1] = w.y();
  collected_at_[4 * j + 2] = w.z();
  collected_at_[4 * j + 3] = std::sqrt(reach_sq_);
}

// The kernel over point j's candidates, each pair weighted by what its candidate stands for (1
// unless the budget thinned them).
kernel::PointSums Registration::candidate_sums(std::size_t j, const Eigen::Vector3f& w) const {
  const float wf[3] = {w.x(), w.y(), w.z()};
  const std::size_t base = j * slots_;
  kernel::PointSums p =
      candidates_(summed_, &candidate_fixed_[base], &candidate_colour_[base], candidate_count_[j], wf, constants_);
  const float weight = candidate_weight_[j];
  p.a *= weight, p.dx *= weight, p.dy *= weight, p.dz *= weight;
  return p;
}

// Σ_i a_ij and Σ_i a_ij (x_i - w) for moving point j at w: from its candidates, collected again
// once it moved more than the slack; without slots, by searching the cells.
kernel::PointSums Registration::point_sums(std::size_t j, const Eigen::Vector3f& w, const float* feature, Cells& cells,
                                           bool candidates, Sums& counts) {
  if (candidates && slots_ > 0) {
    // Valid while every fixed point now within r_max was within the reach at collection.
    const float* at = &collected_at_[4 * j];
    const float mx = w.x() - at[0], my = w.y() - at[1], mz = w.z() - at[2];
    const float margin = at[3] - r_max_;
    if (candidate_count_[j] == kUncollected || mx * mx + my * my + mz * mz > margin * margin) {
      find_cells(w, cells);
      collect_candidates(j, w, feature, cells);
      ++counts.collections;
    }
    return candidate_sums(j, w);
  }
  find_cells(w, cells);
  if (cells.count == 0) return {};
  if (candidates) ++counts.full_searches;
  const float wf[3] = {w.x(), w.y(), w.z()};
  return point_(summed_, cells.ranges, cells.count, wf, feature, constants_);
}

void Registration::accumulate(const PointCloud& moving, std::size_t n, const core::SE3& T, Sums& total,
                              std::size_t stride, bool candidates) {
  const Eigen::Matrix3f R = T.rotation_matrix().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  const auto chunks = static_cast<std::ptrdiff_t>((n + kChunk - 1) / kChunk);

#pragma omp parallel for schedule(static) num_threads(parameters_.threads) if (parameters_.threads > 1)
  for (std::ptrdiff_t chunk = 0; chunk < chunks; ++chunk) {
    Sums sums;
    Cells cells;
    core::Vector6d cluster = core::Vector6d::Zero();
    const std::size_t begin = static_cast<std::size_t>(chunk) * kChunk, end = std::min(n, begin + kChunk);
    for (std::size_t j = begin + (stride - begin % stride) % stride; j < end; j += stride) {
      if ((j - begin) % kScatterCluster == 0) {
        sums.scatter += cluster * cluster.transpose();
        cluster.setZero();
      }
      const Eigen::Vector3f w = R * moving.position(j) + t;
      if (candidates && visibility_ && !fixed_view_.sees(w)) continue;
      float feature[kFeatureDim];
      for (std::size_t c = 0; c < kFeatureDim; ++c) feature[c] = moving.feature_channel(c)[j];
      const kernel::PointSums p = point_sums(j, w, feature, cells, candidates, sums);
      if (p.pairs == 0) continue;
      const Eigen::Vector3d wd = w.cast<double>();
      const Eigen::Vector3d D(p.dx, p.dy, p.dz);
      sums.s0 += p.a;
      sums.s1 += p.a * wd;
      sums.s2 += p.a * wd * wd.transpose();
      sums.bt += D;
      sums.br += wd.cross(D);
      cluster.head<3>() += D;
      cluster.tail<3>() += wd.cross(D);
      sums.pairs += p.pairs;
    }
    sums.scatter += cluster * cluster.transpose();
    chunk_sums_[static_cast<std::size_t>(chunk)] = sums;
  }
  total = Sums{};
  for (std::ptrdiff_t chunk = 0; chunk < chunks; ++chunk) total.add(chunk_sums_[static_cast<std::size_t>(chunk)]);
}

double Registration::inner_product(const PointCloud& fixed, const PointCloud& moving, const core::SE3& T, double ell,
                                   std::size_t stride) {
  const auto status = check(fixed, moving);
  if (status != RegistrationStatus::kOk && status != RegistrationStatus::kCapacityExceeded) return 0.0;
  if (!T.is_finite() || !(ell > 0)) return 0.0;
  const std::size_t nf = std::min(fixed.size(), capacity_), nm = std::min(moving.size(), capacity_);
  if (!build_grid(fixed, nf, ell, 0.0)) return 0.0;
  Sums sums;
  accumulate(moving, nm, T, sums, std::max<std::size_t>(stride, 1));
  return sums.s0;
}

RegistrationResult Registration::align(const PointCloud& fixed, const PointCloud& moving, const core::SE3& initial,
                                       double ell_start, Reuse reuse) {
  RegistrationResult result;
  result.transform = initial;
  pairs_logged_ = 0;
  collections_ = 0;
  full_searches_ = 0;
  result.status = check(fixed, moving);
  if (result.status == RegistrationStatus::kOk && !initial.is_finite()) result.status = RegistrationStatus::kNonFinite;
  if (result.status != RegistrationStatus::kOk && result.status != RegistrationStatus::kCapacityExceeded) return result;
  const RegistrationStatus input_status = result.status;
  const std::size_t nf = std::min(fixed.size(), capacity_), nm = std::min(moving.size(), capacity_);

  const double ell_min = std::min(parameters_.ell_min, parameters_.ell_init);
  double ell = ell_start > 0 ? std::max(ell_start, ell_min) : parameters_.ell_init;
  if (reuse != Reuse::kCandidates || !keep_grid(fixed, nf, ell, moving, nm))
    build_grid(fixed, nf, ell, slots_ > 0 ? kSlackFraction : 0.0);
  if (slots_ > 0) record_labels(moving, nm);
  visibility_ = parameters_.mutual_visibility;
  if (visibility_) {
    fixed_view_ = view_of(fixed, nf);
    moving_view_ = view_of(moving, nm);
    hide_fixed_unseen(nf, initial);
  }
  core::SE3 T = initial;
  Sums sums;
  result.status = RegistrationStatus::kNotConverged;
  for (int it = 0; it < parameters_.max_iterations; ++it) {
    accumulate(moving, nm, T, sums, 1, true);
    collections_ += sums.collections;
    full_searches_ += sums.full_searches;
    result.iterations = it + 1;
    result.pairs = sums.pairs;
    result.inner_product = sums.s0;
    result.final_ell = ell;
    result.hessian = sums.hessian() / (ell * ell);
    result.gradient_scatter = sums.scatter / (ell * ell * ell * ell);
    if (pairs_logged_ < pairs_log_.size()) pairs_log_[pairs_logged_++] = sums.pairs;
    if (sums.pairs < kMinPairs) {
      result.status = RegistrationStatus::kNoOverlap;
      break;
    }
    core::Matrix6d H = sums.hessian();
    H.diagonal().array() += 1e-9 * H.diagonal().maxCoeff();  // keeps a degenerate H solvable
    core::Vector6d b;
    b << sums.bt, sums.br;
    core::Vector6d xi = H.ldlt().solve(b);
    if (!xi.allFinite()) {
      result.status = RegistrationStatus::kNoOverlap;
      break;
    }
    // Trust region: at most ℓ of translation and kMaxRotationStep of rotation per iteration.
    const double scale = std::min(
        {1.0, ell / std::max(xi.head<3>().norm(), 1e-12), kMaxRotationStep / std::max(xi.tail<3>().norm(), 1e-12)});
    xi *= scale;
    T = core::SE3::exp(xi) * T;
    const double step = xi.head<3>().norm() + xi.tail<3>().norm();
    const bool settled = within_noise(b, sums.scatter);
    if (ell <= ell_min && (step < parameters_.min_step || settled)) {
      result.converged = true;
      result.status = input_status;
      break;
    }
    if (ell > ell_min && (step < kShrinkFraction * ell || settled)) {
      ell = std::max(ell * parameters_.ell_decay, ell_min);
      // The grid and the candidates of the wider kernel serve the narrower one (a superset).
      if (slots_ > 0)
        set_length_scale(ell, kSlackFraction);
      else
        build_grid(fixed, nf, ell, 0.0);
      if (visibility_) hide_fixed_unseen(nf, T);
    }
  }
  result.transform = T;
  return result;
}

}  // namespace cvo::registration
