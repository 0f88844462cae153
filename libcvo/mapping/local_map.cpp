#include "libcvo/mapping/local_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cvo::mapping {
namespace {

// Voxel indices packed into one key that sorts by i, then j, then k (21 bits each: ±1 M voxels,
// far beyond max_range).
constexpr std::int64_t kOffset = 1 << 20, kMask = (1 << 21) - 1;
std::uint64_t pack(std::int64_t i, std::int64_t j, std::int64_t k) {
  return (static_cast<std::uint64_t>(i + kOffset) << 42) | (static_cast<std::uint64_t>(j + kOffset) << 21) |
         static_cast<std::uint64_t>(k + kOffset);
}

struct Sample {
  std::uint64_t key;
  float x, y, z;
  std::uint8_t b, g, r;
};

std::int64_t unpack_i(std::uint64_t key) { return static_cast<std::int64_t>(key >> 42) - kOffset; }
std::int64_t unpack_j(std::uint64_t key) { return static_cast<std::int64_t>((key >> 21) & kMask) - kOffset; }
std::int64_t unpack_k(std::uint64_t key) { return static_cast<std::int64_t>(key & kMask) - kOffset; }

bool fits_int16_mm(float v) { return std::abs(v) < 32.0f; }

void check_frame(const core::RgbdFrame& frame, const std::vector<float>& pixel_rays) {
  const auto& in = frame.intrinsics;
  if (frame.depth.type() != CV_16UC1 || frame.depth.cols != in.width || frame.depth.rows != in.height)
    throw std::invalid_argument("local map: depth must be CV_16UC1 of the intrinsics' size");
  if (frame.bgr.type() != CV_8UC3 || frame.bgr.size() != frame.depth.size())
    throw std::invalid_argument("local map: colour must be CV_8UC3 of the depth's size");
  if (pixel_rays.size() != 2 * static_cast<std::size_t>(in.width) * static_cast<std::size_t>(in.height))
    throw std::invalid_argument("local map: pixel rays are not the intrinsics'");
  if (!(in.depth_scale > 0)) throw std::invalid_argument("local map: depth scale must be positive");
}

}  // namespace

std::vector<CloudPoint> make_local_cloud(const core::RgbdFrame& frame, const std::vector<float>& pixel_rays,
                                         const core::MappingParameters& parameters) {
  check_frame(frame, pixel_rays);
  const int stride = std::max(1, parameters.pixel_stride);
  const auto scale = static_cast<float>(1.0 / frame.intrinsics.depth_scale);
  const auto max_range = static_cast<float>(parameters.max_range);
  const auto inverse_voxel = static_cast<float>(1.0 / parameters.voxel_size);
  std::vector<Sample> samples;
  samples.reserve(static_cast<std::size_t>(frame.depth.total()) / static_cast<std::size_t>(stride * stride));
  for (int v = 0; v < frame.depth.rows; v += stride) {
    const auto* depth = frame.depth.ptr<std::uint16_t>(v);
    const auto* bgr = frame.bgr.ptr<cv::Vec3b>(v);
    const float* ray = pixel_rays.data() + 2 * static_cast<std::size_t>(v) * static_cast<std::size_t>(frame.depth.cols);
    for (int u = 0; u < frame.depth.cols; u += stride) {
      const float z = static_cast<float>(depth[u]) * scale;
      if (depth[u] == 0 || z > max_range) continue;
      const float x = ray[2 * u] * z, y = ray[2 * u + 1] * z;
      if (!fits_int16_mm(x) || !fits_int16_mm(y) || !fits_int16_mm(z)) continue;
      const auto key = pack(static_cast<std::int64_t>(std::floor(x * inverse_voxel)),
                            static_cast<std::int64_t>(std::floor(y * inverse_voxel)),
                            static_cast<std::int64_t>(std::floor(z * inverse_voxel)));
      samples.push_back({key, x, y, z, bgr[u][0], bgr[u][1], bgr[u][2]});
    }
  }
  std::sort(samples.begin(), samples.end(), [](const Sample& a, const Sample& b) { return a.key < b.key; });

  std::vector<CloudPoint> cloud;
  for (std::size_t first = 0; first < samples.size();) {
    std::size_t last = first;
    double x = 0, y = 0, z = 0, r = 0, g = 0, b = 0;
    for (; last < samples.size() && samples[last].key == samples[first].key; ++last)
      x += samples[last].x, y += samples[last].y, z += samples[last].z, r += samples[last].r, g += samples[last].g,
          b += samples[last].b;
    const double n = static_cast<double>(last - first);
    const auto mm = [n](double sum) { return static_cast<std::int16_t>(std::lround(sum / n * 1000.0)); };
    const auto byte = [n](double sum) { return static_cast<std::uint8_t>(std::lround(sum / n)); };
    cloud.push_back({mm(x), mm(y), mm(z), byte(r), byte(g), byte(b)});
    first = last;
  }
  cloud.shrink_to_fit();  // kept for the map's life
  return cloud;
}

