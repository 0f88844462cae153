// Mapper's localization in a read-only map: the visitors (mapper.hpp says what they are).
#include <algorithm>
#include <string>
#include <tuple>

#include "libcvo/slam/edge_information.hpp"
#include "libcvo/slam/mapper.hpp"

namespace cvo::slam {
namespace {

constexpr int kFrameBits = 40;

std::string name(core::SessionId session, std::int64_t id) {
  return "keyframe " + std::to_string(id) + " of session " + core::session_name(session);
}

}  // namespace

void Mapper::localize_only() {
  if (!map_below_) map_below_ = next_ordinal_ << kFrameBits;
}

KeyframeOutcome Mapper::visit(const SessionKeyframe& k) {
  auto [it, fresh] = visitors_.try_emplace(k.session);
  Visitor& v = it->second;
  if (fresh) v.ordinal = next_ordinal_++;
  if (v.robot.empty()) v.robot = k.robot;
  if (v.lost) throw MapperError(name(k.session, k.id) + ": the session was lost");
  const auto frame = static_cast<std::int64_t>(k.frame.index);
  for (const auto& w : v.window)
    if (w.id == k.id) {
      KeyframeOutcome duplicate;
      duplicate.duplicate = true;
      return duplicate;
    }
  if (!v.window.empty() && (k.id < v.window.back().id || frame <= (v.window.back().node & ((1LL << kFrameBits) - 1))))
    throw MapperError(name(k.session, k.id) + " (frame " + std::to_string(frame) +
                      ") is older than the session's newest keyframe");

  const posegraph::NodeId id = (v.ordinal << kFrameBits) | frame;
  loop_closure::KeyframePlacement placement{
      id, std::nullopt, v.correction.value_or(core::SE3()) * k.odometry,
      v.correction && !order_.empty() ? backend_.piece(order_.front()) : k.session, map_below_};
  if (!v.window.empty()) placement.previous = v.window.back().node;
  const auto loops = detect(k, placement);
  v.window.push_back({k.id, id, k.frame.timestamp, k.odometry, std::nullopt});
  v.newest_time = k.frame.timestamp;
  v.last_used = ++revision_;
  ++v.keyframes;

  KeyframeOutcome outcome;
  outcome.loops_tried = detector_.last_attempts().size();
  const auto& graph = backend_.keyframe_graph();
  for (const auto& loop : loops) {
    // Only keyframes placed in the map localize: an unplaced stored session is a piece of its own.
    if (!graph.contains(loop.from) || !backend_.placed(backend_.session_of(loop.from))) continue;
    v.matches.push_back({loop, graph.node(loop.from).pose});
    v.last_match_time = k.frame.timestamp;
    MapLoop m;
    m.loop = loop;
    std::tie(m.from_session, m.from_id) = keyframe_of_node_.at(loop.from);
    m.to_session = k.session;
    m.to_id = k.id;
    m.from_frame = loop.from & ((1LL << kFrameBits) - 1);
    m.to_frame = frame;
    outcome.loops.push_back(m);
  }
  move_window(v);
  const bool was_localized = v.correction.has_value();
  solve(v, k.id);
  if (!was_localized && v.correction) {
    v.localized_at_keyframe = k.id;
    outcome.joined.push_back(k.session);
  }
  forget_idle_visitors();
  return outcome;
}

std::vector<loop_closure::LoopClosure> Mapper::detect(const SessionKeyframe& k,
                                                      const loop_closure::KeyframePlacement& placement) {
  try {
    auto loops = detector_.add_keyframe(placement, k.frame, k.cloud);
    loops_tried_ += detector_.last_attempts().size();
    return loops;
  } catch (const std::exception& e) {
    throw MapperError(name(k.session, k.id) + ": " + e.what());
  }
}

// The window keeps its newest keyframes: the oldest leave it, the loop detector and their matches.
void Mapper::move_window(Visitor& v) {
  while (v.window.size() > localization_.window_keyframes) {
    const posegraph::NodeId gone = v.window.front().node;
    detector_.remove_keyframe(gone);
    std::erase_if(v.matches, [&](const WindowMatch& m) { return m.loop.to == gone; });
    v.window.pop_front();
  }
}

// The local graph of window keyframe `keyframe_id` gives its edge to the next keyframe (the graph's
// last frame): the keyframe→last-frame registration, its information as the back end takes it.
void Mapper::add_window_graph(Visitor& v, std::int64_t keyframe_id, const odometry::LocalGraph& graph) {
  const auto k = std::find_if(v.window.begin(), v.window.end(), [&](const auto& w) { return w.id == keyframe_id; });
  if (k == v.window.end()) return;  // it left the window, or its keyframe never came: nothing to add
  const std::uint64_t first = graph.keyframe().frame_index, last = graph.nodes().back().frame_index;
  for (const auto& e : graph.edges()) {
    if (e.from != first || e.to != last) continue;
    const posegraph::NodeId base = v.ordinal << kFrameBits;
    k->next = posegraph::Edge{base | static_cast<std::int64_t>(first), base | static_cast<std::int64_t>(last),
                              e.measurement, edge_information(e.measurement, e.information), false};
  }
  if (k->next && k->next->from != k->node) k->next.reset();  // a graph that does not start at its keyframe
  solve(v, v.window.back().id);
  ++revision_;
}

void Mapper::solve(Visitor& v, std::int64_t newest_id) {
  const auto solution = solve_window(v.window, v.matches, v.correction, backend_.parameters());
  if (!solution) return;
  v.correction = solution->correction;
  v.covariance = solution->covariance;
  v.covariance_keyframe = newest_id;
}

void Mapper::mark_lost(core::SessionId session) {
  if (auto it = sessions_.find(session); it != sessions_.end()) {
    it->second.lost = true;
    ++revision_;
    return;
  }
  auto [it, fresh] = visitors_.try_emplace(session);
  Visitor& v = it->second;
  if (fresh) v.ordinal = next_ordinal_++;
  for (const auto& w : v.window) detector_.remove_keyframe(w.node);
  v.window.clear();
  v.matches.clear();
  v.lost = true;
  v.last_used = ++revision_;
  forget_idle_visitors();
}

// At most kMaxWindows windows (the least recently used give theirs up) and kMaxVisitors visitors.
void Mapper::forget_idle_visitors() {
  const auto by_use = [&] {
    std::vector<Visitor*> all;
    for (auto& [id, v] : visitors_) all.push_back(&v);
    std::sort(all.begin(), all.end(), [](const Visitor* a, const Visitor* b) { return a->last_used > b->last_used; });
    return all;
  };
  std::size_t windows = 0;
  for (Visitor* v : by_use()) {
    if (v->window.empty()) continue;
    if (++windows <= kMaxWindows) continue;
    for (const auto& w : v->window) detector_.remove_keyframe(w.node);
    v->window.clear();
    v->matches.clear();
  }
  while (visitors_.size() > kMaxVisitors) {
    const auto oldest = std::min_element(visitors_.begin(), visitors_.end(), [](const auto& a, const auto& b) {
      return a.second.last_used < b.second.last_used;
    });
    for (const auto& w : oldest->second.window) detector_.remove_keyframe(w.node);
    visitors_.erase(oldest);
  }
}

MapSession Mapper::describe(core::SessionId id, const Visitor& v) const {
  MapSession s;
  s.session = id;
  s.visitor = true;
  s.placed = v.correction.has_value();
  s.piece = s.placed && !order_.empty() ? backend_.piece(order_.front()) : id;
  s.keyframes = v.window.size();
  s.joined_at_keyframe = v.localized_at_keyframe;
  s.correction = v.correction.value_or(core::SE3());
  s.state = v.lost     ? core::LocalizationState::kLost
            : s.placed ? core::LocalizationState::kLocalized
                       : core::LocalizationState::kLocalizing;
  s.last_match_time = v.last_match_time;
  if (v.last_match_time >= 0) s.since_match_s = v.newest_time - v.last_match_time;
  s.keyframe_covariance = v.covariance;
  s.covariance_keyframe = v.covariance_keyframe;
  s.robot = v.robot;
  return s;
}

std::string Mapper::robot(core::SessionId id) const {
  if (const auto v = visitors_.find(id); v != visitors_.end()) return v->second.robot;
  if (const auto s = sessions_.find(id); s != sessions_.end()) return s->second.robot;
  return {};
}

MapSession Mapper::session(core::SessionId id) const {
  if (const auto v = visitors_.find(id); v != visitors_.end()) return describe(id, v->second);
  if (const auto s = sessions_.find(id); s != sessions_.end()) return describe(id, s->second);
  MapSession unknown;
  unknown.session = id;
  unknown.piece = id;
  return unknown;
}

std::size_t Mapper::window_keyframes() const {
  std::size_t n = 0;
  for (const auto& [id, v] : visitors_) n += v.window.size();
  return n;
}

}  // namespace cvo::slam
