#pragma once
// When cvo-backendd's map goes out, and which of it: the policy, without LCM (Backendd wires it).
// A tracker needs only its own session's entry, which goes on CVO_MAP_CORRECTION (O(1) bytes); the
// full CVO_MAP (O(N) bytes in the keyframes) goes rarely:
//   - a session's correction after a change when its entry (map_session_t as encoded: correction,
//     state, placement, covariance and its keyframe, last match, ...) differs from the one sent
//     last for it, or none was; the daemon offers only the sessions a change may have touched
//     (its record's; every live session after an optimisation), so a keyframe costs O(1);
//   - a live session's correction again once `resend` has passed since its last, so that one lost
//     on UDP, or missed by a tracker that started listening late, comes again; live: a CVO_POSE or a
//     record of it within `live`, and not lost;
//   - a session's correction at once when the back end holds more of it than its last correction
//     acknowledged, or than none did (held_prefix.hpp): a lingering tracker waits for that word, and
//     the mapper may reach the session's records only after a long backlog (a hand-over of killed
//     sessions' spools), so it goes whether the mapper has seen the session or not;
//   - the full map: the first one at once, with a `map` period of 0 after every change; after a
//     join at once (a new session is placed: once per session); after a loop closure once `loop`
//     has passed since the last (the grid's pace: a planner sees the loop's grid within a second,
//     yet a robot revisiting a room, whose every keyframe closes a loop, does not send its whole
//     map after every keyframe: O(N) bytes per keyframe, O(N^2) over a run); else once `map` has
//     passed since the last while a change waits. The caller asks again from its loop, so a
//     waiting map goes when its time comes. The final one at the stop is the caller's.
// Time is the caller's (the steady clock), so the policy is tested without waiting. cvo-backend
// only.
#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

namespace cvo::daemon::backendd {

class MapSchedule {
 public:
  using Clock = std::chrono::steady_clock;
  struct Periods {
    std::chrono::duration<double> map{5.0};     // backendd.map_period_s
    std::chrono::duration<double> resend{1.0};  // backendd.status_period_s
    std::chrono::duration<double> live{10.0};
    std::chrono::duration<double> loop{1.0};  // the least time between two maps a loop sent
  };
  explicit MapSchedule(const Periods& periods) : periods_(periods) {}

  /// Whether `entry` (the session's, encoded) is other than the last one sent for it.
  [[nodiscard]] bool differs(std::int64_t session, const std::vector<std::uint8_t>& entry) const;
  /// The session's correction with `entry`, acknowledging `acknowledged` keyframes, went out.
  void sent(std::int64_t session, std::vector<std::uint8_t> entry, Clock::time_point now,
            std::int64_t acknowledged = 0);
  /// A record or a CVO_POSE of the session came: it is live.
  void seen(std::int64_t session, Clock::time_point now);
  /// Its tracker said it is lost: no longer live.
  void lost(std::int64_t session);
  /// The live sessions whose correction went out `resend` ago or longer; forgets those no longer live.
  std::vector<std::int64_t> resends_due(Clock::time_point now);
  /// Of `held` (session -> the prefix held now), those whose last correction acknowledged less, or
  /// that had none while something is held.
  [[nodiscard]] std::vector<std::int64_t> acknowledgements_due(const std::map<std::int64_t, std::int64_t>& held) const;
  /// Of `sessions`, those live at `now`. An optimisation moves every session, but only the live
  /// ones have a tracker that takes a correction: the others' entries go on the full map, so a map of
  /// many sessions costs O(live sessions) per loop, not O(sessions).
  [[nodiscard]] std::vector<std::int64_t> live(const std::vector<std::int64_t>& sessions, Clock::time_point now) const;

  /// The map changed; `loop`: a loop closure moved it.
  void changed(bool loop = false) {
    map_changed_ = true;
    loop_waiting_ = loop_waiting_ || loop;
  }
  /// Whether the full map is to go now; `join`: a session was placed by the change.
  [[nodiscard]] bool map_due(Clock::time_point now, bool join) const;
  /// A loop closure moved the map since the last one went.
  [[nodiscard]] bool loop_waiting() const { return loop_waiting_; }
  /// It went.
  void map_sent(Clock::time_point now);

 private:
  struct Sent {
    std::vector<std::uint8_t> entry;
    Clock::time_point at;
    std::int64_t acknowledged = 0;
  };
  [[nodiscard]] bool live_at(Clock::time_point seen, Clock::time_point now) const {
    return now - seen <= periods_.live;
  }
  Periods periods_;
  std::map<std::int64_t, Sent> sent_;
  std::map<std::int64_t, Clock::time_point> live_;  // when last seen
  std::optional<Clock::time_point> map_sent_;
  bool map_changed_ = false, loop_waiting_ = false;
};

}  // namespace cvo::daemon::backendd
