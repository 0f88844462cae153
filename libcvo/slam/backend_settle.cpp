// Backend: settled merged keyframes (backend.hpp's header).
#include <algorithm>
#include <functional>
#include <string>

#include "libcvo/core/information.hpp"
#include "libcvo/slam/backend.hpp"

namespace cvo::slam {

using posegraph::NodeId;

namespace {
std::tuple<NodeId, NodeId, bool> key_of(const posegraph::Edge& e) {
  return {std::min(e.from, e.to), std::max(e.from, e.to), e.robust};
}
}  // namespace

posegraph::Edge Backend::add_settled(const posegraph::Edge& edge) {
  const posegraph::Edge e = resolved(edge);
  if (e.from == e.to) return e;  // within one keyframe: its alias holds it
  const auto [it, added] = settled_.try_emplace(key_of(e), e);
  if (!added) it->second = fused(it->second, e);
  return it->second;
}

std::optional<Backend::Settled> Backend::settle(NodeId keyframe) {
  const auto g = graphs_.find(keyframe);
  const auto alias = aliases_.find(keyframe);
  if (alias == aliases_.end() || g == graphs_.end() || !g->second.keyframe_edge) return std::nullopt;
  const posegraph::Edge edge = *g->second.keyframe_edge;
  const NodeId last = edge.to;
  if (!aliases_.contains(last)) return std::nullopt;  // it joins a kept keyframe: the graph stays
  for (const auto& [id, session] : sessions_)
    if (session.anchor == keyframe) return std::nullopt;  // a session's first graph: it makes its anchor
  Settled out;
  std::map<std::tuple<NodeId, NodeId, bool>, posegraph::Edge> changed;
  const auto settle_edge = [&](const posegraph::Edge& e) {
    const posegraph::Edge now = add_settled(e);
    if (now.from != now.to) changed.insert_or_assign(key_of(now), now);
  };
  settle_edge(edge);
  graph_ending_at_.erase(last);
  graphs_.erase(g);
  alias->second.settled = true;
  ++revision_;
  for (const NodeId n : {keyframe, last})
    if (forget_if_unused(n, settle_edge)) out.forgotten.push_back(n);
  for (auto& [key, e] : changed) out.edges.push_back(e);
  return out;
}

void Backend::apply_settled(const posegraph::Edge& given) {
  const posegraph::Edge e = resolved(given);
  if (!keyframes_.contains(e.from) || !keyframes_.contains(e.to) || e.from == e.to)
    throw std::invalid_argument("backend: settled edge " + std::to_string(given.from) + " -> " +
                                std::to_string(given.to) + ": not between two nodes of the keyframe graph");
  if (!e.measurement.is_finite() || !core::check_information(e.information).ok())
    throw std::invalid_argument("backend: settled edge: not finite, or information no edge may have");
  const auto [it, added] = settled_.try_emplace(key_of(e), e);
  const posegraph::Edge old = it->second;
  it->second = added ? e : (old.from == e.from ? e : reversed(e));
  if (const auto more = added ? std::optional{e} : increment(old, it->second)) add_graph_edge(*more);
  ++revision_;
}

void Backend::add_alias(NodeId alias, NodeId covering, const core::SE3& T, const core::Matrix6d& information) {
  const std::string name = "backend: alias " + std::to_string(alias) + " of " + std::to_string(covering);
  if (holds(alias)) throw std::invalid_argument(name + ": held already");
  if (!holds(covering)) throw std::invalid_argument(name + ": no such keyframe to merge into");
  if (!T.is_finite()) throw std::invalid_argument(name + ": not finite");
  posegraph::Edge e{covering, alias, T, 0.5 * (information + information.transpose()), false};
  // A store may name a keyframe that was merged since (a chain): the alias names its covering node.
  if (const auto outer = aliases_.find(covering); outer != aliases_.end())
    e = chained(
        {outer->second.alias.covering, covering, outer->second.alias.relative, outer->second.information, false}, e);
  aliases_.emplace(alias, StoredAlias{{alias, e.from, e.measurement}, e.information});
  ++revision_;
}

bool Backend::forget_if_unused(NodeId alias, const std::function<void(const posegraph::Edge&)>& settle_edge) {
  const auto a = aliases_.find(alias);
  if (a == aliases_.end() || !a->second.settled || graph_ending_at_.contains(alias)) return false;
  for (const auto& [id, s] : sessions_)
    if (s.anchor == alias || s.last_node == alias) return false;
  if (std::any_of(bridges_.begin(), bridges_.end(),
                  [&](const posegraph::Edge& b) { return b.from == alias || b.to == alias; }))
    return false;
  for (auto it = loops_.begin(); it != loops_.end();) {
    if (it->loop.from != alias && it->loop.to != alias) {
      ++it;
      continue;
    }
    settle_edge(it->edge);
    it = loops_.erase(it);
  }
  aliases_.erase(a);
  session_of_node_.erase(alias);
  return true;
}

}  // namespace cvo::slam
