#pragma once
// A route for bench/map_scale: one sequence tracked once by KF-CVO (as cvo-trackerd tracks it),
// kept as what a tracker sends the back end, in its order: each closed local graph and each new
// keyframe (its frame, its odometry pose). A session driven along a route sends these again with its
// own perturbation of every keyframe image (perturbed()), and each keyframe's cloud selected afresh
// from its perturbed images (the tracker's point selection, without its motion compensation): so
// no two keyframes the back end sees are the same, yet each session is a real revisit of the route.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "libcvo/config/config.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/odometry/local_graph.hpp"

namespace cvo::bench {

struct RouteKeyframe {
  std::int64_t id = 0;
  core::RgbdFrame frame;  // owns its images
  core::SE3 pose;         // T_odom_keyframe
};

struct RouteGraph {
  std::int64_t keyframe_id = 0;
  odometry::LocalGraph graph;
};

/// One message of the route: a local graph or a keyframe.
struct RouteStep {
  std::optional<RouteGraph> graph;
  std::optional<RouteKeyframe> keyframe;
};

struct Route {
  std::string name;
  std::vector<RouteStep> steps;
  std::size_t keyframes = 0;
};

/// Tracks the TUM folder with the configuration's KF-CVO. Throws io::InputError on a bad folder.
Route track_route(const std::string& name, const std::filesystem::path& tum_folder, const config::Config& config);

/// The frame with seeded noise: colour N(0, 2²) levels per channel, valid depth ±1 raw unit
/// (0.2 mm at 5000 units a metre), both far below a Kinect's own; the same seed, the same images.
core::RgbdFrame perturbed(const core::RgbdFrame& frame, std::uint64_t seed);

}  // namespace cvo::bench
