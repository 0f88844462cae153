#pragma once
// Synthetic tracker output with known truth for the back-end tests: the local graphs a KF-CVO
// tracker would close along a true trajectory, with a constant per-frame bias in every
// measurement (odometry drift), and loop closures between keyframes.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include "libcvo/core/se3.hpp"
#include "libcvo/loop_closure/loop_detector.hpp"
#include "libcvo/odometry/local_graph.hpp"

namespace cvo::slam::testing {

inline core::SE3 pose_xy_yaw(double x, double y, double yaw) {
  return {Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())), Eigen::Vector3d(x, y, 0)};
}

/// A camera driven round a side x side square, `per_side` frames a side, turning smoothly by 90°
/// a side; frame 4 per_side is back at frame 0's pose (a loop).
inline std::vector<core::SE3> square(std::size_t per_side = 10, double side = 2.0) {
  const double corners[5][2] = {{0, 0}, {side, 0}, {side, side}, {0, side}, {0, 0}};
  std::vector<core::SE3> truth;
  for (std::size_t i = 0; i <= 4 * per_side; ++i) {
    const std::size_t s = std::min<std::size_t>(i / per_side, 3);
    const double t = static_cast<double>(i - s * per_side) / static_cast<double>(per_side);
    const double x = corners[s][0] + t * (corners[s + 1][0] - corners[s][0]);
    const double y = corners[s][1] + t * (corners[s + 1][1] - corners[s][1]);
    truth.push_back(pose_xy_yaw(x, y, std::numbers::pi / 2 * static_cast<double>(i) / static_cast<double>(per_side)));
  }
  return truth;
}

struct SyntheticRun {
  std::vector<core::SE3> truth;              // T_world_camera per frame
  std::vector<core::SE3> odometry;           // the tracker's poses
  std::vector<odometry::LocalGraph> graphs;  // in closing order; the last one is the open graph
};

/// Keyframes every `stride` frames (0, stride, ...). A measurement over k frames is the true
/// relative pose times exp(k bias); every edge has information `information` I (CVO-Hessian form).
inline SyntheticRun make_run(const std::vector<core::SE3>& truth, std::size_t stride, const core::Vector6d& bias,
                             double information) {
  SyntheticRun run;
  run.truth = truth;
  const auto measured = [&](std::size_t from, std::size_t to) {
    return truth[from].inverse() * truth[to] * core::SE3::exp(static_cast<double>(to - from) * bias);
  };
  run.odometry.resize(truth.size());
  run.odometry[0] = truth[0];
  for (std::size_t keyframe = 0; keyframe < truth.size(); keyframe += stride) {
    odometry::LocalGraph graph(stride + 1);
    graph.add_node({keyframe, static_cast<double>(keyframe), run.odometry[keyframe]});
    for (std::size_t n = keyframe + 1; n <= keyframe + stride && n < truth.size(); ++n) {
      run.odometry[n] = run.odometry[keyframe] * measured(keyframe, n);
      graph.add_node({n, static_cast<double>(n), run.odometry[n]});
      graph.add_edge({keyframe, n, measured(keyframe, n), information * core::Matrix6d::Identity()});
      if (n > keyframe + 1) graph.add_edge({n - 1, n, measured(n - 1, n), information * core::Matrix6d::Identity()});
    }
    if (graph.nodes().size() > 1 || run.graphs.empty()) run.graphs.push_back(graph);
  }
  return run;
}

/// A loop between frames `from` and `to` measuring `measurement` (the truth when not given).
inline loop_closure::LoopClosure loop(const SyntheticRun& run, std::size_t from, std::size_t to, double information) {
  loop_closure::LoopClosure l;
  l.from = static_cast<std::int64_t>(from);
  l.to = static_cast<std::int64_t>(to);
  l.measurement = run.truth[from].inverse() * run.truth[to];
  l.information = information * core::Matrix6d::Identity();
  return l;
}

/// Translation error of a pose, m.
inline double position_error(const core::SE3& truth, const core::SE3& estimate) {
  return (truth.translation() - estimate.translation()).norm();
}

}  // namespace cvo::slam::testing
