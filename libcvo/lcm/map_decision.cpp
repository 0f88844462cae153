#include "libcvo/lcm/map_decision.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "cvo_lcm/map_correction_t.hpp"
#include "cvo_lcm/map_t.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/core/units.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/map_check.hpp"
#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {
namespace {

using core::BadKind;

// The back end's word on one session, from either channel: its map's order, the entry (none: the
// message has no entry for the session), whether the message is usable (map_check.hpp), and the
// message, for the session's loops.
struct SessionWord {
  std::int64_t epoch = 0, revision = 0;
  const cvo_lcm::map_session_t* entry = nullptr;
  std::string content_error;
  const cvo_lcm::map_t* map = nullptr;                    // a CVO_MAP
  const cvo_lcm::map_correction_t* correction = nullptr;  // or a CVO_MAP_CORRECTION
};

// One of the session's loops to another session's keyframe: by_loop is the map pose of the
// session's keyframe the loop implies, other_pose · measurement⁻¹.
struct PlacementLoop {
  std::int64_t keyframe = -1;
  core::SE3 by_loop;
};

CorrectionDecision refuse(BadKind kind, std::string why) {
  CorrectionDecision d;
  d.refusal = kind;
  d.why = std::move(why);
  return d;
}

CorrectionDecision ignore(std::string why) {
  CorrectionDecision d;
  d.ignored = true;
  d.why = std::move(why);
  return d;
}

std::string rounded(double v) {
  const auto r = std::lround(v * 100);  // two decimals, without iostreams
  return std::to_string(r / 100) + "." + (std::abs(r % 100) < 10 ? "0" : "") + std::to_string(std::abs(r % 100));
}

std::string name(const SessionWord& w) {
  return "revision " + std::to_string(w.revision) + " of epoch " + std::to_string(w.epoch);
}

// "" when going from `from` to `to` moves the map frame within the limits; otherwise by how much.
std::string implausible_jump(const core::SE3& from, const core::SE3& to, const CorrectionLimits& limits) {
  const core::SE3 jump = from.inverse() * to;
  const double metres = jump.translation().norm();
  const double degrees = core::degrees(jump.angle());
  if (metres <= limits.max_jump_m && degrees <= limits.max_jump_deg) return {};
  return "its correction jumps " + rounded(metres) + " m and " + rounded(degrees) +
         " deg from the one applied (at most " + rounded(limits.max_jump_m) + " m and " + rounded(limits.max_jump_deg) +
         " deg)";
}

// The epoch and sender rules: "" when `w` may come from the back end whose word was applied last
// (or from a newer one): not of an older epoch, an epoch not from the future, within its epoch a
// plausible revision from the same sender; otherwise why not, and the kind. Whether it is newer
// than `last` is not asked: another session's word may be of an earlier revision.
std::string untrusted_origin(const SessionWord& w, const AppliedCorrection& last, const CorrectionLimits& limits,
                             const MapContext& context, BadKind& kind) {
  kind = BadKind::kStale;
  if (w.epoch < last.epoch)
    return name(w) + ": of an older back end than the applied word's (epoch " + std::to_string(last.epoch) + ")";
  kind = BadKind::kImplausible;
  const double ahead_s = static_cast<double>(w.epoch - context.now_utime) * 1e-6;
  if (ahead_s > limits.epoch_slack_s)
    return name(w) + ": its epoch lies " + rounded(ahead_s) + " s in the future of this clock (at most " +
           rounded(limits.epoch_slack_s) + " s)";
  if (w.epoch != last.epoch) return {};  // a newer back end: its revisions count afresh
  const double since_s = static_cast<double>(context.now_utime - last.applied_utime) * 1e-6;
  const double leap = limits.revisions_per_s * std::max(1.0, since_s);
  // Each side in double: a forged revision near either end of int64 must not overflow the difference.
  if (static_cast<double>(w.revision) - static_cast<double>(last.revision) > leap) {
    // w.revision > last.revision here, so the difference is exact in uint64 (and defined in any case).
    const auto leaps = static_cast<std::uint64_t>(w.revision) - static_cast<std::uint64_t>(last.revision);
    return name(w) + ": it leaps " + std::to_string(leaps) + " revisions from the applied " +
           std::to_string(last.revision) + " (at most " + std::to_string(std::lround(leap)) + " since then)";
  }
  kind = BadKind::kConflict;
  if (context.sender != last.sender) return name(w) + ": another sender than the applied word of its epoch";
  return {};
}

// The order of words: "" when `w` may follow `last` (newer, and untrusted_origin's rules);
// otherwise why not, and the kind.
std::string out_of_order(const SessionWord& w, const AppliedCorrection& last, const CorrectionLimits& limits,
                         const MapContext& context, BadKind& kind) {
  kind = BadKind::kStale;
  if (w.epoch < last.epoch || (w.epoch == last.epoch && w.revision <= last.revision))
    return name(w) + ", not newer than the applied revision " + std::to_string(last.revision) + " of epoch " +
           std::to_string(last.epoch);
  return untrusted_origin(w, last, limits, context, kind);
}

// The session's loops to keyframes of other sessions that the word carries (poses that do not
// convert are left out: content_error refuses such a word before its loops are looked at).
std::vector<PlacementLoop> placement_loops(const SessionWord& w, std::int64_t session) {
  std::vector<PlacementLoop> out;
  const auto add = [&](std::int64_t keyframe, const cvo_lcm::pose3d_t& measurement, const cvo_lcm::pose3d_t& other) {
    const auto T = from_message(measurement, nullptr);  // T_keyframe^other
    const auto M = from_message(other, nullptr);
    if (T && M) out.push_back({keyframe, *M * T->inverse()});
  };
  if (w.correction != nullptr)
    for (const auto& l : w.correction->loops)
      if (l.other_session != session) add(l.keyframe, l.measurement, l.other_pose);
  if (w.map == nullptr) return out;
  const auto map_pose = [&](std::int64_t s, std::int64_t id) -> const cvo_lcm::pose3d_t* {
    for (const auto& k : w.map->keyframes)
      if (k.session == s && k.id == id) return &k.pose;
    return nullptr;
  };
  for (const auto& loop : w.map->loops) {
    if (loop.from_session == loop.to_session) continue;  // within one session: says nothing of its placement
    const bool from_own = loop.from_session == session;
    if (!from_own && loop.to_session != session) continue;
    const auto* other =
        from_own ? map_pose(loop.to_session, loop.edge.to) : map_pose(loop.from_session, loop.edge.from);
    if (other == nullptr) continue;
    cvo_lcm::pose3d_t measurement = loop.edge.measurement;  // T_from^to, made T_own^other
    if (!from_own)
      if (const auto T = from_message(measurement, nullptr)) measurement = to_message(T->inverse());
    add(from_own ? loop.edge.from : loop.edge.to, measurement, *other);
  }
  return out;
}

// "" when placing the session by `C` agrees with each of its loops whose own keyframe the tracker
// holds; otherwise the first disagreement.
std::string loop_disagreement(const std::vector<PlacementLoop>& loops, const core::SE3& C,
                              const CorrectionLimits& limits, const MapContext& context) {
  for (const auto& loop : loops) {
    const auto own = std::find_if(context.keyframes.begin(), context.keyframes.end(),
                                  [&](const OwnKeyframe& k) { return k.id == loop.keyframe; });
    if (own == context.keyframes.end()) continue;
    if (std::string bad = implausible_jump(C * own->odometry_pose, loop.by_loop, limits); !bad.empty())
      return "its placement disagrees with the loop of keyframe " + std::to_string(loop.keyframe) + ": " + bad;
  }
  return {};
}

// The correction the entry gives (a usable entry: content_error checked it).
AppliedCorrection correction_of(const SessionWord& w, std::int64_t session, const MapContext& context) {
  const cvo_lcm::map_session_t& e = *w.entry;
  AppliedCorrection c{w.epoch, w.revision,   session, e.placed != 0,  core::SE3{},
                      -1,      std::nullopt, -1,      context.sender, context.now_utime};
  if (e.last_match_utime > 0) c.last_match_time = from_utime(e.last_match_utime);
  if (e.covariance_keyframe >= 0) {
    c.keyframe_covariance = matrix6_from_message(e.keyframe_covariance);
    c.covariance_keyframe = e.covariance_keyframe;
  }
  if (c.placed) c.T_map_odom = *from_message(e.correction, nullptr);
  return c;
}

// The word applied last again, from its sender: the same order and the same correction.
bool repeats(const SessionWord& w, std::int64_t session, const AppliedCorrection& last, const MapContext& context) {
  if (w.entry == nullptr || !w.content_error.empty() || last.session != session || w.epoch != last.epoch ||
      w.revision != last.revision || context.sender != last.sender)
    return false;
  const AppliedCorrection c = correction_of(w, session, context);
  return c.placed == last.placed && c.T_map_odom.translation() == last.T_map_odom.translation() &&
         c.T_map_odom.rotation() == last.T_map_odom.rotation() && c.last_match_time == last.last_match_time &&
         c.covariance_keyframe == last.covariance_keyframe && c.keyframe_covariance == last.keyframe_covariance;
}

// The one decision, whichever channel the word came on.
CorrectionDecision decide(const SessionWord& w, std::int64_t session, const AppliedCorrection& last,
                          const CorrectionLimits& limits, const MapContext& context) {
  if (repeats(w, session, last, context)) return ignore(name(w) + ": the correction applied already");
  auto kind = BadKind::kStale;
  if (std::string bad = out_of_order(w, last, limits, context, kind); !bad.empty()) return refuse(kind, std::move(bad));
  if (w.entry == nullptr) return refuse(BadKind::kForeign, name(w) + " has no entry for this session");
  if (!is_finite(w.entry->correction))
    return refuse(BadKind::kNotFinite, name(w) + ": the session's correction is not finite");
  if (!w.content_error.empty()) return refuse(BadKind::kContent, w.content_error);

  const bool was_placed = last.placed && last.session == session;
  if (was_placed && w.entry->placed == 0 && w.epoch == last.epoch)
    return refuse(BadKind::kConflict, name(w) + ": the session, placed in this epoch, is not placed in it");
  CorrectionDecision d;
  d.correction = correction_of(w, session, context);
  if (d.correction.placed) {
    const core::SE3& C = d.correction.T_map_odom;
    const std::string bad = was_placed ? implausible_jump(last.T_map_odom, C, limits)
                                       : loop_disagreement(placement_loops(w, session), C, limits, context);
    if (!bad.empty()) return refuse(BadKind::kImplausible, name(w) + ": " + bad);
  }
  d.apply = true;
  return d;
}

// Another session's CVO_MAP_CORRECTION: ignored (every tracker hears every session's), and what it
// acknowledges taken only when the word may come from the back end the tracker trusts (the header).
CorrectionDecision another_sessions(const SessionWord& w, std::pair<std::int64_t, std::int64_t> acknowledged,
                                    const AppliedCorrection& last, const CorrectionLimits& limits,
                                    const MapContext& context) {
  auto d = ignore("another session's correction");
  if (std::string bad = untrusted_origin(w, last, limits, context, d.refusal); !bad.empty()) {
    d.why = "its acknowledgement of session " + core::session_name(acknowledged.first) + ": " + bad;
    d.acknowledgement_refused = acknowledged.first;
    return d;
  }
  d.acknowledged = acknowledged;
  return d;
}

}  // namespace

