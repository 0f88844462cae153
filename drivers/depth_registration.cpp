#include "drivers/depth_registration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "libcvo/core/pixel_rays.hpp"

namespace cvo::drivers {
namespace {

void check(const core::Intrinsics& k, const char* which) {
  if (const auto why = k.validate(); !why.empty())
    throw std::invalid_argument(std::string("depth registration: the ") + which + " camera: " + why);
}

}  // namespace

DepthRegistration::DepthRegistration(const core::DepthSensor& depth, const core::Intrinsics& colour)
    : depth_(depth), colour_(colour) {
  check(depth.intrinsics, "depth");
  check(colour, "colour");
  // Pixel (u, v) of a camera whose centre is half a pixel further on is corner (u - 1/2, v - 1/2).
  core::Intrinsics corners = depth.intrinsics;
  corners.cx += 0.5;
  corners.cy += 0.5;
  corners.width += 1;
  corners.height += 1;
  const std::vector<float> rays = core::undistorted_pixel_rays(corners);
  const Eigen::Matrix3f R = depth.T_colour_depth.rotation().toRotationMatrix().cast<float>();
  corners_.resize(rays.size() / 2 * 3);
  for (std::size_t i = 0; i < rays.size() / 2; ++i)  // turned into the colour camera's axes once
    Eigen::Map<Eigen::Vector3f>(corners_.data() + 3 * i) = R * Eigen::Vector3f(rays[2 * i], rays[2 * i + 1], 1.0f);
  t_ = depth.T_colour_depth.translation().cast<float>();
}

// Where the point at depth z on `ray` (R (x, y, 1)) lands in the colour image, in pixels, and its
// colour-camera z; nullopt behind the colour camera.
std::optional<Eigen::Vector3f> DepthRegistration::land(const float* ray, float z) const {
  const Eigen::Vector3f X = z * Eigen::Map<const Eigen::Vector3f>(ray) + t_;
  if (!(X.z() > 0)) return std::nullopt;
  float x = X.x() / X.z(), y = X.y() / X.z();
  if (colour_.has_distortion()) {
    const auto p = core::distort(colour_.distortion, x, y);
    x = p[0];
    y = p[1];
  }
  return Eigen::Vector3f(static_cast<float>(colour_.fx) * x + static_cast<float>(colour_.cx),
                         static_cast<float>(colour_.fy) * y + static_cast<float>(colour_.cy), X.z());
}

void DepthRegistration::apply(const cv::Mat& depth, cv::Mat& registered) const {
  const core::Intrinsics& d = depth_.intrinsics;
  if (depth.type() != CV_16UC1 || depth.cols != d.width || depth.rows != d.height)
    throw std::invalid_argument("depth registration: depth image is not " + std::to_string(d.width) + "x" +
                                std::to_string(d.height) + " 16-bit");
  registered.create(colour_.height, colour_.width, CV_16UC1);  // no allocation when already so
  for (int y = 0; y < registered.rows; ++y)                    // not setTo(0): that allocates
    std::fill_n(registered.ptr<std::uint16_t>(y), registered.cols, std::uint16_t{0});
  const auto to_metres = static_cast<float>(1.0 / d.depth_scale), to_raw = static_cast<float>(colour_.depth_scale);
  const auto corner = [&](int u, int v) {
    return corners_.data() + 3 * (static_cast<std::size_t>(v) * (d.width + 1) + u);
  };
  for (int v = 0; v < d.height; ++v) {
    const auto* row = depth.ptr<std::uint16_t>(v);
    for (int u = 0; u < d.width; ++u) {
      if (row[u] == 0) continue;
      const float z = static_cast<float>(row[u]) * to_metres;
      const auto a = land(corner(u, v), z), b = land(corner(u + 1, v + 1), z);
      if (!a || !b) continue;
      const float raw = std::round(0.5f * (a->z() + b->z()) * to_raw);  // the centre's z, to within the footprint
      if (raw < 1 || raw > std::numeric_limits<std::uint16_t>::max()) continue;
      // The colour pixels whose centres lie in [first corner, second corner): footprints that tile
      // the depth image tile the colour image, each centre covered once.
      const int x0 = std::max(0, static_cast<int>(std::ceil(std::min(a->x(), b->x())))),
                x1 = std::min(colour_.width, static_cast<int>(std::ceil(std::max(a->x(), b->x())))) - 1,
                y0 = std::max(0, static_cast<int>(std::ceil(std::min(a->y(), b->y())))),
                y1 = std::min(colour_.height, static_cast<int>(std::ceil(std::max(a->y(), b->y())))) - 1;
      for (int y = y0; y <= y1; ++y) {
        auto* out = registered.ptr<std::uint16_t>(y);
        for (int x = x0; x <= x1; ++x)
          if (out[x] == 0 || raw < out[x]) out[x] = static_cast<std::uint16_t>(raw);
      }
    }
  }
}

}  // namespace cvo::drivers
