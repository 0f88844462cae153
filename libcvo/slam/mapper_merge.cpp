// Mapper: keyframes merged into the earlier keyframes that cover them (mapper.hpp's header).
#include "libcvo/slam/mapper.hpp"

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
  detector_.remove_keyframe(keyframe);
  sessions_.at(m.session).keyframes.at(m.id).merged = true;
  marginals_.invalidate();
  ++revision_;
}

void Mapper::apply_merge(const KeyframeMerge& m) {
  const std::string what = "merge of keyframe " + std::to_string(m.id) + " of session " +
                           core::session_name(m.session) + " into keyframe " + std::to_string(m.covering_id) +
                           " of session " + core::session_name(m.covering_session);
  const auto s = sessions_.find(m.session);
  const auto c = sessions_.find(m.covering_session);
  if (s == sessions_.end() || c == sessions_.end() || !s->second.keyframes.contains(m.id) ||
      !c->second.keyframes.contains(m.covering_id))
    throw MapperError(what + ": a keyframe is unknown");
  const auto& record = s->second.keyframes.at(m.id);
  const auto keyframe = node(s->second, record.frame);
  const auto covering = node(c->second, c->second.keyframes.at(m.covering_id).frame);
  const auto& graph = backend_.keyframe_graph();
  if (record.merged || !graph.contains(keyframe) || graph.node(keyframe).fixed || !graph.contains(covering) ||
      keyframe == covering)
    throw MapperError(what + ": not two keyframes of the graph, the first free");
  merge(m, keyframe, covering);
}

}  // namespace cvo::slam
