#pragma once
// The map as a 3-D occupancy octree through OctoMap (its own ray casting and log-odds update,
// with the grid's probabilities and cell size): every placed keyframe's local cloud inserted from
// its camera centre, in the grid frame (z up, z = 0 on the floor), where OctoMap's tools and
// octovis expect z to be up.
#include <memory>
#include <vector>

#include <octomap/OcTree.h>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/mapping/local_map.hpp"

namespace cvo::mapping {

struct GridPlacedCloud {
  const std::vector<CloudPoint>* cloud = nullptr;
  core::SE3 grid_T_camera;
};

std::unique_ptr<octomap::OcTree> make_octree(const std::vector<GridPlacedCloud>& clouds,
                                             const core::MappingParameters& parameters);

}  // namespace cvo::mapping
