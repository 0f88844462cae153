// Receiving's side of keyframes lost in transport (keyframe_gaps.hpp): what cvo-receive asks for
// again on CVO_KEYFRAME_REQUEST, and what it gives up.
#include <algorithm>
#include <limits>

#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/keyframe_chunk_t.hpp"
#include "cvo_lcm/keyframe_request_t.hpp"
#include "daemon/backendd/receiving.hpp"
#include "libcvo/auth/lcm_publish.hpp"
#include "libcvo/core/units.hpp"

namespace cvo::daemon::backendd {
namespace {

// Why the back end stopped asking for keyframes (KeyframeGaps::GivenUp::Reason), for its note.
std::string why_given_up(KeyframeGaps::GivenUp::Reason reason) {
  using Reason = KeyframeGaps::GivenUp::Reason;
  switch (reason) {
    case Reason::kSilent: return "asked again, and its tracker is no longer heard";
    case Reason::kUnanswered: return "asked again while its tracker ran, with no answer: it no longer holds them";
    case Reason::kNoAsking: return "a recording cannot be asked again";
    case Reason::kBounds: return "beyond what is waited for (a gap older than any tracker keeps, or too many)";
    case Reason::kStopped: return "the back end stopped while waiting";
  }
  return "unknown";
}

}  // namespace

// A log cannot answer: what it lacks is lost as soon as it is noticed.
GapPolicy Receiving::gap_policy(const config::Config& config) {
  GapPolicy policy;
  if (is_log(config.backendd.lcm_url)) policy.requests = 0;
  policy.ids_per_round = std::min<std::size_t>(policy.ids_per_round, cvo_lcm::keyframe_request_t::MAX_IDS);
  return policy;
}

// What a request asks of the tracker: of a keyframe nothing of which came, all of it (`ids`: the
// keyframe, then its local graph); of one that came in part, the slices missing and all of its
// local graph; of a local graph alone, its missing slices, or all of it. The ranges of one keyframe
// are the closest holes merged, so that all fit the request (MAX_RANGES).
cvo_lcm::keyframe_request_t Receiving::request_message(const KeyframeGaps::Request& request) const {
  using Chunk = cvo_lcm::keyframe_chunk_t;
  cvo_lcm::keyframe_request_t m{};
  m.version = cvo_lcm::keyframe_request_t::SCHEMA_VERSION;
  m.utime = core::wall_utime();
  m.session = request.session;
  const auto add_range = [&m](std::int64_t id, std::int8_t message, lcm::SliceRange r) {
    m.range_ids.push_back(id);
    m.range_messages.push_back(message);
    m.range_first.push_back(r.first);
    m.range_count.push_back(r.count);
  };
  const lcm::SliceRange all{0, std::numeric_limits<std::int32_t>::max()};
  const std::size_t per_keyframe =
      std::max<std::size_t>(2, cvo_lcm::keyframe_request_t::MAX_RANGES / std::max<std::size_t>(1, request.ids.size()));
  for (const auto id : request.ids) {
    const bool graph_only =
        std::find(request.graphs_only.begin(), request.graphs_only.end(), id) != request.graphs_only.end();
    const auto keyframe =
        graph_only ? std::nullopt : slices_.missing({request.session, id, Chunk::KEYFRAME}, per_keyframe - 1);
    if (!graph_only && !keyframe) {
      m.ids.push_back(id);
      continue;
    }
    for (const auto& r : keyframe.value_or(std::vector<lcm::SliceRange>{})) add_range(id, Chunk::KEYFRAME, r);
    if (early_graphs_.contains({request.session, id})) continue;  // its graph came already
    const auto graph = slices_.missing({request.session, id, Chunk::LOCAL_GRAPH}, 1);
    add_range(id, Chunk::LOCAL_GRAPH, graph ? graph->front() : all);
  }
  m.num_ids = static_cast<std::int32_t>(m.ids.size());
  m.num_ranges = static_cast<std::int32_t>(m.range_ids.size());
  return m;
}

// cvo-receive: the requests due go out on CVO_KEYFRAME_REQUEST, what was given up is noted; at the
// stop everything still waited for is given up. The counts go to CVO_STATUS.
void Receiving::ask_for_missing(::lcm::LCM& lcm, bool stopping) {
  const auto round = stopping ? KeyframeGaps::Round{{}, gaps_.give_up_all()} : gaps_.due(Clock::now());
  for (const auto& request : round.requests) {
    const cvo_lcm::keyframe_request_t m = request_message(request);
    auth::publish(lcm, shared_.bus.signer(), "CVO_KEYFRAME_REQUEST", m);
    std::string ids;
    for (const auto id : request.ids) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
    shared_.notes.note_limited("keyframe request", "asking session " + core::session_name(request.session) +
                                                       " again for keyframes " + ids + " (lost in transport)");
  }
  for (const auto& g : round.given_up) {
    const std::string which = g.first == g.last ? "keyframe " + std::to_string(g.first)
                                                : "keyframes " + std::to_string(g.first) + "-" + std::to_string(g.last);
    shared_.notes.note_limited("keyframes lost", "gave up on " + which + " of session " +
                                                     core::session_name(g.session) +
                                                     ": never came (lost): " + why_given_up(g.reason));
  }
  if (gaps_.recovered() > shared_.counters.keyframes_recovered)
    shared_.notes.note_limited("keyframes recovered",
                               std::to_string(gaps_.recovered()) + " keyframes recovered after a loss in transport");
  shared_.counters.keyframes_requested = gaps_.requested();
  shared_.counters.keyframes_recovered = gaps_.recovered();
  shared_.counters.keyframes_lost = gaps_.lost();
  if (stopping && gaps_.requested() + gaps_.lost() > 0)
    shared_.notes.note("keyframes lost in transport: " + std::to_string(gaps_.requested()) + " asked for again, " +
                       std::to_string(gaps_.recovered()) + " recovered, " + std::to_string(gaps_.lost()) + " lost");
}

}  // namespace cvo::daemon::backendd