namespace {

// The lowest crossing, by a ray from the camera, of every half-cell column within `reach` (a
// side x side lattice centred on the camera): rays go to the lowest surface voxel of every column,
// sampled every half-cell and stopping one cell short of it. A ray to a higher voxel of the same
// column runs above that one all the way (both start at the camera), so it would lower no crossing.
std::vector<std::int16_t> lowest_crossings(const std::vector<std::uint64_t>& keys, double h, std::int64_t reach) {
  const std::int64_t side = 2 * reach + 1;
  std::vector<std::int16_t> lowest(static_cast<std::size_t>(side * side), FootprintColumn::kNoRay);
  const auto index = [h](double v) { return static_cast<std::int64_t>(std::floor(v / h)); };
  for (std::size_t n = 0; n < keys.size(); ++n) {
    if (n > 0 && (keys[n - 1] >> 21) == (keys[n] >> 21)) continue;  // not the column's lowest
    const Eigen::Vector3d end((unpack_i(keys[n]) + 0.5) * h, (unpack_j(keys[n]) + 0.5) * h,
                              (unpack_k(keys[n]) + 0.5) * h);
    const double length = end.norm();
    const auto steps = static_cast<int>(std::floor((length - 2 * h) / h));
    for (int step = 0; step <= steps; ++step) {
      const Eigen::Vector3d q = end * (step * h / length);
      const std::int64_t i = index(q.x()) + reach, j = index(q.y()) + reach;
      if (i < 0 || j < 0 || i >= side || j >= side) continue;
      auto& k = lowest[static_cast<std::size_t>(i * side + j)];  // by i, then j, as the columns
      k = std::min<std::int16_t>(k, static_cast<std::int16_t>(index(q.z())));
    }
  }
  return lowest;
}

}  // namespace

Footprint make_footprint(const std::vector<CloudPoint>& cloud, const Eigen::Matrix3d& level_R_camera,
                         const core::MappingParameters& parameters) {
  Footprint footprint;
  footprint.half_cell = parameters.cell_size / 2;
  footprint.level_R_camera = level_R_camera;
  const double h = footprint.half_cell;
  const auto index = [h](double v) { return static_cast<std::int64_t>(std::floor(v / h)); };
  // Half-cells within max_range (plus a margin for the cloud's rounding) in each direction.
  const std::int64_t reach = static_cast<std::int64_t>(std::ceil(parameters.max_range * 1.01 / h)) + 1;
  if (reach >= std::numeric_limits<std::int16_t>::max() / 2)
    throw std::invalid_argument("footprint: max_range / cell_size too large");

  std::vector<std::uint64_t> keys;  // surface voxels, sorted by i, j, k
  keys.reserve(cloud.size());
  const Eigen::Matrix3f rotation = level_R_camera.cast<float>();
  for (const auto& p : cloud) {
    const Eigen::Vector3d q = (rotation * p.position()).cast<double>();
    keys.push_back(pack(index(q.x()), index(q.y()), index(q.z())));
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  const auto lowest = lowest_crossings(keys, h, reach);

  // Columns in (i, j) order: the lattice's, merged with the surfaces' (already in that order).
  const std::int64_t side = 2 * reach + 1;
  std::size_t next = 0;
  for (std::int64_t i = 0; i < side; ++i)
    for (std::int64_t j = 0; j < side; ++j) {
      FootprintColumn column{static_cast<std::int16_t>(i - reach), static_cast<std::int16_t>(j - reach),
                             lowest[static_cast<std::size_t>(i * side + j)], 0};
      for (; next < keys.size() && unpack_i(keys[next]) == column.i && unpack_j(keys[next]) == column.j; ++next) {
        footprint.surface_k.push_back(static_cast<std::int16_t>(unpack_k(keys[next])));
        ++column.surfaces;
      }
      if (column.surfaces == 0 && column.ray_k_min == FootprintColumn::kNoRay) continue;
      footprint.columns.push_back(column);
      if (footprint.i_max < footprint.i_min)
        footprint.i_min = footprint.i_max = column.i, footprint.j_min = footprint.j_max = column.j;
      footprint.i_min = std::min(footprint.i_min, column.i), footprint.i_max = std::max(footprint.i_max, column.i);
      footprint.j_min = std::min(footprint.j_min, column.j), footprint.j_max = std::max(footprint.j_max, column.j);
    }
  footprint.columns.shrink_to_fit();
  footprint.surface_k.shrink_to_fit();
  return footprint;
}

}  // namespace cvo::mapping
