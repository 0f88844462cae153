#include "libcvo/sim/render.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "libcvo/core/units.hpp"
#include "libcvo/sim/colour_noise.hpp"
#include "libcvo/sim/random.hpp"

namespace cvo::sim {
namespace {

constexpr std::uint64_t kDropoutTag = 1;
constexpr std::uint64_t kAxialTag = 2;
constexpr std::uint64_t kDisparityTag = 4;  // 3 is colour_noise.cpp's

// The ray against the unbounded plane of one surface (for sub-pixel rays whose neighbourhood is
// known to see only that surface).
std::optional<Hit> hit_plane(const Scene& scene, int surface, const Ray& ray) {
  const Quad& q = scene.surfaces[static_cast<std::size_t>(surface)].quad;
  const Eigen::Vector3d n = q.normal();
  const double denom = n.dot(ray.direction);
  if (std::abs(denom) < 1e-15) return std::nullopt;
  Hit hit;
  hit.t = n.dot(q.origin - ray.origin) / denom;
  if (!(hit.t > 0)) return std::nullopt;
  hit.point = ray.origin + hit.t * ray.direction;
  hit.normal = n;
  hit.surface = surface;
  const Eigen::Vector3d rel = hit.point - q.origin;
  hit.st = {rel.dot(q.axis_s), rel.dot(q.axis_t)};
  return hit;
}

// Drops depth next to discontinuities; reads the clean map, writes a mask.
std::vector<bool> edge_mask(const std::vector<DepthSample>& clean, int width, int height, const NoiseOptions& noise) {
  std::vector<bool> edge(clean.size(), false);
  const int r = noise.edge_band_px;
  if (r <= 0) return edge;
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const double z = clean[static_cast<std::size_t>(v * width + u)].z;
      if (z <= 0) continue;
      bool found = false;
      for (int dv = -r; dv <= r && !found; ++dv)
        for (int du = -r; du <= r && !found; ++du) {
          const int uu = u + du, vv = v + dv;
          if (uu < 0 || vv < 0 || uu >= width || vv >= height) continue;
          const double zn = clean[static_cast<std::size_t>(vv * width + uu)].z;
          found = zn <= 0 || std::abs(zn - z) > noise.edge_jump_fraction * z;
        }
      edge[static_cast<std::size_t>(v * width + u)] = found;
    }
  return edge;
}

}  // namespace

double axial_noise_sigma(double z) { return 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4); }

core::RgbdFrame render(const Scene& scene, const core::Intrinsics& k, const core::SE3& T_world_camera,
                       const NoiseOptions& noise, std::uint64_t seed, const RenderOptions& options) {
  return render(
      scene, k, [&](int) { return T_world_camera; }, noise, seed, options);
}

core::RgbdFrame render(const Scene& scene, const core::Intrinsics& k, const PoseAtRow& T_world_camera_at_row,
                       const NoiseOptions& noise, std::uint64_t seed, const RenderOptions& options) {
  const Radiance radiance = render_radiance(scene, k, T_world_camera_at_row, options);
  core::RgbdFrame frame;
  frame.intrinsics = k;
  frame.bgr = develop_colour(radiance.bgr, 1.0, {}, 0);
  frame.depth = depth_image(radiance.depth, k, noise, seed);
  return frame;
}

