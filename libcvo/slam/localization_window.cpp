#include "libcvo/slam/localization_window.hpp"

#include <stdexcept>

#include "libcvo/posegraph/cost.hpp"
#include "libcvo/posegraph/marginals.hpp"
#include "libcvo/posegraph/optimizer.hpp"

namespace cvo::slam {
namespace {

// The window's poses before the solve: the current correction, else the first match's.
core::SE3 initial_correction(const std::deque<WindowKeyframe>& window, const std::vector<WindowMatch>& matches,
                             const std::optional<core::SE3>& correction) {
  if (correction) return *correction;
  const WindowMatch& first = matches.front();
  for (const auto& k : window)
    if (k.node == first.loop.to) return first.map_pose * first.loop.measurement * k.odometry.inverse();
  return core::SE3();
}

posegraph::Edge odometry_edge(const WindowKeyframe& a, const WindowKeyframe& b,
                              const core::PoseGraphParameters& parameters) {
  if (a.next && a.next->to == b.node && a.next->from == a.node) return *a.next;
  return {a.node, b.node, a.odometry.inverse() * b.odometry, parameters.bridge_information * core::Matrix6d::Identity(),
          false};
}

posegraph::PoseGraph window_graph(const std::deque<WindowKeyframe>& window, const std::vector<WindowMatch>& matches,
                                  const core::SE3& correction, const core::PoseGraphParameters& parameters) {
  posegraph::PoseGraph graph;
  for (const auto& k : window) graph.add_node(k.node, correction * k.odometry);
  for (std::size_t i = 1; i < window.size(); ++i) graph.add_edge(odometry_edge(window[i - 1], window[i], parameters));
  for (const auto& m : matches) {
    if (!graph.contains(m.loop.from)) graph.add_node(m.loop.from, m.map_pose, /*fixed=*/true);
    graph.add_edge({m.loop.from, m.loop.to, m.loop.measurement,
                    0.5 * (m.loop.information + m.loop.information.transpose()), /*robust=*/true});
  }
  return graph;
}

}  // namespace

std::optional<WindowSolution> solve_window(const std::deque<WindowKeyframe>& window,
                                           const std::vector<WindowMatch>& matches,
                                           const std::optional<core::SE3>& correction,
                                           const core::PoseGraphParameters& parameters) {
  if (window.empty() || matches.empty()) return std::nullopt;
  posegraph::PoseGraph graph =
      window_graph(window, matches, initial_correction(window, matches, correction), parameters);
  posegraph::OptimizerOptions options;
  options.pose_graph = parameters;
  posegraph::optimize(graph, options);

  const WindowKeyframe& newest = window.back();
  WindowSolution solution;
  solution.correction = graph.node(newest.node).pose * newest.odometry.inverse();
  try {
    solution.covariance = posegraph::marginal_covariances(graph, {newest.node}, options).at(newest.node);
  } catch (const std::runtime_error&) {  // a window node no edge constrains: no covariance to give
  }
  const posegraph::RobustKernel kernel{parameters.cauchy_delta};
  const auto& edges = graph.edges();
  for (std::size_t e = edges.size() - matches.size(); e < edges.size(); ++e)
    solution.loop_weights.push_back(kernel.weight(posegraph::edge_chi2(graph, edges[e]), true));
  return solution;
}

}  // namespace cvo::slam
