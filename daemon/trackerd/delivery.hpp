#pragma once
// cvo-trackerd's side of "nothing lost to a dead peer" (issue 28): what the back end acknowledged of
// each session (acknowledgements.hpp), the spool that keeps the rest across a crash (spool.hpp), and
// the linger at a clean exit. The publisher tells it what went out and what the back end said; it
// says what to send again, what an old session left in the spool to hand over, when the exit may
// come, and what was not acknowledged by then. No LCM here. Used by the publisher thread only.
//
// The linger: once the tracker is done, it waits up to trackerd.linger_s for the back end to
// acknowledge every keyframe it published (sending again what is due meanwhile), but only when a
// back end ever acknowledged anything: with none listening it exits at once (the spool keeps it all).
#include <chrono>
#include <cstdint>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "daemon/trackerd/acknowledgements.hpp"
#include "daemon/trackerd/spool.hpp"

namespace cvo::daemon::trackerd {

class Delivery {
 public:
  using Clock = Acknowledgements::Clock;
  /// spool_dir "none" (or ""): no spool. A spool that cannot be opened is none, said in *warning.
  Delivery(const std::string& spool_dir, std::uintmax_t spool_bytes, double linger_s, std::string* warning);

  /// A message of keyframe `id` went out for the first time (graph: its local graph).
  void published(std::int64_t session, std::int64_t id, bool graph, std::span<const std::uint8_t> message,
                 Clock::time_point now);
  /// The back end acknowledged keyframes below `prefix` of `session` (a word the tracker trusts:
  /// libcvo/lcm/map_decision.hpp). Taken no further than just past the newest keyframe published of
  /// it, since a back end cannot hold what never went out; the spool deletes only what is taken.
  /// Returns the prefix taken (below `prefix` when it claimed more), or nullopt: not a session of ours.
  std::optional<std::int64_t> acknowledged(std::int64_t session, std::int64_t prefix, Clock::time_point now);
  /// The newest keyframe of `session` published with its local graph, or handed over without it;
  /// nullopt: none (a session not ours).
  [[nodiscard]] std::optional<std::int64_t> newest_published(std::int64_t session) const;
  /// Keyframes to send again unasked now: (session, id), keyframe then graph each.
  std::vector<std::pair<std::int64_t, std::int64_t>> due(Clock::time_point now);

  /// What earlier runs left in the spool (sessions other than `session`), oldest first: to hand over.
  [[nodiscard]] std::vector<Spool::Entry> left_over(std::int64_t session) const;
  /// A message the spool holds (graph: the local graph), or nullopt.
  [[nodiscard]] std::optional<std::vector<std::uint8_t>> spooled(std::int64_t session, std::int64_t id,
                                                                 bool graph) const;
  /// Keeps a message made at the hand-over (killed_graph.hpp) in the spool; false when it is not
  /// (why: in spool_note()).
  bool spool(const Spool::Entry& entry, std::span<const std::uint8_t> message);
  /// Marks the left-over messages handed over: their keyframes wait for acknowledgement as this run's do.
  void handed_over(const std::vector<Spool::Entry>& entries, Clock::time_point now);

  /// Whether the publisher, done, may exit now (`done_at`: when it was done).
  [[nodiscard]] bool may_exit(Clock::time_point done_at, Clock::time_point now) const;
  /// What the exit leaves unacknowledged, for the closing note ("" when nothing).
  [[nodiscard]] std::string unacknowledged_note() const;
  /// Spool messages dropped for room, and spool writes that failed, since the last call ("": none).
  std::string spool_note();

 private:
  std::optional<Spool> spool_;
  Acknowledgements acks_;
  std::chrono::duration<double> linger_;
  bool ever_acknowledged_ = false;
  std::set<std::pair<std::int64_t, std::int64_t>> lone_;  // keyframes handed over without their graphs
  std::vector<std::string> failures_;                     // spool writes that failed, since the last note
};

}  // namespace cvo::daemon::trackerd
