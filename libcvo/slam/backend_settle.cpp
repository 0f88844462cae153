// Backend: settled merged keyframes (backend.hpp's header).
#include <algorithm>

#include "libcvo/slam/backend.hpp"

namespace cvo::slam {

using posegraph::NodeId;

void Backend::add_settled(const posegraph::Edge& edge) {
  const posegraph::Edge e = resolved(edge);
  if (e.from == e.to) return;  // within one keyframe: its alias holds it
  const auto key = std::tuple{std::min(e.from, e.to), std::max(e.from, e.to), e.robust};
  if (const auto it = settled_.find(key); it != settled_.end())
    it->second = fused(it->second, e);
  else
    settled_.emplace(key, e);
}

std::optional<std::vector<NodeId>> Backend::settle(NodeId keyframe) {
  const auto g = graphs_.find(keyframe);
  const auto alias = aliases_.find(keyframe);
  if (alias == aliases_.end() || g == graphs_.end() || !g->second.keyframe_edge) return std::nullopt;
  const posegraph::Edge edge = *g->second.keyframe_edge;
  const NodeId last = edge.to;
  if (!holds(last)) return std::nullopt;
  add_settled(edge);
  graph_ending_at_.erase(last);
  graphs_.erase(g);
  alias->second.settled = true;
  ++revision_;
  std::vector<NodeId> forgotten;
  for (const NodeId n : {keyframe, last})
    if (forget_if_unused(n)) forgotten.push_back(n);
  return forgotten;
}

bool Backend::forget_if_unused(NodeId alias) {
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
    add_settled(it->edge);
    it = loops_.erase(it);
  }
  aliases_.erase(a);
  session_of_node_.erase(alias);
  return true;
}

}  // namespace cvo::slam
