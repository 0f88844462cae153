// AArch64 only: Advanced SIMD (NEON) is part of the base ARMv8-A ISA, so no runtime check is needed.
#include <arm_neon.h>

#include "libcvo/registration/kernel.hpp"

namespace cvo::registration::kernel {
namespace {

// exp(x) for x in about [-88, 0], as exp256 in kernel_avx2.cpp: x = n ln2 + r, |r| <= ln2/2,
// exp(r) by a degree-6 polynomial (Cephes expf coefficients), 2^n through the exponent bits.
inline float32x4_t exp128(float32x4_t x) {
  x = vmaxq_f32(x, vdupq_n_f32(-87.0f));
  const float32x4_t n = vrndnq_f32(vmulq_f32(x, vdupq_n_f32(1.44269504088896341f)));  // to nearest, ties even
  float32x4_t r = vfmsq_f32(x, n, vdupq_n_f32(0.693359375f));                         // x - n * c1
  r = vfmsq_f32(r, n, vdupq_n_f32(-2.12194440e-4f));                                  // r - n * c2
  float32x4_t p = vdupq_n_f32(1.9875691500e-4f);
  p = vfmaq_f32(vdupq_n_f32(1.3981999507e-3f), p, r);
  p = vfmaq_f32(vdupq_n_f32(8.3334519073e-3f), p, r);
  p = vfmaq_f32(vdupq_n_f32(4.1665795894e-2f), p, r);
  p = vfmaq_f32(vdupq_n_f32(1.6666665459e-1f), p, r);
  p = vfmaq_f32(vdupq_n_f32(5.0000001201e-1f), p, r);
  p = vfmaq_f32(vaddq_f32(r, vdupq_n_f32(1.0f)), p, vmulq_f32(r, r));
  const int32x4_t e = vshlq_n_s32(vaddq_s32(vcvtnq_s32_f32(n), vdupq_n_s32(127)), 23);
  return vmulq_f32(p, vreinterpretq_f32_s32(e));
}

struct Block {
  float32x4_t x, y, z, f[kFeatureDim];
};

inline Block load_full(const FixedCloudView& fixed, std::uint32_t i) {
  Block b;
  b.x = vld1q_f32(fixed.x + i);
  b.y = vld1q_f32(fixed.y + i);
  b.z = vld1q_f32(fixed.z + i);
  for (std::size_t c = 0; c < kFeatureDim; ++c) b.f[c] = vld1q_f32(fixed.f[c] + i);
  return b;
}

// The last 1..3 points of a run, through zero-padded local copies: never reads past the run's end.
inline Block load_tail(const FixedCloudView& fixed, std::uint32_t i, std::uint32_t count) {
  alignas(16) float buf[3 + kFeatureDim][4] = {};
  for (std::uint32_t l = 0; l < count; ++l) {
    buf[0][l] = fixed.x[i + l];
    buf[1][l] = fixed.y[i + l];
    buf[2][l] = fixed.z[i + l];
    for (std::size_t c = 0; c < kFeatureDim; ++c) buf[3 + c][l] = fixed.f[c][i + l];
  }
  Block b;
  b.x = vld1q_f32(buf[0]);
  b.y = vld1q_f32(buf[1]);
  b.z = vld1q_f32(buf[2]);
  for (std::size_t c = 0; c < kFeatureDim; ++c) b.f[c] = vld1q_f32(buf[3 + c]);
  return b;
}

}  // namespace

PointSums point_neon(const FixedCloudView& fixed, const Range* ranges, int range_count, const float w[3],
                     const float feature[kFeatureDim], const Constants& k) {
  const float32x4_t wx = vdupq_n_f32(w[0]), wy = vdupq_n_f32(w[1]), wz = vdupq_n_f32(w[2]);
  float32x4_t fz[kFeatureDim];
  for (std::size_t c = 0; c < kFeatureDim; ++c) fz[c] = vdupq_n_f32(feature[c]);
  const float32x4_t inv_s = vdupq_n_f32(k.inv_two_ell_sq), inv_c = vdupq_n_f32(k.inv_two_ell_color_sq);
  const float32x4_t log_amp = vdupq_n_f32(k.log_amplitude), log_thr = vdupq_n_f32(k.log_threshold);
  const uint32x4_t lane = {0, 1, 2, 3};
  float32x4_t sa = vdupq_n_f32(0), sx = vdupq_n_f32(0), sy = vdupq_n_f32(0), sz = vdupq_n_f32(0);
  std::uint32_t pairs = 0;

  for (int r = 0; r < range_count; ++r) {
    const std::uint32_t end = ranges[r].end;
    for (std::uint32_t i = ranges[r].begin; i < end; i += 4) {
      const std::uint32_t remaining = end - i;
      const bool full = remaining >= 4;
      const Block b = full ? load_full(fixed, i) : load_tail(fixed, i, remaining);
      // Lanes past the run's end hold zeros (see load_tail) and are masked out of the keep mask.
      const uint32x4_t valid = vcltq_u32(lane, vdupq_n_u32(remaining));
      const float32x4_t dx = vsubq_f32(b.x, wx), dy = vsubq_f32(b.y, wy), dz = vsubq_f32(b.z, wz);
      float32x4_t r2 = vmulq_f32(dx, dx);
      r2 = vfmaq_f32(r2, dy, dy);
      r2 = vfmaq_f32(r2, dz, dz);
      float32x4_t c2 = vdupq_n_f32(0);
      for (std::size_t c = 0; c < kFeatureDim; ++c) {
        const float32x4_t d = vsubq_f32(b.f[c], fz[c]);
        c2 = vfmaq_f32(c2, d, d);
      }
      const float32x4_t log_a = vfmsq_f32(vfmsq_f32(log_amp, r2, inv_s), c2, inv_c);
      const uint32x4_t keep = vandq_u32(vcgeq_f32(log_a, log_thr), valid);
      if (vmaxvq_u32(keep) == 0) continue;
      pairs += vaddvq_u32(vshrq_n_u32(keep, 31));  // popcount of the keep mask: one bit per kept lane
      const float32x4_t a = vreinterpretq_f32_u32(vandq_u32(vreinterpretq_u32_f32(exp128(log_a)), keep));
      sa = vaddq_f32(sa, a);
      sx = vfmaq_f32(sx, a, dx);
      sy = vfmaq_f32(sy, a, dy);
      sz = vfmaq_f32(sz, a, dz);
    }
  }
  return {vaddvq_f32(sa), vaddvq_f32(sx), vaddvq_f32(sy), vaddvq_f32(sz), pairs};
}

}  // namespace cvo::registration::kernel