Radiance render_radiance(const Scene& scene, const core::Intrinsics& k, const PoseAtRow& T_world_camera_at_row,
                         const RenderOptions& options) {
  if (const std::string problem = k.validate(); !problem.empty()) throw std::invalid_argument("render: " + problem);
  const int w = k.width, h = k.height;
  std::vector<Eigen::Matrix3d> row_rotation(static_cast<std::size_t>(h));
  std::vector<Eigen::Vector3d> row_origin(static_cast<std::size_t>(h));
  for (int v = 0; v < h; ++v) {
    const core::SE3 pose = T_world_camera_at_row(v);
    row_rotation[static_cast<std::size_t>(v)] = pose.rotation_matrix();
    row_origin[static_cast<std::size_t>(v)] = pose.translation();
  }
  // A sub-pixel ray belongs to its pixel's row (one row, one exposure time).
  auto ray_through = [&](double u, double v) {
    const auto row = static_cast<std::size_t>(std::clamp(static_cast<int>(std::lround(v)), 0, h - 1));
    return Ray{row_origin[row], row_rotation[row] * Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0)};
  };
  auto colour_of = [&](const std::optional<Hit>& hit) {
    return hit ? surface_colour(scene, *hit) : Eigen::Vector3d::Zero().eval();
  };
  auto to_bgr = [](const Eigen::Vector3d& rgb) { return cv::Vec3d(rgb.z(), rgb.y(), rgb.x()); };

  Radiance radiance;
  radiance.bgr.create(h, w, CV_64FC3);
  radiance.depth.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  std::vector<DepthSample>& clean = radiance.depth;

  for (int v = 0; v < h; ++v) {
    auto* bgr = radiance.bgr.ptr<cv::Vec3d>(v);
    for (int u = 0; u < w; ++u) {
      const Ray ray = ray_through(u, v);
      const auto hit = intersect(scene, ray);
      DepthSample& sample = clean[static_cast<std::size_t>(v * w + u)];
      if (hit) {
        sample.surface = hit->surface;
        if (hit->t <= options.max_depth) {
          sample.z = hit->t;  // d_z = 1, so t is the camera-frame z
          sample.cos_incidence = std::abs(hit->normal.dot(ray.direction)) / ray.direction.norm();
        }
      }
      if (!options.supersample) bgr[u] = to_bgr(colour_of(hit));
    }
  }

  // Sub-pixel rays: when the centre rays of the pixel and its 4-neighbours all meet one surface,
  // the sub-rays (a quarter pixel off centre) are taken to meet it too and skip the full search.
  // This can only miss a feature that fits between pixel centres, and affects colour only.
  if (options.supersample) {
    constexpr std::array<std::array<double, 2>, 4> kSub{{{-0.25, -0.25}, {0.25, -0.25}, {-0.25, 0.25}, {0.25, 0.25}}};
    auto surface_at = [&](int u, int v, int fallback) {
      return u < 0 || v < 0 || u >= w || v >= h ? fallback : clean[static_cast<std::size_t>(v * w + u)].surface;
    };
    for (int v = 0; v < h; ++v) {
      auto* bgr = radiance.bgr.ptr<cv::Vec3d>(v);
      for (int u = 0; u < w; ++u) {
        const int surface = surface_at(u, v, -1);
        const bool uniform = surface >= 0 && surface_at(u - 1, v, surface) == surface &&
                             surface_at(u + 1, v, surface) == surface && surface_at(u, v - 1, surface) == surface &&
                             surface_at(u, v + 1, surface) == surface;
        Eigen::Vector3d rgb = Eigen::Vector3d::Zero();
        for (const auto& [du, dv] : kSub) {
          const Ray sub = ray_through(u + du, v + dv);
          rgb += colour_of(uniform ? hit_plane(scene, surface, sub) : intersect(scene, sub));
        }
        bgr[u] = to_bgr(rgb / 4.0);
      }
    }
  }
  return radiance;
}

cv::Mat depth_image(const std::vector<DepthSample>& clean, const core::Intrinsics& k, const NoiseOptions& noise,
                    std::uint64_t seed, const KinectDepthOptions& kinect) {
  const int w = k.width, h = k.height;
  cv::Mat image(h, w, CV_16UC1);
  const bool holes = noise.enabled || kinect.enabled;
  std::vector<bool> edge;
  if (holes) edge = edge_mask(clean, w, h, noise);
  const double cos_grazing = std::cos(core::radians(noise.grazing_angle_deg));
  for (int v = 0; v < h; ++v) {
    auto* depth = image.ptr<std::uint16_t>(v);
    for (int u = 0; u < w; ++u) {
      const auto index = static_cast<std::size_t>(v * w + u);
      double z = clean[index].z;
      if (holes && z > 0) {
        const std::uint64_t key = hash(seed, index);
        if (clean[index].cos_incidence < cos_grazing || edge[index] ||
            to_unit(hash(key, kDropoutTag)) < noise.dropout_probability)
          z = 0;
        else if (kinect.enabled)
          z = kinect_depth(kinect, z, hash(key, kDisparityTag));
        else if (noise.axial)
          z += axial_noise_sigma(z) * gaussian(hash(key, kAxialTag));
      }
      const double raw = std::round(z * k.depth_scale);
      depth[u] = raw > 0 && raw <= std::numeric_limits<std::uint16_t>::max() ? static_cast<std::uint16_t>(raw) : 0;
    }
  }
  return image;
}

core::RgbdFrame render_separate_depth(const Scene& scene, const core::Intrinsics& colour,
                                      const core::DepthSensor& depth, const core::SE3& T_world_colour,
                                      const NoiseOptions& noise, std::uint64_t seed, const RenderOptions& options) {
  core::RgbdFrame frame = render(scene, colour, T_world_colour, {}, seed, options);
  RenderOptions depth_only = options;
  depth_only.supersample = false;  // its colour is thrown away
  frame.depth = render(scene, depth.intrinsics, T_world_colour * depth.T_colour_depth, noise, seed, depth_only).depth;
  return frame;
}

}  // namespace cvo::sim