CorrectionDecision decide_map_correction(const void* data, int size, std::int64_t session,
                                         const AppliedCorrection& last, const CorrectionLimits& limits,
                                         const MapContext& context) {
  std::string error;
  auto failure = BadKind::kBody;
  const auto message = decode<cvo_lcm::map_t>(data, size, &error, &failure);
  if (!message) return refuse(failure, error);
  const auto entry = std::find_if(message->sessions.begin(), message->sessions.end(),
                                  [&](const cvo_lcm::map_session_t& s) { return s.session == session; });
  const SessionWord word{message->epoch,      message->revision, entry == message->sessions.end() ? nullptr : &*entry,
                         map_error(*message), &*message,         nullptr};
  return decide(word, session, last, limits, context);
}

CorrectionDecision decide_session_correction(const void* data, int size, std::int64_t session,
                                             const AppliedCorrection& last, const CorrectionLimits& limits,
                                             const MapContext& context) {
  std::string error;
  auto failure = BadKind::kBody;
  const auto message = decode<cvo_lcm::map_correction_t>(data, size, &error, &failure);
  if (!message) return refuse(failure, error);
  const std::pair acknowledged{message->session.session, message->acknowledged};
  if (message->session.session != session) {
    const SessionWord word{message->epoch, message->revision, &message->session, {}, nullptr, &*message};
    return another_sessions(word, acknowledged, last, limits, context);
  }
  const SessionWord word{message->epoch, message->revision, &message->session, correction_error(*message),
                         nullptr,        &*message};
  auto d = decide(word, session, last, limits, context);
  if (d.apply || d.ignored) d.acknowledged = acknowledged;  // ignored: the applied word again, from its sender
  return d;
}

}  // namespace cvo::lcm
