#pragma once
// A pose graph replayed as it would have been built: node after node (in id order), each with the
// edges that join it to the nodes before it. What an incremental optimiser is fed in tests and
// benchmarks, from a g2o file or a simulated patrol.
#include <vector>

#include "libcvo/posegraph/incremental_optimizer.hpp"
#include "libcvo/posegraph/pose_graph.hpp"

namespace cvo::posegraph {

struct Arrival {
  NodeId node = 0;
  bool fixed = false;
  std::vector<Edge> edges;  // every edge whose later node (in id order) is `node`, in the graph's order
};

/// The graph's nodes in id order with their edges; an edge between a node and itself is refused
/// by PoseGraph already.
std::vector<Arrival> arrivals(const PoseGraph& graph);

/// The usual odometry initial guess of an arriving node: the estimate of the earlier end of its
/// first edge composed with that edge's measurement (inverted when the edge points backwards);
/// `fallback` (the file's pose) for a node that arrives without an edge.
core::SE3 arrival_guess(const IncrementalOptimizer& optimizer, const Arrival& arrival, const core::SE3& fallback);

/// Adds the arriving node (at arrival_guess) and its edges.
void add_arrival(IncrementalOptimizer& optimizer, const Arrival& arrival, const core::SE3& fallback);

}  // namespace cvo::posegraph
