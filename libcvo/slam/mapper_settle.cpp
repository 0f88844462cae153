// Mapper: settled merged keyframes (mapper.hpp's header, Backend::settle).
#include <algorithm>

#include "libcvo/slam/mapper.hpp"

namespace cvo::slam {

Settlement Mapper::settle() {
  Settlement out;
  for (auto& [id, s] : sessions_) {
    if (s.unsettled.empty() || s.keyframes.size() < 2) continue;
    const std::int64_t below = std::prev(s.keyframes.end(), 2)->first;  // its two newest stay
    for (auto it = s.unsettled.begin(); it != s.unsettled.end() && *it < below;) {
      const std::int64_t keyframe = *it;
      const auto record = s.keyframes.find(keyframe);
      const auto settled = record == s.keyframes.end() ? std::nullopt : backend_.settle(node(s, record->second.frame));
      if (record != s.keyframes.end() && !settled) {
        const bool never = backend_.has_local_graph(node(s, record->second.frame));  // it leaves the revisit
        it = never ? s.unsettled.erase(it) : std::next(it);                          // else: not in yet
        continue;
      }
      s.settled_through = std::max(s.settled_through, keyframe);
      it = s.unsettled.erase(it);
      if (!settled) continue;
      out.graphs.emplace_back(id, keyframe);
      for (const auto& e : settled->edges) out.edges.push_back(named(e));
      for (const posegraph::NodeId n : settled->forgotten)
        if (const auto name = forget(n)) out.keyframes.push_back(*name);
    }
  }
  for (auto& [key, s] : sessions_) {  // forget() may count a keyframe of another session
    const core::SessionId id = key;   // a copy: clang 14 cannot capture a structured binding
    if (std::find_if(out.keyframes.begin(), out.keyframes.end(), [&](const auto& k) { return k.first == id; }) !=
            out.keyframes.end() ||
        std::find_if(out.graphs.begin(), out.graphs.end(), [&](const auto& k) { return k.first == id; }) !=
            out.graphs.end())
      out.tallies.push_back({id, s.forgotten_before + s.forgotten, s.settled_through});
  }
  // The map's loops changed; the keyframe graph, and so its marginals, did not.
  if (!out.empty()) ++revision_;
  check_in_debug();
  return out;
}

SettledEdge Mapper::named(const posegraph::Edge& e) const {
  const auto [from_session, from_id] = keyframe_of_node_.at(e.from);
  const auto [to_session, to_id] = keyframe_of_node_.at(e.to);
  return {from_session, to_session, from_id, to_id, e.robust, e.measurement, e.information};
}

void Mapper::apply_settled(const SettledEdge& e) {
  const auto node_of = [&](core::SessionId session, std::int64_t id) {
    const auto s = sessions_.find(session);
    if (s == sessions_.end() || !s->second.keyframes.contains(id))
      throw MapperError("settled edge: keyframe " + std::to_string(id) + " of session " + core::session_name(session) +
                        " is unknown");
    return node(s->second, s->second.keyframes.at(id).frame);
  };
  try {
    backend_.apply_settled(
        {node_of(e.from_session, e.from_id), node_of(e.to_session, e.to_id), e.measurement, e.information, e.robust});
  } catch (const std::invalid_argument& error) {
    throw MapperError(std::string("settled edge: ") + error.what());
  }
  ++revision_;
  marginals_.invalidate();
  check_in_debug();
}

void Mapper::apply_tally(const SessionTally& tally) {
  const auto s = sessions_.find(tally.session);
  if (s == sessions_.end())
    throw MapperError("tally of session " + core::session_name(tally.session) + ": the session is unknown");
  // Those it counts have no record left, so none is among those this run forgot: they add up.
  s->second.forgotten_before = std::max(s->second.forgotten_before, tally.forgotten);
  s->second.settled_through = std::max(s->second.settled_through, tally.settled_through);
  ++revision_;
}

std::optional<std::pair<core::SessionId, std::int64_t>> Mapper::forget(posegraph::NodeId keyframe) {
  const auto of = keyframe_of_node_.find(keyframe);
  if (of == keyframe_of_node_.end()) return std::nullopt;
  const auto name = of->second;
  Session& s = sessions_.at(name.first);
  s.keyframes.erase(name.second);
  s.unsettled.erase(name.second);
  ++s.forgotten;
  ++forgotten_keyframes_;
  keyframe_of_node_.erase(of);
  for (auto it = loops_.begin(); it != loops_.end();) {
    if (it->second.from != keyframe && it->second.to != keyframe) {
      ++it;
      continue;
    }
    for (auto& [other_id, other] : sessions_) std::erase(other.loops, it->first);
    it = loops_.erase(it);
  }
  return name;
}

}  // namespace cvo::slam
