#pragma once
// What the mapper tests feed slam::Mapper without a tracker: keyframes of a TUM folder at their
// ground-truth poses (every third frame, CVO points selected as the tracker selects them), and the
// exact keyframe→next-keyframe local graph a tracker would close between two of them.
#include <cstddef>
#include <filesystem>
#include <vector>

#include "libcvo/core/trajectory.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/odometry/local_graph.hpp"
#include "libcvo/registration/point_selection.hpp"

namespace cvo::testing {

struct TruthKeyframe {
  core::RgbdFrame frame;
  registration::PointCloud cloud{4096};
  core::SE3 truth;  // T_world_camera
};

inline core::SE3 ground_truth_at(const core::Trajectory& gt, double t) {
  return gt[core::find_closest_index(core::timestamps(gt), t)].pose;
}

/// Every third frame of a TUM folder from `first` to `last`, with its ground-truth pose.
inline std::vector<TruthKeyframe> keyframes_of(const std::filesystem::path& folder, std::size_t first,
                                               std::size_t last) {
  const auto sequence = io::TumSequence::open(folder);
  const auto gt = io::read_tum_trajectory(folder / "groundtruth.txt");
  std::vector<TruthKeyframe> out;
  for (std::size_t i = first; i <= last; i += 3) {
    TruthKeyframe& k = out.emplace_back();
    k.frame = sequence.read(i);
    registration::PointSelector selector(k.frame.bgr.cols, k.frame.bgr.rows, core::SelectionParameters{});
    selector.select(k.frame, k.cloud);
    k.truth = ground_truth_at(gt, k.frame.timestamp);
  }
  return out;
}

/// The local graph from a to b in an odometry frame odom_T_world, exact, with `information` times
/// the identity on its one edge.
inline odometry::LocalGraph graph_between(const TruthKeyframe& a, const TruthKeyframe& b, const core::SE3& odom_T_world,
                                          double information) {
  odometry::LocalGraph graph(2);
  graph.add_node({a.frame.index, a.frame.timestamp, odom_T_world * a.truth});
  graph.add_node({b.frame.index, b.frame.timestamp, odom_T_world * b.truth});
  graph.add_edge({a.frame.index, b.frame.index, a.truth.inverse() * b.truth, information * core::Matrix6d::Identity()});
  return graph;
}

}  // namespace cvo::testing
