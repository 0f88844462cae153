#include "libcvo/slam/keyframe_marginals.hpp"

#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "libcvo/posegraph/marginals.hpp"
#include "libcvo/posegraph/residual.hpp"

namespace cvo::slam {

using posegraph::NodeId;

void KeyframeMarginals::invalidate() {
  valid_ = false;
  failed_ = false;
  known_.clear();
}

void KeyframeMarginals::follow(const posegraph::PoseGraph& graph) {
  if (!valid_) {
    failed_ = failed_ && graph.edges().size() == edges_seen_ && graph.nodes().size() == seen_.size();
    return;
  }
  const auto& edges = graph.edges();
  for (std::size_t k = edges_seen_; k < edges.size(); ++k)
    if (!extend(graph, edges[k])) return invalidate();
  edges_seen_ = edges.size();
  if (graph.nodes().size() != seen_.size()) invalidate();  // a new node no edge holds
}

// One new edge: a leaf (one end new) hung from a node whose marginal is held. A new fixed node at
// its other end is a new piece's anchor: its marginal is zero, and it conditions no other piece.
bool KeyframeMarginals::extend(const posegraph::PoseGraph& graph, const posegraph::Edge& e) {
  if (e.robust) return false;
  bool from_new = !seen_.contains(e.from);
  const bool to_new = !seen_.contains(e.to);
  if (from_new && to_new && graph.node(e.from).fixed) {
    known_[e.from] = core::Matrix6d::Zero();
    seen_.insert(e.from);
    from_new = false;
  }
  if (from_new == to_new) return false;  // between old nodes (a cycle), or not hung from the graph
  const NodeId leaf = from_new ? e.from : e.to, old = from_new ? e.to : e.from;
  const auto held = known_.find(old);
  if (held == known_.end() || graph.node(leaf).fixed) return false;
  const Eigen::LLT<core::Matrix6d> omega(e.information);
  if (omega.info() != Eigen::Success) return false;
  const auto lin = posegraph::linearise_edge(graph.node(e.from).pose, graph.node(e.to).pose, e.measurement);
  const core::Matrix6d& J_leaf = from_new ? lin.jacobian_i : lin.jacobian_j;
  const core::Matrix6d& J_old = from_new ? lin.jacobian_j : lin.jacobian_i;
  const core::Matrix6d J_inv = J_leaf.inverse();
  const core::Matrix6d inner = omega.solve(core::Matrix6d::Identity()) + J_old * held->second * J_old.transpose();
  const core::Matrix6d sigma = J_inv * inner * J_inv.transpose();
  known_[leaf] = 0.5 * (sigma + sigma.transpose());
  seen_.insert(leaf);
  return true;
}

void KeyframeMarginals::compute(const posegraph::PoseGraph& graph, const std::vector<NodeId>& nodes,
                                const posegraph::OptimizerOptions& options) {
  invalidate();
  seen_.clear();
  for (const auto& [id, node] : graph.nodes()) seen_.insert(id);
  edges_seen_ = graph.edges().size();
  ++factorisations_;
  try {
    for (const auto& [id, covariance] : posegraph::marginal_covariances(graph, nodes, options))
      known_.emplace(id, covariance);
    valid_ = true;
  } catch (const std::runtime_error&) {  // a piece no edge holds yet: none this time
    failed_ = true;
  }
}

void KeyframeMarginals::keep(const std::vector<NodeId>& nodes) {
  const std::unordered_set<NodeId> wanted(nodes.begin(), nodes.end());
  std::erase_if(known_, [&](const auto& entry) { return !wanted.contains(entry.first); });
}

std::optional<core::Matrix6d> KeyframeMarginals::find(NodeId node) const {
  if (!valid_) return std::nullopt;
  const auto it = known_.find(node);
  return it == known_.end() ? std::nullopt : std::optional<core::Matrix6d>(it->second);
}

}  // namespace cvo::slam
