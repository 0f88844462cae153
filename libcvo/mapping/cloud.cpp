#include "libcvo/mapping/cloud.hpp"

#include <algorithm>
#include <cmath>

namespace cvo::mapping {

std::vector<ColouredPoint> assemble_cloud(const std::vector<PlacedCloud>& clouds, double voxel_size) {
  struct Sample {
    std::int64_t i, j, k;
    Eigen::Vector3f p;
    std::uint8_t r, g, b;
  };
  std::vector<Sample> samples;
  std::size_t total = 0;
  for (const auto& placed : clouds) total += placed.cloud->size();
  samples.reserve(total);
  const double inverse = 1.0 / voxel_size;
  for (const auto& placed : clouds) {
    const Eigen::Matrix3f rotation = placed.map_T_camera.rotation_matrix().cast<float>();
    const Eigen::Vector3f translation = placed.map_T_camera.translation().cast<float>();
    for (const auto& point : *placed.cloud) {
      const Eigen::Vector3f p = rotation * point.position() + translation;
      samples.push_back({static_cast<std::int64_t>(std::floor(p.x() * inverse)),
                         static_cast<std::int64_t>(std::floor(p.y() * inverse)),
                         static_cast<std::int64_t>(std::floor(p.z() * inverse)), p, point.r, point.g, point.b});
    }
  }
  const auto voxel_less = [](const Sample& a, const Sample& b) {
    return std::tie(a.i, a.j, a.k) < std::tie(b.i, b.j, b.k);
  };
  std::stable_sort(samples.begin(), samples.end(), voxel_less);
  std::vector<ColouredPoint> points;
  for (std::size_t first = 0; first < samples.size();) {
    std::size_t last = first;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double r = 0, g = 0, b = 0;
    for (; last < samples.size() && !voxel_less(samples[first], samples[last]); ++last)
      sum += samples[last].p.cast<double>(), r += samples[last].r, g += samples[last].g, b += samples[last].b;
    const double n = static_cast<double>(last - first);
    points.push_back({(sum / n).cast<float>(), static_cast<std::uint8_t>(std::lround(r / n)),
                      static_cast<std::uint8_t>(std::lround(g / n)), static_cast<std::uint8_t>(std::lround(b / n))});
    first = last;
  }
  return points;
}

}  // namespace cvo::mapping
