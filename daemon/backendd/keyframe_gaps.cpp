#include "daemon/backendd/keyframe_gaps.hpp"

#include <algorithm>
#include <iterator>
#include <utility>

namespace cvo::daemon::backendd {

KeyframeGaps::KeyframeGaps(GapPolicy policy) : policy_(policy) {}

KeyframeGaps::Session& KeyframeGaps::session(std::int64_t id, Clock::time_point now) {
  auto it = sessions_.find(id);
  if (it == sessions_.end()) {
    if (!sessions_.empty() && sessions_.size() >= policy_.max_sessions) {  // forget the least recently seen
      const auto oldest = std::min_element(sessions_.begin(), sessions_.end(), [](const auto& a, const auto& b) {
        return a.second.last_seen < b.second.last_seen;
      });
      for (const auto& [missing_id, m] : oldest->second.missing)
        give_up(oldest->first, missing_id, missing_id, GivenUp::Reason::kBounds);
      missing_ -= oldest->second.missing.size();
      sessions_.erase(oldest);
    }
    it = sessions_.try_emplace(id).first;
  }
  it->second.last_seen = now;
  return it->second;
}

void KeyframeGaps::seen(Seen what, std::int64_t session_id, std::int64_t id, Clock::time_point now) {
  if (id < 0) return;
  Session& s = session(session_id, now);
  switch (what) {
    case Seen::kKeyframe: {
      const bool late = id < s.keyframes_until;
      expect(session_id, s, id, id, now);
      if (late)
        came(s, id, /*keyframe=*/true);
      else
        s.keyframes_until = id + 1;
      return;
    }
    case Seen::kLocalGraph: {
      const bool late = id < s.graphs_until;
      expect(session_id, s, id + 1, id, now);
      if (late)
        came(s, id, /*keyframe=*/false);
      else
        s.graphs_until = id + 1;
      return;
    }
    case Seen::kGraphWithoutKeyframe: {
      // Below the keyframe mark and not waited for: that keyframe was given up, and its graph,
      // which cannot be let in without it, is lost with it (counted once).
      const bool given_up = id < s.keyframes_until && !s.missing.contains(id);
      expect(session_id, s, id + 1, given_up ? id : id + 1, now);
      if (given_up) s.graphs_until = std::max(s.graphs_until, id + 1);
      if (const auto it = s.missing.find(id); it != s.missing.end()) it->second.graph = true;  // refused: needed again
      return;
    }
    case Seen::kPose: expect(session_id, s, id + 1, id, now); return;
    case Seen::kGraphPart: expect(session_id, s, id + 1, id + 1, now); return;
  }
}

void KeyframeGaps::heard(std::int64_t session_id, Clock::time_point now) {
  if (const auto it = sessions_.find(session_id); it != sessions_.end()) it->second.last_seen = now;
}

void KeyframeGaps::progressed(std::int64_t session_id, std::int64_t id, Clock::time_point now) {
  const auto s = sessions_.find(session_id);
  if (s == sessions_.end()) return;
  s->second.last_seen = now;
  const auto m = s->second.missing.find(id);
  if (m == s->second.missing.end()) return;
  m->second.unanswered = 0;
  m->second.answered = now;
  m->second.next = now + policy_.after_part;
}

// Keyframes [s.keyframes_until, keyframes_until) and local graphs [s.graphs_until, graphs_until)
// should have come: each not yet waited for is, from now on.
void KeyframeGaps::expect(std::int64_t session_id, Session& s, std::int64_t keyframes_until, std::int64_t graphs_until,
                          Clock::time_point now) {
  const bool new_keyframes = keyframes_until > s.keyframes_until, new_graphs = graphs_until > s.graphs_until;
  if (!new_keyframes && !new_graphs) return;
  std::int64_t lo =
      std::min(new_keyframes ? s.keyframes_until : graphs_until, new_graphs ? s.graphs_until : keyframes_until);
  const std::int64_t hi = std::max(new_keyframes ? keyframes_until : lo, new_graphs ? graphs_until : lo);
  if (hi - lo > policy_.max_gap) {  // older than any tracker keeps (or a forged id): not asked for
    const std::int64_t cut = hi - policy_.max_gap;
    const auto first = s.missing.lower_bound(lo), last = s.missing.lower_bound(cut);
    missing_ -= static_cast<std::size_t>(std::distance(first, last));
    s.missing.erase(first, last);  // counted in the range given up
    give_up(session_id, lo, cut - 1, GivenUp::Reason::kBounds);
    lo = cut;
  }
  for (std::int64_t id = lo; id < hi; ++id) {
    const bool keyframe = id >= s.keyframes_until && id < keyframes_until;
    const bool graph = id >= s.graphs_until && id < graphs_until;
    if (!keyframe && !graph) continue;
    auto [it, inserted] = s.missing.try_emplace(id);
    if (inserted) {
      if (missing_ >= policy_.max_missing) {
        s.missing.erase(it);
        give_up(session_id, id, id, GivenUp::Reason::kBounds);
        continue;
      }
      ++missing_;
      it->second.next = now + policy_.first_wait;
    }
    it->second.keyframe = it->second.keyframe || keyframe;
    it->second.graph = it->second.graph || graph;
  }
  s.keyframes_until = std::max(s.keyframes_until, keyframes_until);
  s.graphs_until = std::max(s.graphs_until, graphs_until);
}

// A keyframe or local graph that was waited for came; once all of its keyframe id is there, it is
// recovered when it had been asked for (else it was only late).
void KeyframeGaps::came(Session& s, std::int64_t id, bool keyframe) {
  const auto it = s.missing.find(id);
  if (it == s.missing.end()) return;
  (keyframe ? it->second.keyframe : it->second.graph) = false;
  if (it->second.keyframe || it->second.graph) return;
  if (it->second.requests > 0) ++recovered_;
  s.missing.erase(it);
  --missing_;
}

void KeyframeGaps::give_up(std::int64_t session, std::int64_t first, std::int64_t last, GivenUp::Reason reason) {
  lost_ += last - first + 1;
  if (!given_up_.empty() && given_up_.back().session == session && given_up_.back().last + 1 == first &&
      given_up_.back().reason == reason)
    given_up_.back().last = last;
  else
    given_up_.push_back({session, first, last, reason});
}

// retry_wait doubled after each request; past `requests`, at most max_retry_wait.
KeyframeGaps::Clock::duration KeyframeGaps::wait_after(int requests) const {
  const Clock::duration doubled = policy_.retry_wait * (std::int64_t{1} << std::clamp(requests - 1, 0, 20));
  return requests >= policy_.requests ? std::min<Clock::duration>(doubled, policy_.max_retry_wait) : doubled;
}

// Why asking for `m` is over (see the header), or nothing while it goes on.
std::optional<KeyframeGaps::GivenUp::Reason> KeyframeGaps::done_asking(const Session& s, const Missing& m,
                                                                       Clock::time_point now) const {
  using Reason = GivenUp::Reason;
  if (policy_.requests <= 0) return Reason::kNoAsking;
  if (m.requests < policy_.requests) return std::nullopt;
  if (now - s.last_seen > policy_.alive_window) return Reason::kSilent;
  if (now - m.answered >= policy_.give_up_after) return Reason::kUnanswered;
  return std::nullopt;
}

KeyframeGaps::Round KeyframeGaps::due(Clock::time_point now) {
  Round round;
  std::size_t budget = now >= next_round_ ? policy_.ids_per_round : 0;
  for (auto& [session_id, s] : sessions_) {
    Request request{session_id, {}, {}};
    for (auto it = s.missing.begin(); it != s.missing.end();) {
      Missing& m = it->second;
      if (m.next > now) {
        ++it;
      } else if (const auto reason = done_asking(s, m, now)) {
        give_up(session_id, it->first, it->first, *reason);
        it = s.missing.erase(it);
        --missing_;
      } else {
        if (budget > 0) {  // else due in a later round, not counted as asked
          --budget;
          if (m.requests++ == 0) ++requested_, m.answered = now;
          m.next = now + wait_after(++m.unanswered);
          request.ids.push_back(it->first);
          if (!m.keyframe) request.graphs_only.push_back(it->first);
        }
        ++it;
      }
    }
    if (!request.ids.empty()) round.requests.push_back(std::move(request));
  }
  if (!round.requests.empty()) next_round_ = now + policy_.round_interval;
  round.given_up = std::exchange(given_up_, {});
  return round;
}

std::vector<KeyframeGaps::GivenUp> KeyframeGaps::give_up_all() {
  for (auto& [session_id, s] : sessions_) {
    for (const auto& [id, m] : s.missing) give_up(session_id, id, id, GivenUp::Reason::kStopped);
    s.missing.clear();
  }
  missing_ = 0;
  return std::exchange(given_up_, {});
}

}  // namespace cvo::daemon::backendd
