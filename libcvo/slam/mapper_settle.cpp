// Mapper: settled merged keyframes (mapper.hpp's header, Backend::settle).
#include <algorithm>

#include "libcvo/slam/mapper.hpp"

namespace cvo::slam {

std::size_t Mapper::settle() {
  const std::size_t before = forgotten_keyframes_;
  for (auto& [id, s] : sessions_) {
    if (s.unsettled.empty() || s.keyframes.size() < 2) continue;
    const std::int64_t below = std::prev(s.keyframes.end(), 2)->first;  // its two newest stay
    for (auto it = s.unsettled.begin(); it != s.unsettled.end() && *it < below;) {
      const auto record = s.keyframes.find(*it);
      const auto forgotten =
          record == s.keyframes.end() ? std::nullopt : backend_.settle(node(s, record->second.frame));
      if (record != s.keyframes.end() && !forgotten) {  // its local graph is not in yet
        ++it;
        continue;
      }
      s.settled_through = std::max(s.settled_through, *it);
      it = s.unsettled.erase(it);
      if (forgotten)
        for (const posegraph::NodeId n : *forgotten) forget(n);
    }
  }
  // The map's loops changed; the keyframe graph, and so its marginals, did not.
  if (forgotten_keyframes_ != before) ++revision_;
  return forgotten_keyframes_ - before;
}

void Mapper::forget(posegraph::NodeId keyframe) {
  const auto of = keyframe_of_node_.find(keyframe);
  if (of == keyframe_of_node_.end()) return;
  const auto [session, id] = of->second;
  Session& s = sessions_.at(session);
  s.keyframes.erase(id);
  s.unsettled.erase(id);
  ++s.forgotten;
  keyframe_of_node_.erase(of);
  ++forgotten_keyframes_;
  for (auto it = loops_.begin(); it != loops_.end();) {
    if (it->second.from != keyframe && it->second.to != keyframe) {
      ++it;
      continue;
    }
    for (auto& [other_id, other] : sessions_) std::erase(other.loops, it->first);
    it = loops_.erase(it);
  }
}

}  // namespace cvo::slam
