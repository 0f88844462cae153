// Compiled with -mavx2 -mfma; only called after a runtime check of the CPU.
#include <immintrin.h>

#include "libcvo/registration/kernel.hpp"

namespace cvo::registration::kernel {
namespace {

// exp(x) for x in about [-88, 0]: x = n ln2 + r, |r| <= ln2/2, exp(r) by a degree-6 polynomial
// (Cephes expf coefficients), 2^n through the exponent bits. Relative error ~2e-7.
inline __m256 exp256(__m256 x) {
  x = _mm256_max_ps(x, _mm256_set1_ps(-87.0f));
  const __m256 n = _mm256_round_ps(_mm256_mul_ps(x, _mm256_set1_ps(1.44269504088896341f)),
                                   _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
  __m256 r = _mm256_fnmadd_ps(n, _mm256_set1_ps(0.693359375f), x);
  r = _mm256_fnmadd_ps(n, _mm256_set1_ps(-2.12194440e-4f), r);
  __m256 p = _mm256_set1_ps(1.9875691500e-4f);
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.3981999507e-3f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(8.3334519073e-3f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(4.1665795894e-2f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(1.6666665459e-1f));
  p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(5.0000001201e-1f));
  p = _mm256_fmadd_ps(p, _mm256_mul_ps(r, r), _mm256_add_ps(r, _mm256_set1_ps(1.0f)));
  const __m256i e = _mm256_slli_epi32(_mm256_add_epi32(_mm256_cvtps_epi32(n), _mm256_set1_epi32(127)), 23);
  return _mm256_mul_ps(p, _mm256_castsi256_ps(e));
}

inline float horizontal_sum(__m256 v) {
  const __m128 s = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  const __m128 t = _mm_add_ps(s, _mm_movehl_ps(s, s));
  return _mm_cvtss_f32(_mm_add_ss(t, _mm_shuffle_ps(t, t, 1)));
}

// Eight fixed points against one moving point w: their offsets x_i - w, squared distances and
// squared colour distances, and which lanes hold points (the tail of a run is masked: lanes past
// its end read nothing).
struct Lanes {
  __m256i mask;
  __m256 dx, dy, dz, r2;
};

struct Point {
  __m256 wx, wy, wz;
  __m256 f[kFeatureDim];
  Point(const float w[3], const float feature[kFeatureDim])
      : wx(_mm256_set1_ps(w[0])), wy(_mm256_set1_ps(w[1])), wz(_mm256_set1_ps(w[2])) {
    for (std::size_t c = 0; c < kFeatureDim; ++c) f[c] = _mm256_set1_ps(feature[c]);
  }
};

inline Lanes offsets(const FixedCloudView& fixed, std::uint32_t i, std::uint32_t end, const Point& p) {
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  Lanes l;
  l.mask = _mm256_cmpgt_epi32(_mm256_set1_epi32(static_cast<int>(end - i)), lane);
  l.dx = _mm256_sub_ps(_mm256_maskload_ps(fixed.x + i, l.mask), p.wx);
  l.dy = _mm256_sub_ps(_mm256_maskload_ps(fixed.y + i, l.mask), p.wy);
  l.dz = _mm256_sub_ps(_mm256_maskload_ps(fixed.z + i, l.mask), p.wz);
  l.r2 = _mm256_fmadd_ps(l.dz, l.dz, _mm256_fmadd_ps(l.dy, l.dy, _mm256_mul_ps(l.dx, l.dx)));
  return l;
}

inline __m256 colour_distance_sq(const FixedCloudView& fixed, std::uint32_t i, const Lanes& l, const Point& p) {
  __m256 c2 = _mm256_setzero_ps();
  for (std::size_t c = 0; c < kFeatureDim; ++c) {
    const __m256 d = _mm256_sub_ps(_mm256_maskload_ps(fixed.f[c] + i, l.mask), p.f[c]);
    c2 = _mm256_fmadd_ps(d, d, c2);
  }
  return c2;
}

}  // namespace

PointSums point_avx2(const FixedCloudView& fixed, const Range* ranges, int range_count, const float w[3],
                     const float feature[kFeatureDim], const Constants& k) {
  const Point p(w, feature);
  const __m256 inv_s = _mm256_set1_ps(k.inv_two_ell_sq), inv_c = _mm256_set1_ps(k.inv_two_ell_color_sq);
  const __m256 log_amp = _mm256_set1_ps(k.log_amplitude), log_thr = _mm256_set1_ps(k.log_threshold);
  __m256 sa = _mm256_setzero_ps(), sx = _mm256_setzero_ps(), sy = _mm256_setzero_ps(), sz = _mm256_setzero_ps();
  std::uint32_t pairs = 0;

  for (int r = 0; r < range_count; ++r) {
    for (std::uint32_t i = ranges[r].begin; i < ranges[r].end; i += 8) {
      const Lanes l = offsets(fixed, i, ranges[r].end, p);
      const __m256 c2 = colour_distance_sq(fixed, i, l, p);
      const __m256 log_a = _mm256_fnmadd_ps(c2, inv_c, _mm256_fnmadd_ps(l.r2, inv_s, log_amp));
      const __m256 keep = _mm256_and_ps(_mm256_cmp_ps(log_a, log_thr, _CMP_GE_OQ), _mm256_castsi256_ps(l.mask));
      const int bits = _mm256_movemask_ps(keep);
      if (bits == 0) continue;
      pairs += static_cast<std::uint32_t>(__builtin_popcount(static_cast<unsigned>(bits)));
      const __m256 a = _mm256_and_ps(exp256(log_a), keep);
      sa = _mm256_add_ps(sa, a);
      sx = _mm256_fmadd_ps(a, l.dx, sx);
      sy = _mm256_fmadd_ps(a, l.dy, sy);
      sz = _mm256_fmadd_ps(a, l.dz, sz);
    }
  }
  return {horizontal_sum(sa), horizontal_sum(sx), horizontal_sum(sy), horizontal_sum(sz), pairs};
}

// Eight candidates at a time: their positions gathered by index (the candidates of one point lie
// in a few neighbouring cells, so the gathers hit cache), their colour terms loaded.
PointSums candidates_avx2(const FixedCloudView& fixed, const std::uint32_t* index, const float* colour,
                          std::size_t count, const float w[3], const Constants& k) {
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256 wx = _mm256_set1_ps(w[0]), wy = _mm256_set1_ps(w[1]), wz = _mm256_set1_ps(w[2]);
  const __m256 inv_s = _mm256_set1_ps(k.inv_two_ell_sq);
  const __m256 log_amp = _mm256_set1_ps(k.log_amplitude), log_thr = _mm256_set1_ps(k.log_threshold);
  __m256 sa = _mm256_setzero_ps(), sx = _mm256_setzero_ps(), sy = _mm256_setzero_ps(), sz = _mm256_setzero_ps();
  std::uint32_t pairs = 0;
  for (std::size_t c = 0; c < count; c += 8) {
    const __m256i mask = _mm256_cmpgt_epi32(_mm256_set1_epi32(static_cast<int>(count - c)), lane);
    const __m256 fmask = _mm256_castsi256_ps(mask);
    const __m256i i = _mm256_maskload_epi32(reinterpret_cast<const int*>(index + c), mask);
    const __m256 zero = _mm256_setzero_ps();
    const __m256 dx = _mm256_sub_ps(_mm256_mask_i32gather_ps(zero, fixed.x, i, fmask, 4), wx);
    const __m256 dy = _mm256_sub_ps(_mm256_mask_i32gather_ps(zero, fixed.y, i, fmask, 4), wy);
    const __m256 dz = _mm256_sub_ps(_mm256_mask_i32gather_ps(zero, fixed.z, i, fmask, 4), wz);
    const __m256 r2 = _mm256_fmadd_ps(dz, dz, _mm256_fmadd_ps(dy, dy, _mm256_mul_ps(dx, dx)));
    const __m256 log_a = _mm256_sub_ps(_mm256_fnmadd_ps(r2, inv_s, log_amp), _mm256_maskload_ps(colour + c, mask));
    const __m256 keep = _mm256_and_ps(_mm256_cmp_ps(log_a, log_thr, _CMP_GE_OQ), fmask);
    const int bits = _mm256_movemask_ps(keep);
    if (bits == 0) continue;
    pairs += static_cast<std::uint32_t>(__builtin_popcount(static_cast<unsigned>(bits)));
    const __m256 a = _mm256_and_ps(exp256(log_a), keep);
    sa = _mm256_add_ps(sa, a);
    sx = _mm256_fmadd_ps(a, dx, sx);
    sy = _mm256_fmadd_ps(a, dy, sy);
    sz = _mm256_fmadd_ps(a, dz, sz);
  }
  return {horizontal_sum(sa), horizontal_sum(sx), horizontal_sum(sy), horizontal_sum(sz), pairs};
}

std::size_t collect_avx2(const FixedCloudView& fixed, const Range* ranges, int range_count, const float w[3],
                         const float feature[kFeatureDim], const Constants& k, float reach_sq, std::uint32_t* index,
                         float* colour, std::size_t capacity) {
  const Point p(w, feature);
  const __m256 inv_c = _mm256_set1_ps(k.inv_two_ell_color_sq), reach = _mm256_set1_ps(reach_sq);
  const __m256 max_colour = _mm256_set1_ps(k.log_amplitude - k.log_threshold);
  std::size_t count = 0;
  alignas(32) float terms[8];
  for (int r = 0; r < range_count; ++r) {
    for (std::uint32_t i = ranges[r].begin; i < ranges[r].end; i += 8) {
      const Lanes l = offsets(fixed, i, ranges[r].end, p);
      const __m256 near = _mm256_and_ps(_mm256_cmp_ps(l.r2, reach, _CMP_LE_OQ), _mm256_castsi256_ps(l.mask));
      if (_mm256_movemask_ps(near) == 0) continue;
      const __m256 term = _mm256_mul_ps(colour_distance_sq(fixed, i, l, p), inv_c);
      auto bits =
          static_cast<unsigned>(_mm256_movemask_ps(_mm256_and_ps(near, _mm256_cmp_ps(term, max_colour, _CMP_LE_OQ))));
      if (bits == 0) continue;
      _mm256_store_ps(terms, term);
      for (; bits != 0; bits &= bits - 1) {  // the lanes kept, in order
        if (count == capacity) return capacity + 1;
        const auto lane_index = static_cast<unsigned>(__builtin_ctz(bits));
        index[count] = i + lane_index;
        colour[count++] = terms[lane_index];
      }
    }
  }
  return count;
}

}  // namespace cvo::registration::kernel
