#pragma once
// The pair loop of the CVO inner product, eq. (6) of the paper:
//
//   F(T) = Σ_ij  c_ij · k(x_i, T z_j),
//   k(x, w)  = s   · exp(-|x - w|² / (2 ℓ²))        spatial kernel, signal variance s = σ
//   c_ij     = s_c · exp(-|ℓ(x_i) - ℓ(z_j)|² / (2 ℓ_c²))   colour kernel, signal variance s_c = σ_c
//
// A pair counts only when its product a_ij = c_ij k(x_i, T z_j) reaches the sparsification
// threshold; since c_ij ≤ s_c, such a pair lies within r_max = ℓ sqrt(2 ln(s s_c / threshold)) of
// T z_j, which is what lets the neighbour search visit only nearby hash cells.
//
// For one moving point w = T z_j and a set of candidate fixed points, a kernel returns
//   Σ_i a_ij,  Σ_i a_ij (x_i - w)  and the number of contributing pairs,
// which is all the solver needs (see registration.cpp). Scalar, AVX2+FMA (x86-64) and NEON (AArch64)
// versions exist; they agree to float rounding (the SIMD exp is a polynomial with ~2 ulp error).
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "libcvo/registration/feature.hpp"  // not point_cloud.hpp: this header is also built for AVX2

namespace cvo::registration::kernel {

struct Constants {
  float inv_two_ell_sq = 0;        // 1 / (2 ℓ²)
  float inv_two_ell_color_sq = 0;  // 1 / (2 ℓ_c²)
  float log_amplitude = 0;         // ln(s s_c)
  float log_threshold = 0;         // ln(threshold): keep a pair iff its log a_ij ≥ this
};

/// The fixed cloud as the kernels read it: SoA arrays in hash-bucket order.
struct FixedCloudView {
  const float* x;
  const float* y;
  const float* z;
  const float* f[kFeatureDim];
};

/// A half-open run [begin, end) of fixed points (one hash bucket).
struct Range {
  std::uint32_t begin, end;
};

struct PointSums {
  float a = 0;                   // Σ a_ij
  float dx = 0, dy = 0, dz = 0;  // Σ a_ij (x_i - w)
  std::uint32_t pairs = 0;
};

/// One pair, a = exp(log_a) at offset (dx, dy, dz) = x_i - w, into `sums` when it reaches the
/// threshold: the scalar kernels' arithmetic.
inline void add_pair(PointSums& sums, float log_a, float dx, float dy, float dz, const Constants& k) {
  if (log_a < k.log_threshold) return;
  const float a = std::exp(log_a);
  sums.a += a;
  sums.dx += a * dx;
  sums.dy += a * dy;
  sums.dz += a * dz;
  ++sums.pairs;
}

using PointFunction = PointSums (*)(const FixedCloudView& fixed, const Range* ranges, int range_count, const float w[3],
                                    const float feature[kFeatureDim], const Constants& k);

PointSums point_scalar(const FixedCloudView& fixed, const Range* ranges, int range_count, const float w[3],
                       const float feature[kFeatureDim], const Constants& k);
#if defined(CVO_HAVE_AVX2)
PointSums point_avx2(const FixedCloudView& fixed, const Range* ranges, int range_count, const float w[3],
                     const float feature[kFeatureDim], const Constants& k);
#endif
#if defined(CVO_HAVE_NEON)
PointSums point_neon(const FixedCloudView& fixed, const Range* ranges, int range_count, const float w[3],
                     const float feature[kFeatureDim], const Constants& k);
#endif

/// Candidate pairs (registration.hpp): the fixed points of `ranges` within sqrt(reach_sq) of w
/// whose colour term c = |Δf|² / 2ℓ_c² alone leaves the threshold reachable (log_amplitude - c ≥
/// log_threshold), in range order: their indices into `index`, their colour terms into `colour`.
/// Returns how many, or capacity + 1 as soon as there are more than `capacity`.
using CollectFunction = std::size_t (*)(const FixedCloudView& fixed, const Range* ranges, int range_count,
                                        const float w[3], const float feature[kFeatureDim], const Constants& k,
                                        float reach_sq, std::uint32_t* index, float* colour, std::size_t capacity);

std::size_t collect_scalar(const FixedCloudView& fixed, const Range* ranges, int range_count, const float w[3],
                           const float feature[kFeatureDim], const Constants& k, float reach_sq, std::uint32_t* index,
                           float* colour, std::size_t capacity);
#if defined(CVO_HAVE_AVX2)
std::size_t collect_avx2(const FixedCloudView& fixed, const Range* ranges, int range_count, const float w[3],
                         const float feature[kFeatureDim], const Constants& k, float reach_sq, std::uint32_t* index,
                         float* colour, std::size_t capacity);
#endif

/// The pairs of one moving point at w with its candidates (registration.hpp): fixed point
/// index[k] and its colour term colour[k], k < count; the sums as a PointFunction's.
using CandidateFunction = PointSums (*)(const FixedCloudView& fixed, const std::uint32_t* index, const float* colour,
                                        std::size_t count, const float w[3], const Constants& k);

PointSums candidates_scalar(const FixedCloudView& fixed, const std::uint32_t* index, const float* colour,
                            std::size_t count, const float w[3], const Constants& k);
#if defined(CVO_HAVE_AVX2)
PointSums candidates_avx2(const FixedCloudView& fixed, const std::uint32_t* index, const float* colour,
                          std::size_t count, const float w[3], const Constants& k);
#endif

enum class Isa { kScalar, kAvx2, kNeon };
/// The best kernel this CPU runs (AVX2+FMA when built in and supported; NEON on AArch64, where it
/// is always present), or the requested one.
Isa best_isa();
PointFunction point_function(Isa isa);
CollectFunction collect_function(Isa isa);      // NEON: the scalar one (collection is rare)
CandidateFunction candidate_function(Isa isa);  // NEON: the scalar one
const char* to_string(Isa isa);

}  // namespace cvo::registration::kernel
