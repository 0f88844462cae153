#include "daemon/backendd/slice_intake.hpp"

#include <algorithm>

namespace cvo::daemon::backendd {

SliceIntake::SliceIntake(Limits limits) : limits_(limits), live_(limits.live), strangers_(limits.strangers) {}

void SliceIntake::heard(std::int64_t session, Clock::time_point now, std::optional<std::int64_t> keyframe) {
  if (!heard_.contains(session) && !heard_.empty() && heard_.size() >= limits_.max_sessions)
    heard_.erase(std::min_element(heard_.begin(), heard_.end(),
                                  [](const auto& a, const auto& b) { return a.second.when < b.second.when; }));
  Heard& h = heard_[session];
  h.when = now;
  h.newest_keyframe = std::max(h.newest_keyframe, keyframe.value_or(-1));
}

bool SliceIntake::live(std::int64_t session, Clock::time_point now) const {
  const auto it = heard_.find(session);
  return it != heard_.end() && now - it->second.when <= limits_.alive_window;
}

// A message begun among strangers stays there until it completes or goes (its session may be heard
// meanwhile: its slices are not split between the two rooms).
lcm::ChunkAssembly::Added SliceIntake::add(const cvo_lcm::keyframe_chunk_t& chunk, KeyframeGaps& gaps,
                                           Clock::time_point now) {
  const lcm::SlicedName name{chunk.session, chunk.id, chunk.message};
  if (!live(chunk.session, now) || strangers_.holds(name)) {
    // A slice of a session the gaps already wait on is its tracker answering (on a lossy link its
    // slices may come when its statuses do not): its requests go on. progressed() creates nothing,
    // so a stranger's slice still asks for nothing.
    gaps.progressed(chunk.session, chunk.id, now);
    return strangers_.add(chunk);
  }
  const bool graph = chunk.message == cvo_lcm::keyframe_chunk_t::LOCAL_GRAPH;
  if (chunk.id <= heard_.at(chunk.session).newest_keyframe)  // else the pose naming it will say it exists
    gaps.seen(graph ? KeyframeGaps::Seen::kGraphPart : KeyframeGaps::Seen::kPose, chunk.session, chunk.id, now);
  gaps.progressed(chunk.session, chunk.id, now);
  return live_.add(chunk);
}

std::optional<std::vector<lcm::SliceRange>> SliceIntake::missing(const lcm::SlicedName& name,
                                                                 std::size_t max_ranges) const {
  if (auto ranges = live_.missing(name, max_ranges)) return ranges;
  return strangers_.missing(name, max_ranges);
}

void SliceIntake::forget(const lcm::SlicedName& name) {
  live_.forget(name);
  strangers_.forget(name);
}

std::int64_t SliceIntake::strangers_dropped() {
  const std::int64_t dropped = strangers_.dropped_slices() - strangers_counted_;
  strangers_counted_ = strangers_.dropped_slices();
  return dropped;
}

}  // namespace cvo::daemon::backendd
