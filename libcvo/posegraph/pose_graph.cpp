#include "libcvo/posegraph/pose_graph.hpp"

#include <stdexcept>
#include <string>

#include "libcvo/core/information.hpp"

namespace cvo::posegraph {

void PoseGraph::add_node(NodeId id, const core::SE3& pose, bool fixed) {
  if (!pose.is_finite()) throw std::invalid_argument("pose graph: node " + std::to_string(id) + " is not finite");
  if (!nodes_.emplace(id, Node{pose, fixed}).second)
    throw std::invalid_argument("pose graph: node " + std::to_string(id) + " exists already");
}

void PoseGraph::add_edge(const Edge& edge) {
  const std::string name = "pose graph: edge " + std::to_string(edge.from) + " -> " + std::to_string(edge.to);
  if (!contains(edge.from) || !contains(edge.to)) throw std::invalid_argument(name + " names an unknown node");
  if (edge.from == edge.to) throw std::invalid_argument(name + " joins a node to itself");
  if (!edge.measurement.is_finite()) throw std::invalid_argument(name + " is not finite");
  // A non-symmetric information would make the normal equations non-symmetric, an indefinite one
  // the cost unbounded below (information.hpp): refuse both rather than optimise a wrong problem.
  if (const auto check = core::check_information(edge.information); !check.ok())
    throw std::invalid_argument(name + ": " + check.why());
  edges_.push_back(edge);
}

void PoseGraph::set_pose(NodeId id, const core::SE3& pose) { nodes_.at(id).pose = pose; }

void PoseGraph::set_fixed(NodeId id, bool fixed) { nodes_.at(id).fixed = fixed; }

}  // namespace cvo::posegraph
