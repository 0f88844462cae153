// Backend: merged keyframes (backend.hpp's header, keyframe_merge.hpp's algebra).
#include <optional>
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
  repoint_aliases_of(alias);  // before any edge is resolved through them
  rerouting_ = true;
  for (const auto& e : edges) add_graph_edge(e);
  rerouting_ = false;
  // Held as the keyframe graph holds it, rigidly: a tie far stiffer than any measurement (a softer
  // one, the loop's own information, lets k and c drift apart by the loop's uncertainty, and the
  // estimates that later revisits are confirmed against with them).
  unsynced_.push_back({covering, alias, T, kTieStiffness * symmetric, /*robust=*/false});
  ++revision_;
}

// Keyframes merged into `merged` before it was merged itself now name its covering keyframe: an
// alias must name a node of the graph (keyframe_merge.hpp: chained), never another alias.
void Backend::repoint_aliases_of(NodeId merged) {
  const StoredAlias& outer = aliases_.at(merged);
  const posegraph::Edge first{outer.alias.covering, merged, outer.alias.relative, outer.information, false};
  for (auto& [id, a] : aliases_) {
    if (a.alias.covering != merged) continue;
    const posegraph::Edge e = chained(first, {merged, id, a.alias.relative, a.information, false});
    a.alias.covering = e.from;
    a.alias.relative = e.measurement;
    a.information = e.information;
  }
}

std::optional<std::string> Backend::inconsistency() const {
  for (const auto& [id, a] : aliases_) {
    const std::string name = "alias " + std::to_string(id) + " of " + std::to_string(a.alias.covering);
    if (a.alias.alias != id) return name + ": it names another keyframe";
    if (keyframes_.contains(id)) return name + ": a node of the keyframe graph as well";
    if (aliases_.contains(a.alias.covering)) return name + ": a chain (the keyframe it names is an alias)";
    if (!keyframes_.contains(a.alias.covering)) return name + ": the keyframe it names is not in the keyframe graph";
  }
  const auto unheld = [&](NodeId n, const std::string& what) -> std::optional<std::string> {
    if (holds(n)) return std::nullopt;
    return what + " names " + std::to_string(n) + ", which is not held";
  };
  for (const auto& [id, s] : sessions_)
    for (const auto& n : {s.anchor, s.last_node})
      if (const auto why = n ? unheld(*n, "session " + core::session_name(id)) : std::nullopt) return why;
  for (const auto& l : loops_)
    for (const NodeId n : {l.edge.from, l.edge.to})
      if (const auto why = unheld(n, "a loop")) return why;
  for (const auto& b : bridges_)
    for (const NodeId n : {b.from, b.to})
      if (const auto why = unheld(n, "a bridge")) return why;
  return std::nullopt;
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
