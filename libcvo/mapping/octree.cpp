#include "libcvo/mapping/octree.hpp"

namespace cvo::mapping {

std::unique_ptr<octomap::OcTree> make_octree(const std::vector<GridPlacedCloud>& clouds,
                                             const core::MappingParameters& parameters) {
  auto tree = std::make_unique<octomap::OcTree>(parameters.cell_size);
  tree->setProbHit(parameters.hit_probability);
  tree->setProbMiss(parameters.miss_probability);
  for (const auto& placed : clouds) {
    octomap::Pointcloud points;
    points.reserve(placed.cloud->size());
    for (const auto& point : *placed.cloud) {
      const Eigen::Vector3d p = placed.grid_T_camera * point.position().cast<double>();
      points.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    }
    const Eigen::Vector3d& origin = placed.grid_T_camera.translation();
    // Discretised: one ray per endpoint voxel, as many rays as the octree can tell apart.
    tree->insertPointCloud(points,
                           octomap::point3d(static_cast<float>(origin.x()), static_cast<float>(origin.y()),
                                            static_cast<float>(origin.z())),
                           parameters.max_range * 1.01, /*lazy_eval=*/true, /*discretize=*/true);
  }
  tree->updateInnerOccupancy();
  tree->prune();
  return tree;
}

}  // namespace cvo::mapping
