#include "libcvo/mapping/up.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>

namespace cvo::mapping {

std::string_view up_source_name(UpSource source) {
  switch (source) {
    case UpSource::mount: return "mount";
    case UpSource::accelerometer: return "accelerometer";
    case UpSource::floor_plane: return "floor plane";
  }
  return "?";
}

namespace {

// A unit vector orthogonal to `z`, along `preferred` made orthogonal (`fallback` when `preferred`
// is nearly parallel to z).
Eigen::Vector3d horizontal(const Eigen::Vector3d& z, const Eigen::Vector3d& preferred,
                           const Eigen::Vector3d& fallback) {
  Eigen::Vector3d x = preferred - preferred.dot(z) * z;
  if (x.norm() < 1e-3) x = fallback - fallback.dot(z) * z;
  return x.normalized();
}

Eigen::Matrix3d rows(const Eigen::Vector3d& x, const Eigen::Vector3d& z) {
  Eigen::Matrix3d r;
  r.row(0) = x.transpose();
  r.row(1) = z.cross(x).transpose();
  r.row(2) = z.transpose();
  return r;
}

}  // namespace

Eigen::Matrix3d level_rotation(const Eigen::Vector3d& up_camera) {
  const Eigen::Vector3d z = up_camera.normalized();
  return rows(horizontal(z, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX()), z);
}

Eigen::Matrix3d grid_rotation(const Eigen::Vector3d& up_map, const Eigen::Matrix3d& map_R_camera) {
  const Eigen::Vector3d z = up_map.normalized();
  // Columns are the grid axes in the map frame.
  return rows(horizontal(z, map_R_camera.col(2), map_R_camera.col(0)), z).transpose();
}

std::optional<Eigen::Vector3d> horizontal_plane_up(const std::vector<CloudPoint>& cloud, double inlier_distance) {
  if (cloud.size() < 30) return std::nullopt;
  // At most ~2000 points: a plane's support is a share, which a sample measures well enough.
  const std::size_t step = std::max<std::size_t>(1, cloud.size() / 2000);
  std::vector<Eigen::Vector3d> points;
  for (std::size_t i = 0; i < cloud.size(); i += step) points.push_back(cloud[i].position().cast<double>());
  const Eigen::Vector3d image_up(0, -1, 0);
  const double cos_cone = std::cos(60.0 * M_PI / 180.0);
  std::mt19937 random(7);
  std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
  std::size_t best_support = 0;
  Eigen::Vector3d best_normal = Eigen::Vector3d::Zero(), best_point = Eigen::Vector3d::Zero();
  for (int trial = 0; trial < 300; ++trial) {
    const auto& a = points[pick(random)];
    const auto& b = points[pick(random)];
    const auto& c = points[pick(random)];
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-9) continue;
    n.normalize();
    if (n.dot(image_up) < 0) n = -n;
    if (n.dot(image_up) < cos_cone || n.dot(a) >= 0) continue;  // not horizontal enough, or above the camera
    std::size_t support = 0;
    for (const auto& p : points) support += std::abs(n.dot(p - a)) <= inlier_distance;
    if (support > best_support) best_support = support, best_normal = n, best_point = a;
  }
  if (best_support * 5 < points.size()) return std::nullopt;
  // Refit to the inliers: the normal is the least eigenvector of their scatter.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::vector<const Eigen::Vector3d*> inliers;
  for (const auto& p : points)
    if (std::abs(best_normal.dot(p - best_point)) <= inlier_distance) inliers.push_back(&p), mean += p;
  mean /= static_cast<double>(inliers.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto* p : inliers) scatter += (*p - mean) * (*p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(scatter);
  Eigen::Vector3d normal = solver.eigenvectors().col(0).normalized();
  return normal.dot(best_normal) < 0 ? Eigen::Vector3d(-normal) : normal;
}

std::optional<long> HeightHistogram::floor_bin() const {
  if (total_ <= 0) return std::nullopt;
  long below = 0;
  for (const auto& [bin, count] : counts_) {
    below += count;
    if (below * 100 >= total_) return bin;
  }
  return counts_.rbegin()->first;
}

}  // namespace cvo::mapping
