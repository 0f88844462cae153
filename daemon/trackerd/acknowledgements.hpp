#pragma once
// cvo-trackerd's view of what the back end holds of its sessions (map_correction_t.acknowledged,
// issue 28): keyframes below the acknowledged id are stored with their local graphs. What is not
// acknowledged yet is what the tracker must keep (its spool), wait for at its exit, and send again
// unasked: a back end that restarted, or that lost a session's newest keyframes with nothing after
// them to name them, never asks for those.
//
// A keyframe can be acknowledged once its local graph is out (the back end acknowledges both).
// From then on, while the back end is heard (an acknowledgement of the session within kAlive), a
// keyframe not acknowledged after kFirstWait is due to be sent again, then again after waits that
// double up to kMaxWait. A keyframe never published is not waited for. Used by the publisher
// thread only.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <vector>

namespace cvo::daemon::trackerd {

class Acknowledgements {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr std::chrono::seconds kFirstWait{3}, kMaxWait{20}, kAlive{5};

  /// Keyframe `id` of `session` and its local graph are out: from now on it can be acknowledged.
  void ready(std::int64_t session, std::int64_t id, Clock::time_point now);
  /// The back end said keyframes below `prefix` of `session` are held (its newest word counts: a back
  /// end that restarted without its store says less than before). The caller passes a prefix no
  /// further than newest() + 1: keyframes made later are waited for whatever a word said before.
  void acknowledged(std::int64_t session, std::int64_t prefix, Clock::time_point now);

  /// Keyframes of `session` due to be sent again now (at most `max`), each counted sent.
  std::vector<std::int64_t> due(std::int64_t session, Clock::time_point now, std::size_t max);
  /// Keyframes ready and not acknowledged, ascending.
  [[nodiscard]] std::vector<std::int64_t> unacknowledged(std::int64_t session) const;
  [[nodiscard]] std::int64_t prefix(std::int64_t session) const;
  [[nodiscard]] std::vector<std::int64_t> sessions() const;  // every session with keyframes ready
  /// The newest keyframe of `session` ever ready (acknowledged or not); nullopt: none (not ours).
  [[nodiscard]] std::optional<std::int64_t> newest(std::int64_t session) const;

 private:
  struct Waiting {
    Clock::time_point next;  // when it is due again
    int sent = 0;            // times sent again
  };
  struct Session {
    std::int64_t prefix = 0;
    std::int64_t newest = -1;   // the newest keyframe ready
    Clock::time_point heard{};  // the last acknowledgement
    bool ever_heard = false;
    std::map<std::int64_t, Waiting> waiting;  // ready, at or past the prefix
  };
  std::map<std::int64_t, Session> sessions_;
};

}  // namespace cvo::daemon::trackerd
