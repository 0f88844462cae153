#pragma once
// A 3-D pose graph as a plain value: nodes are poses T_world_node, edges are relative-pose
// measurements between two nodes.
//
// An edge (i, j) measures T_ij = T_i^-1 T_j. Its residual is, with E = T_ij^-1 T_i^-1 T_j,
//   e_ij = [t_E; 2 vec(q_E)]   in R^6, [translation; rotation] (core::SE3's order),
// equal to log(E) to first order (residual.hpp says why not log(E) itself), and its information matrix Omega (6x6,
// symmetric positive semi-definite) is in that same order. The cost of the graph is  F = 1/2 sum_edges rho(e^T Omega e)
// with rho the identity, or the Cauchy kernel on edges marked robust (see cost.hpp).
#include <cstddef>
#include <cstdint>
#include <map>
#include <vector>

#include "libcvo/core/se3.hpp"

namespace cvo::posegraph {

using NodeId = std::int64_t;

struct Node {
  core::SE3 pose;      // T_world_node
  bool fixed = false;  // held constant by the optimiser
};

struct Edge {
  NodeId from = 0;                                          // i
  NodeId to = 0;                                            // j
  core::SE3 measurement;                                    // T_ij = T_i^-1 T_j
  core::Matrix6d information = core::Matrix6d::Identity();  // [translation, rotation] order
  bool robust = false;                                      // Cauchy kernel instead of plain squares
};

class PoseGraph {
 public:
  /// Throws std::invalid_argument when the id exists already or the pose is not finite.
  void add_node(NodeId id, const core::SE3& pose, bool fixed = false);
  /// Both nodes must exist, from != to, the measurement must be finite and the information pass
  /// check_information (information.hpp: finite, symmetric, positive semi-definite); throws
  /// std::invalid_argument otherwise.
  void add_edge(const Edge& edge);

  void set_pose(NodeId id, const core::SE3& pose);  // throws std::out_of_range for an unknown id
  void set_fixed(NodeId id, bool fixed);            // throws std::out_of_range for an unknown id
  /// Removes a node and every edge that touches it, returned in their order (a keyframe merged into
  /// another, slam/keyframe_merge.hpp). Throws std::out_of_range for an unknown id.
  std::vector<Edge> remove_node(NodeId id);
  /// The index in edges() of an edge between a and b in either direction; edges().size() if none.
  [[nodiscard]] std::size_t edge_between(NodeId a, NodeId b) const;
  /// Replaces edge `index` by one between the same two nodes (checked as add_edge does).
  void replace_edge(std::size_t index, const Edge& edge);

  [[nodiscard]] bool contains(NodeId id) const { return nodes_.contains(id); }
  [[nodiscard]] const Node& node(NodeId id) const { return nodes_.at(id); }
  /// Ordered by id, so every walk over the graph (and so the optimiser's variable order) is
  /// deterministic.
  [[nodiscard]] const std::map<NodeId, Node>& nodes() const { return nodes_; }
  [[nodiscard]] const std::vector<Edge>& edges() const { return edges_; }

 private:
  std::map<NodeId, Node> nodes_;
  std::vector<Edge> edges_;
};

}  // namespace cvo::posegraph
