// Mapper: keyframes merged into the earlier keyframes that cover them (mapper.hpp's header).
#include "libcvo/slam/mapper.hpp"

#include "libcvo/core/information.hpp"

namespace cvo::slam {

std::optional<std::pair<std::size_t, double>> Mapper::covering_loop(const std::vector<loop_closure::LoopClosure>& loops,
                                                                    const std::vector<bool>& entered,
                                                                    posegraph::NodeId keyframe,
                                                                    core::SessionId session) {
  const auto& graph = backend_.keyframe_graph();
  if (!graph.contains(keyframe) || graph.node(keyframe).fixed) return std::nullopt;  // not yet, or an anchor
  const double threshold = detector_.parameters().keyframe.inner_product_ratio_threshold;
  std::optional<std::pair<std::size_t, double>> best;
  for (std::size_t i = 0; i < loops.size(); ++i) {
    const auto& loop = loops[i];
    if (entered[i] || loop.to != keyframe || !graph.contains(loop.from)) continue;
    if (backend_.piece(backend_.session_of(loop.from)) != backend_.piece(session)) continue;  // a join, not a revisit
    const double gamma = detector_.coverage(loop.from, keyframe, loop.measurement);
    if (gamma >= threshold && (!best || gamma > best->second)) best = std::pair{i, gamma};
  }
  return best;
}

void Mapper::merge(const KeyframeMerge& m, posegraph::NodeId keyframe, posegraph::NodeId covering) {
  backend_.merge_keyframe(keyframe, covering, m.relative, m.information);
  if (detector_.contains(keyframe)) detector_.remove_keyframe(keyframe);  // a replayed merge's may be absent
  sessions_.at(m.session).keyframes.at(m.id).merged = true;
  marginals_.invalidate();
  ++revision_;
}

bool Mapper::apply_merge(const KeyframeMerge& m) {
  const std::string what = "merge of keyframe " + std::to_string(m.id) + " of session " +
                           core::session_name(m.session) + " into keyframe " + std::to_string(m.covering_id) +
                           " of session " + core::session_name(m.covering_session);
  const auto s = sessions_.find(m.session);
  const auto c = sessions_.find(m.covering_session);
  if (s == sessions_.end() || c == sessions_.end() || !c->second.keyframes.contains(m.covering_id))
    throw MapperError(what + ": a session or the covering keyframe is unknown");
  if (m.frame < 0 || m.frame >= (std::int64_t{1} << 40) || m.id < 0) throw MapperError(what + ": bad frame or id");
  if (!m.relative.is_finite() || !core::check_information(m.information).ok())
    throw MapperError(what + ": its pose or information is not one an edge may have");
  const auto known = s->second.keyframes.find(m.id);
  if (known != s->second.keyframes.end() && known->second.frame != m.frame)
    throw MapperError(what + ": the keyframe is known with another frame");
  if (known != s->second.keyframes.end() && known->second.merged) return false;
  const auto keyframe = node(s->second, m.frame);
  const auto covering = node(c->second, c->second.keyframes.at(m.covering_id).frame);
  const auto& graph = backend_.keyframe_graph();
  if (!graph.contains(keyframe) || graph.node(keyframe).fixed || !graph.contains(covering) || keyframe == covering)
    throw MapperError(what + ": not two keyframes of the graph, the first free");
  if (known != s->second.keyframes.end()) {  // replayed with its images: its loops are in already
    merge(m, keyframe, covering);
    return true;
  }
  // Its record compacted away: registered from the merge alone, its loops as add_keyframe entered them.
  s->second.keyframes.emplace(m.id, KeyframeRecord{m.frame, m.timestamp, m.odometry});
  keyframe_of_node_.emplace(keyframe, std::pair{m.session, m.id});
  KeyframeOutcome outcome;
  for (const auto& loop : m.joining) enter_loop(s->second, loop, m.timestamp, outcome);
  merge(m, keyframe, covering);
  s->second.last_match_time = m.timestamp;
  for (const auto& loop : m.others) enter_loop(s->second, loop, m.timestamp, outcome);
  after_change();
  return true;
}

}  // namespace cvo::slam
