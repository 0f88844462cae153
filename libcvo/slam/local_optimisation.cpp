#include "libcvo/slam/local_optimisation.hpp"

#include <stdexcept>

#include "libcvo/slam/edge_information.hpp"

namespace cvo::slam {

LocalSolution optimise_local_graph(const odometry::LocalGraph& graph, const posegraph::OptimizerOptions& options) {
  if (graph.empty()) throw std::invalid_argument("local graph: no nodes");
  const core::SE3 world_keyframe_inverse = graph.keyframe().pose.inverse();

  posegraph::PoseGraph local;
  LocalSolution solution;
  solution.frames.reserve(graph.nodes().size());
  for (const auto& node : graph.nodes()) {
    const auto id = static_cast<posegraph::NodeId>(node.frame_index);
    const bool keyframe = solution.frames.empty();
    const core::SE3 relative = keyframe ? core::SE3() : world_keyframe_inverse * node.pose;
    local.add_node(id, relative, /*fixed=*/keyframe);
    solution.frames.push_back({id, node.timestamp, relative, node.pose});
  }
  solution.edges.reserve(graph.edges().size());
  for (const auto& e : graph.edges()) {
    const posegraph::Edge edge{static_cast<posegraph::NodeId>(e.from), static_cast<posegraph::NodeId>(e.to),
                               e.measurement, edge_information(e.measurement, e.information), false};
    local.add_edge(edge);
    solution.edges.push_back(edge);
  }
  if (!local.edges().empty()) {
    solution.report = posegraph::optimize(local, options);
    for (auto& frame : solution.frames) frame.relative = local.node(frame.id).pose;
  }
  return solution;
}

}  // namespace cvo::slam
