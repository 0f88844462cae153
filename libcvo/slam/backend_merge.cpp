// Backend: merged keyframes (backend.hpp's header, keyframe_merge.hpp's algebra).
#include <stdexcept>
#include <string>

#include "libcvo/slam/backend.hpp"

namespace cvo::slam {

using posegraph::NodeId;

NodeId Backend::resolve(NodeId node) const {
  const auto it = aliases_.find(node);
  return it == aliases_.end() ? node : it->second.alias.covering;
}

core::SE3 Backend::pose_of(NodeId node) const {
  if (const auto it = aliases_.find(node); it != aliases_.end())
    return keyframes_.node(it->second.alias.covering).pose * it->second.alias.relative;
  return keyframes_.node(node).pose;
}

posegraph::Edge Backend::resolved(const posegraph::Edge& edge) const {
  posegraph::Edge out = edge;
  for (const NodeId end : {edge.from, edge.to})
    if (const auto it = aliases_.find(end); it != aliases_.end()) out = reroute(out, it->second.alias);
  return out;
}

void Backend::add_graph_edge(const posegraph::Edge& edge) {
  const posegraph::Edge e = resolved(edge);
  if (e.from == e.to) return;  // k's own link to the keyframe it was merged into: the alias holds it
  if (!rerouting_) unsynced_.push_back(e);
  const auto& edges = keyframes_.edges();
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const auto& old = edges[i];
    const bool between = (old.from == e.from && old.to == e.to) || (old.from == e.to && old.to == e.from);
    if (between && old.robust == e.robust) return keyframes_.replace_edge(i, fused(old, e));
  }
  keyframes_.add_edge(e);
}

void Backend::merge_keyframe(NodeId alias, NodeId covering, const core::SE3& T, const core::Matrix6d& information) {
  const std::string name = "backend: merge of " + std::to_string(alias) + " into " + std::to_string(covering);
  if (alias == covering) throw std::invalid_argument(name + ": one node");
  if (!keyframes_.contains(covering)) throw std::invalid_argument(name + ": no such keyframe to merge into");
  if (!keyframes_.contains(alias) || keyframes_.node(alias).fixed)
    throw std::invalid_argument(name + ": not a free node of the keyframe graph");
  if (!T.is_finite()) throw std::invalid_argument(name + ": not finite");
  sync_incremental();  // the incremental optimiser keeps k's factors on k (see sync_incremental)
  const auto edges = keyframes_.remove_node(alias);
  const core::Matrix6d symmetric = 0.5 * (information + information.transpose());
  aliases_.emplace(alias, StoredAlias{{alias, covering, T}, symmetric});
  rerouting_ = true;
  for (const auto& e : edges) add_graph_edge(e);
  rerouting_ = false;
  // Held as the keyframe graph holds it, rigidly: a tie far stiffer than any measurement (a softer
  // one, the loop's own information, lets k and c drift apart by the loop's uncertainty, and the
  // estimates that later revisits are confirmed against with them).
  unsynced_.push_back({covering, alias, T, kTieStiffness * symmetric, /*robust=*/false});
  ++revision_;
}

// The global optimisation's view: each alias is a frame held to its covering keyframe.
void Backend::add_alias_edges(posegraph::PoseGraph& all) const {
  for (const auto& [id, a] : aliases_)
    if (all.contains(id) && all.contains(a.alias.covering))
      all.add_edge({a.alias.covering, id, a.alias.relative, a.information, /*robust=*/true});
}

void Backend::follow_aliases(const posegraph::PoseGraph& all) {
  for (auto& [id, a] : aliases_)
    if (all.contains(id) && all.contains(a.alias.covering))
      a.alias.relative = all.node(a.alias.covering).pose.inverse() * all.node(id).pose;
}

}  // namespace cvo::slam
