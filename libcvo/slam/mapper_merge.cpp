// Mapper: keyframes merged into the earlier keyframes that cover them (mapper.hpp's header).
#include "libcvo/slam/mapper.hpp"

#include <tuple>

#include "libcvo/core/information.hpp"

namespace cvo::slam {

std::optional<std::pair<std::size_t, double>> Mapper::covering_loop(const std::vector<loop_closure::LoopClosure>& loops,
                                                                    posegraph::NodeId keyframe,
                                                                    core::SessionId session) {
  const auto& graph = backend_.keyframe_graph();
  if (!graph.contains(keyframe) || graph.node(keyframe).fixed) return std::nullopt;  // not yet, or an anchor
  const double threshold = detector_.parameters().keyframe.inner_product_ratio_threshold;
  std::optional<std::pair<std::size_t, double>> best;
  for (std::size_t i = 0; i < loops.size(); ++i) {
    const auto& loop = loops[i];
    if (loop.to != keyframe || !graph.contains(loop.from)) continue;
    if (backend_.piece(backend_.session_of(loop.from)) != backend_.piece(session)) continue;  // a join, not a revisit
    const double gamma = detector_.coverage(loop.from, keyframe, loop.measurement);
    if (gamma >= threshold && (!best || gamma > best->second)) best = std::pair{i, gamma};
  }
  return best;
}

void Mapper::merge(const KeyframeMerge& m, posegraph::NodeId keyframe, posegraph::NodeId covering) {
  backend_.merge_keyframe(keyframe, covering, m.relative, m.information);
  if (detector_.contains(keyframe)) detector_.remove_keyframe(keyframe);  // a replayed merge's may be absent
  auto& s = sessions_.at(m.session);
  s.keyframes.at(m.id).merged = true;
  s.unsettled.insert(m.id);
  marginals_.invalidate();
  ++revision_;
  check_in_debug();
}

KeyframeMerge Mapper::merge_of(core::SessionId session, std::int64_t id, const KeyframeRecord& record) {
  KeyframeMerge m;
  m.session = session;
  m.id = id;
  m.frame = record.frame;
  m.timestamp = record.timestamp;
  m.odometry = record.odometry;
  return m;
}

std::optional<KeyframeMerge> Mapper::enter_loops(Session& s, KeyframeMerge m, posegraph::NodeId node,
                                                 const FoundLoops& found, KeyframeOutcome& outcome) {
  const auto& loops = found.loops;
  std::vector<bool> entered(loops.size(), false);
  // Loops that join pieces first: then the keyframe is in the map and may be merged (see the header).
  for (std::size_t i = 0; i < loops.size(); ++i)
    if (backend_.holds(loops[i].from) &&
        backend_.piece(backend_.session_of(backend_.resolve(loops[i].from))) != backend_.piece(m.session)) {
      enter_loop(s, loops[i], m.timestamp, outcome);
      m.joining.push_back(loops[i]);
      entered[i] = true;
    }
  auto covering = covering_loop(loops, node, m.session);
  const auto confirmed = covering_loop(found.confirmations, node, m.session);
  const bool by_confirmation = confirmed && (!covering || confirmed->second > covering->second);
  if (by_confirmation) covering = confirmed;
  if (covering) {
    const auto& loop = by_confirmation ? found.confirmations[covering->first] : loops[covering->first];
    std::tie(m.covering_session, m.covering_id) = keyframe_of_node_.at(loop.from);
    m.relative = loop.measurement;
    m.information = loop.information;
    m.gamma = covering->second;
    merge(m, node, loop.from);
    if (!by_confirmation) entered[covering->first] = true;  // the alias holds it (a joining loop: from now on)
    s.last_match_time = m.timestamp;
  }
  for (std::size_t i = 0; i < loops.size(); ++i)
    if (!entered[i]) {
      enter_loop(s, loops[i], m.timestamp, outcome);
      if (covering) m.others.push_back(loops[i]);
    }
  if (!covering) return std::nullopt;
  return m;
}

std::optional<Mapper::FirstLoops> Mapper::first_loops(Session& s, std::int64_t next, posegraph::NodeId next_node) {
  if (!s.undetected_first) return std::nullopt;
  const std::int64_t first = *s.undetected_first;
  const auto before = s.keyframes.lower_bound(next);
  if (before == s.keyframes.begin() || std::prev(before)->first != first) return std::nullopt;  // not its successor
  s.undetected_first.reset();
  const auto node = this->node(s, std::prev(before)->second.frame);
  if (std::prev(before)->second.merged || !detector_.contains(node) || !detector_.contains(next_node))
    return std::nullopt;
  auto loops = detector_.detect_first(node, next_node);
  loops_tried_ += detector_.last_attempts().size();
  return FirstLoops{first, node, {std::move(loops), detector_.last_confirmations()}};
}

std::optional<KeyframeMerge> Mapper::merge_first(Session& s, const FirstLoops& found) {
  const core::SessionId session = keyframe_of_node_.at(found.node).first;
  if (!covering_loop(found.found.loops, found.node, session) &&
      !covering_loop(found.found.confirmations, found.node, session))
    return std::nullopt;    // nothing entered
  KeyframeOutcome ignored;  // its loops are the merge's
  return enter_loops(s, merge_of(session, found.id, s.keyframes.at(found.id)), found.node, found.found, ignored);
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
  if (known == s->second.keyframes.end() && !backend_.holds(keyframe)) return merge_settled(m, keyframe, covering);
  // An anchor may be merged through a loop that joins its piece (which frees it) and is entered first.
  // A session's first keyframe, merged once its successor's loops had joined the session: replayed
  // without its record, the successor finds none (its predecessor, η's normaliser, is not in the
  // detector), so the merge's own verified loop joins in their place.
  std::vector<loop_closure::LoopClosure> joining = m.joining;
  const bool apart = backend_.piece(m.session) != backend_.piece(m.covering_session);
  if (known == s->second.keyframes.end() && joining.empty() && apart && graph.contains(keyframe))
    joining.push_back({covering, keyframe, m.relative, m.information, 0, 0, 0});
  const bool freed_by_join = !joining.empty() && apart;
  if (!graph.contains(keyframe) || (graph.node(keyframe).fixed && !freed_by_join) || !graph.contains(covering) ||
      keyframe == covering)
    throw MapperError(what + ": not two keyframes of the graph, the first free");
  // Replayed with its images, its loops are in already, unless it is a first keyframe whose
  // successor's images are gone (its loops searched at the successor: merge_first).
  if (known != s->second.keyframes.end() && s->second.undetected_first != m.id) {
    merge(m, keyframe, covering);
    return true;
  }
  if (known == s->second.keyframes.end()) {  // its record compacted away: registered from the merge alone
    s->second.keyframes.emplace(m.id, KeyframeRecord{m.frame, m.timestamp, m.odometry});
    keyframe_of_node_.emplace(keyframe, std::pair{m.session, m.id});
  }
  if (s->second.undetected_first == m.id) s->second.undetected_first.reset();
  KeyframeOutcome outcome;
  for (const auto& loop : joining) enter_loop(s->second, loop, m.timestamp, outcome);
  merge(m, keyframe, covering);
  s->second.last_match_time = m.timestamp;
  for (const auto& loop : m.others) enter_loop(s->second, loop, m.timestamp, outcome);
  after_change();
  return true;
}

// A merged keyframe whose local graph into it was settled (a store of settled revisits): an alias
// that no graph node ever was; its own graph, if kept, follows. Its session had joined already (its
// predecessor was merged), so it has no joining loops.
bool Mapper::merge_settled(const KeyframeMerge& m, posegraph::NodeId keyframe, posegraph::NodeId covering) {
  Session& s = sessions_.at(m.session);
  if (!m.joining.empty() || !backend_.holds(covering))  // Backend::add_alias follows a merged one
    throw MapperError("merge of keyframe " + std::to_string(m.id) + " of session " + core::session_name(m.session) +
                      ": neither in the graph nor after a settled one");
  try {
    backend_.add_alias(keyframe, covering, m.relative, m.information);
  } catch (const std::invalid_argument& e) {
    throw MapperError(e.what());
  }
  s.keyframes.emplace(m.id, KeyframeRecord{m.frame, m.timestamp, m.odometry, true});
  keyframe_of_node_.emplace(keyframe, std::pair{m.session, m.id});
  s.unsettled.insert(m.id);
  s.last_match_time = m.timestamp;
  KeyframeOutcome outcome;
  for (const auto& loop : m.others) enter_loop(s, loop, m.timestamp, outcome);
  marginals_.invalidate();
  ++revision_;
  after_change();
  return true;
}

}  // namespace cvo::slam
