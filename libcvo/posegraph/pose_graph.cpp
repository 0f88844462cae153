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

std::vector<Edge> PoseGraph::remove_node(NodeId id) {
  if (nodes_.erase(id) == 0) throw std::out_of_range("pose graph: node " + std::to_string(id) + " is unknown");
  std::vector<Edge> removed;
  std::erase_if(edges_, [&](const Edge& e) {
    if (e.from != id && e.to != id) return false;
    removed.push_back(e);
    return true;
  });
  return removed;
}

std::size_t PoseGraph::edge_between(NodeId a, NodeId b) const {
  for (std::size_t i = 0; i < edges_.size(); ++i)
    if ((edges_[i].from == a && edges_[i].to == b) || (edges_[i].from == b && edges_[i].to == a)) return i;
  return edges_.size();
}

void PoseGraph::replace_edge(std::size_t index, const Edge& edge) {
  const Edge& old = edges_.at(index);
  if (!((old.from == edge.from && old.to == edge.to) || (old.from == edge.to && old.to == edge.from)))
    throw std::invalid_argument("pose graph: replace_edge between other nodes");
  if (!edge.measurement.is_finite()) throw std::invalid_argument("pose graph: replaced edge is not finite");
  if (const auto check = core::check_information(edge.information); !check.ok())
    throw std::invalid_argument("pose graph: replaced edge: " + check.why());
  edges_[index] = edge;
}

}  // namespace cvo::posegraph
