#include <cmath>

#include "libcvo/registration/kernel.hpp"

namespace cvo::registration::kernel {

PointSums point_scalar(const FixedCloudView& fixed, const Range* ranges, int range_count, const float w[3],
                       const float feature[kFeatureDim], const Constants& k) {
  PointSums sums;
  for (int r = 0; r < range_count; ++r) {
    for (std::uint32_t i = ranges[r].begin; i < ranges[r].end; ++i) {
      const float dx = fixed.x[i] - w[0], dy = fixed.y[i] - w[1], dz = fixed.z[i] - w[2];
      float colour = 0;
      for (std::size_t c = 0; c < kFeatureDim; ++c) {
        const float d = fixed.f[c][i] - feature[c];
        colour += d * d;
      }
      add_pair(sums,
               k.log_amplitude - (dx * dx + dy * dy + dz * dz) * k.inv_two_ell_sq - colour * k.inv_two_ell_color_sq, dx,
               dy, dz, k);
    }
  }
  return sums;
}

PointSums candidates_scalar(const FixedCloudView& fixed, const std::uint32_t* index, const float* colour,
                            std::size_t count, const float w[3], const Constants& k) {
  PointSums sums;
  for (std::size_t c = 0; c < count; ++c) {
    const std::uint32_t i = index[c];
    const float dx = fixed.x[i] - w[0], dy = fixed.y[i] - w[1], dz = fixed.z[i] - w[2];
    add_pair(sums, k.log_amplitude - (dx * dx + dy * dy + dz * dz) * k.inv_two_ell_sq - colour[c], dx, dy, dz, k);
  }
  return sums;
}

std::size_t collect_scalar(const FixedCloudView& fixed, const Range* ranges, int range_count, const float w[3],
                           const float feature[kFeatureDim], const Constants& k, float reach_sq, std::uint32_t* index,
                           float* colour, std::size_t capacity) {
  const float max_colour = k.log_amplitude - k.log_threshold;
  std::size_t count = 0;
  for (int r = 0; r < range_count; ++r) {
    for (std::uint32_t i = ranges[r].begin; i < ranges[r].end; ++i) {
      const float dx = fixed.x[i] - w[0], dy = fixed.y[i] - w[1], dz = fixed.z[i] - w[2];
      if (dx * dx + dy * dy + dz * dz > reach_sq) continue;
      float c2 = 0;
      for (std::size_t c = 0; c < kFeatureDim; ++c) {
        const float d = fixed.f[c][i] - feature[c];
        c2 += d * d;
      }
      const float term = c2 * k.inv_two_ell_color_sq;
      if (term > max_colour) continue;
      if (count == capacity) return capacity + 1;
      index[count] = i;
      colour[count++] = term;
    }
  }
  return count;
}

}  // namespace cvo::registration::kernel
