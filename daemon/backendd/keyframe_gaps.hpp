#pragma once
// cvo-backendd's bookkeeping of keyframes lost in transport (LCM over UDP drops a large message
// whole when a socket buffer overflows). Per tracker session it knows which keyframes and local
// graphs should have come and have not, says when to ask the tracker for them again
// (CVO_KEYFRAME_REQUEST, with back-off) and when to give up. No LCM here: cvo-receive tells it what
// it saw and sends the requests it hands out.
//
// How long it asks (issue 28): `requests` times in any case; then on, the wait capped at
// max_retry_wait, for as long as the session's tracker is heard (a pose, keyframe, local graph or
// CVO_STATUS of the session within alive_window: a live tracker may still answer once its link
// clears), up to give_up_after with nothing of it coming (a tracker that no longer holds the
// keyframe never answers). What it gives up on says why (GivenUp::Reason).
//
// A keyframe sent in slices (CVO_KEYFRAME_CHUNK) comes in part: each slice of it is progress
// (progressed()), which restarts its back-off, and puts its next request after_part after the
// newest slice (once the burst of an answer is over), so that a lossy link costs a few quick
// rounds, each asking for what the last one lost.
//
// What a message says should have come, in its session (the tracker publishes keyframe k's local
// graph just before keyframe k+1, and names the keyframe of every pose):
//   keyframe k                          keyframes below k, local graphs below k
//   local graph k                       keyframes up to k, local graphs below k
//   local graph k refused because its keyframe is unknown (the door): keyframe and local graph k too
//   a pose tracked against keyframe k   keyframes up to k, local graphs below k
//   a slice of local graph k            keyframes up to k, local graphs up to k
// The tracker answers a request for keyframe k with the keyframe, then its local graph, so one
// request per keyframe id covers both. Counted (CVO_STATUS): keyframes asked for (once each however
// often asked), recovered (all that was missing of it came after a request), lost (given up).
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

namespace cvo::daemon::backendd {

struct GapPolicy {
  // From noticing to the first request: a message that is only late still comes (reordered, or a
  // keyframe whose paced slices a pose naming it overtook, on a loaded tracker).
  std::chrono::milliseconds first_wait{500};
  // From the newest part of a keyframe that came in part to the next request: the rest of an
  // answer's burst is waited out.
  std::chrono::milliseconds after_part{100};
  // From the first request to the second, doubled after each; `requests` requests, then given up
  // (0: never ask, give up at once: a recording cannot answer).
  std::chrono::milliseconds retry_wait{500};
  int requests = 4;
  // After those, while the tracker is heard within alive_window: again every max_retry_wait at
  // most, until give_up_after from the first request.
  std::chrono::milliseconds alive_window{5000};  // five CVO_STATUS periods: a lossy link loses a few
  std::chrono::milliseconds max_retry_wait{4000};
  std::chrono::milliseconds give_up_after{60000};
  // Requests go out at most once per round_interval, for at most ids_per_round keyframes (each
  // answer is a burst of large messages that must not overflow the socket again); at most
  // keyframe_request_t::MAX_IDS.
  std::chrono::milliseconds round_interval{100};
  std::size_t ids_per_round = 4;
  // Bounds against a forged id or session: of one gap only the newest max_gap ids are asked for
  // (a tracker keeps fewer), the older given up at once; at most max_missing keyframes are waited
  // for at a time and max_sessions sessions remembered (the least recently seen is forgotten).
  std::int64_t max_gap = 256;
  std::size_t max_missing = 1024;
  std::size_t max_sessions = 1024;
};

class KeyframeGaps {
 public:
  using Clock = std::chrono::steady_clock;

  explicit KeyframeGaps(GapPolicy policy = {});

  enum class Seen {
    kKeyframe,              // let in (received, or replayed from the store)
    kLocalGraph,            // let in
    kGraphWithoutKeyframe,  // a local graph refused: its keyframe is unknown
    kPose,                  // CVO_POSE: a frame tracked against keyframe `id` (or a slice of that keyframe)
    kGraphPart,             // a slice of keyframe `id`'s local graph: it and its keyframe should come
  };
  void seen(Seen what, std::int64_t session, std::int64_t id, Clock::time_point now);
  /// The session's tracker was heard otherwise (its CVO_STATUS): it is alive, and may still answer.
  /// A session not known here is not remembered for it.
  void heard(std::int64_t session, Clock::time_point now);
  /// A part of keyframe `id` (or of its local graph) came: its tracker is alive and answering.
  void progressed(std::int64_t session, std::int64_t id, Clock::time_point now);

  struct Request {
    std::int64_t session = 0;
    std::vector<std::int64_t> ids;          // ascending
    std::vector<std::int64_t> graphs_only;  // of those, the ones whose keyframe came: only the local graph is missing
  };
  struct GivenUp {  // keyframes first..last of a session, lost
    enum class Reason {
      kSilent,      // asked `requests` times, and the tracker is no longer heard
      kUnanswered,  // asked for give_up_after, nothing of it coming, while the tracker was heard
      kNoAsking,    // requests == 0: nothing to ask (a recording)
      kBounds,      // beyond max_gap, max_missing or max_sessions
      kStopped,     // the back end stopped
    };
    std::int64_t session = 0, first = 0, last = 0;
    Reason reason = Reason::kSilent;
  };
  struct Round {
    std::vector<Request> requests;  // to send now
    std::vector<GivenUp> given_up;  // since the last round
  };
  /// What to do now: the requests due (within the round's budget; the rest stay due) and what was
  /// given up, and why (see the header).
  Round due(Clock::time_point now);
  /// At a stop: everything still waited for is given up (and counted lost).
  std::vector<GivenUp> give_up_all();

  [[nodiscard]] std::int64_t requested() const { return requested_; }
  [[nodiscard]] std::int64_t recovered() const { return recovered_; }
  [[nodiscard]] std::int64_t lost() const { return lost_; }
  [[nodiscard]] std::size_t missing() const { return missing_; }  // keyframes waited for now

 private:
  struct Missing {
    bool keyframe = false, graph = false;  // what has not come
    int requests = 0;                      // sent so far
    int unanswered = 0;                    // sent since a part of it last came: the back-off
    Clock::time_point next;                // the next request, or giving up once all were sent
    Clock::time_point answered;            // when it was first asked for, or a part of it came since
  };
  struct Session {
    std::int64_t keyframes_until = 0;  // every keyframe id below came, or is in `missing`, or was given up
    std::int64_t graphs_until = 0;     // the same for local graphs
    std::map<std::int64_t, Missing> missing;
    Clock::time_point last_seen;
  };

  Session& session(std::int64_t id, Clock::time_point now);
  void expect(std::int64_t session, Session& s, std::int64_t keyframes_until, std::int64_t graphs_until,
              Clock::time_point now);
  void came(Session& s, std::int64_t id, bool keyframe);
  void give_up(std::int64_t session, std::int64_t first, std::int64_t last, GivenUp::Reason reason);
  [[nodiscard]] Clock::duration wait_after(int requests) const;
  [[nodiscard]] std::optional<GivenUp::Reason> done_asking(const Session& s, const Missing& m,
                                                           Clock::time_point now) const;

  GapPolicy policy_;
  std::map<std::int64_t, Session> sessions_;
  std::vector<GivenUp> given_up_;  // since the last round
  Clock::time_point next_round_{};
  std::size_t missing_ = 0;
  std::int64_t requested_ = 0, recovered_ = 0, lost_ = 0;
};

}  // namespace cvo::daemon::backendd
