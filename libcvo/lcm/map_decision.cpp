#include "libcvo/lcm/map_decision.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "cvo_lcm/map_t.hpp"
#include "libcvo/core/units.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/map_check.hpp"
#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {
namespace {

using core::BadKind;

CorrectionDecision refuse(BadKind kind, std::string why) {
  CorrectionDecision d;
  d.refusal = kind;
  d.why = std::move(why);
  return d;
}

std::string rounded(double v) {
  const auto r = std::lround(v * 100);  // two decimals, without iostreams
  return std::to_string(r / 100) + "." + (std::abs(r % 100) < 10 ? "0" : "") + std::to_string(std::abs(r % 100));
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

// The order of maps: "" when `m` may follow `last` (newer, from a present epoch, a plausible
// revision, the same sender within an epoch); otherwise why not, and the kind.
std::string out_of_order(const cvo_lcm::map_t& m, const AppliedCorrection& last, const CorrectionLimits& limits,
                         const MapContext& context, BadKind& kind) {
  const std::string revision = "revision " + std::to_string(m.revision) + " of epoch " + std::to_string(m.epoch);
  kind = BadKind::kStale;
  if (m.epoch < last.epoch || (m.epoch == last.epoch && m.revision <= last.revision))
    return revision + ", not newer than the applied revision " + std::to_string(last.revision) + " of epoch " +
           std::to_string(last.epoch);
  kind = BadKind::kImplausible;
  const double ahead_s = static_cast<double>(m.epoch - context.now_utime) * 1e-6;
  if (ahead_s > limits.epoch_slack_s)
    return revision + ": its epoch lies " + rounded(ahead_s) + " s in the future of this clock (at most " +
           rounded(limits.epoch_slack_s) + " s)";
  if (m.epoch != last.epoch) return {};  // a newer back end: its revisions count afresh
  const double since_s = static_cast<double>(context.now_utime - last.applied_utime) * 1e-6;
  const double leap = limits.revisions_per_s * std::max(1.0, since_s);
  if (static_cast<double>(m.revision - last.revision) > leap)
    return revision + ": it leaps " + std::to_string(m.revision - last.revision) + " revisions from the applied " +
           std::to_string(last.revision) + " (at most " + std::to_string(std::lround(leap)) + " since then)";
  kind = BadKind::kConflict;
  if (context.sender != last.sender) return revision + ": another sender than the applied map of its epoch";
  return {};
}

// "" when placing the session by `C` agrees with each of its loops in `m` whose own keyframe the
// tracker holds; otherwise the first disagreement.
std::string loop_disagreement(const cvo_lcm::map_t& m, std::int64_t session, const core::SE3& C,
                              const CorrectionLimits& limits, const MapContext& context) {
  const auto own = [&](std::int64_t id) -> const OwnKeyframe* {
    for (const auto& k : context.keyframes)
      if (k.id == id) return &k;
    return nullptr;
  };
  const auto map_pose = [&](std::int64_t s, std::int64_t id) -> std::optional<core::SE3> {
    for (const auto& k : m.keyframes)
      if (k.session == s && k.id == id) return from_message(k.pose, nullptr);
    return std::nullopt;
  };
  for (const auto& loop : m.loops) {
    if (loop.from_session == loop.to_session) continue;  // within one session: says nothing of its placement
    const bool from_own = loop.from_session == session;
    if (!from_own && loop.to_session != session) continue;
    const OwnKeyframe* a = own(from_own ? loop.edge.from : loop.edge.to);
    const auto b = from_own ? map_pose(loop.to_session, loop.edge.to) : map_pose(loop.from_session, loop.edge.from);
    const auto T = from_message(loop.edge.measurement, nullptr);
    if (a == nullptr || !b || !T) continue;
    const core::SE3 by_loop = from_own ? *b * T->inverse() : *b * *T;
    if (std::string bad = implausible_jump(C * a->odometry_pose, by_loop, limits); !bad.empty())
      return "its placement disagrees with the loop of keyframe " + std::to_string(a->id) + ": " + bad;
  }
  return {};
}

}  // namespace

CorrectionDecision decide_map_correction(const void* data, int size, std::int64_t session,
                                         const AppliedCorrection& last, const CorrectionLimits& limits,
                                         const MapContext& context) {
  std::string error;
  auto failure = BadKind::kBody;
  const auto message = decode<cvo_lcm::map_t>(data, size, &error, &failure);
  if (!message) return refuse(failure, error);
  const std::string revision =
      "revision " + std::to_string(message->revision) + " of epoch " + std::to_string(message->epoch);
  auto kind = BadKind::kStale;
  if (std::string bad = out_of_order(*message, last, limits, context, kind); !bad.empty())
    return refuse(kind, std::move(bad));
  const auto entry = std::find_if(message->sessions.begin(), message->sessions.end(),
                                  [&](const cvo_lcm::map_session_t& s) { return s.session == session; });
  if (entry == message->sessions.end()) return refuse(BadKind::kForeign, revision + " has no entry for this session");
  if (!is_finite(entry->correction))
    return refuse(BadKind::kNotFinite, revision + ": the session's correction is not finite");
  if (std::string bad = map_error(*message); !bad.empty()) return refuse(BadKind::kContent, bad);

  const bool was_placed = last.placed && last.session == session;
  if (was_placed && entry->placed == 0 && message->epoch == last.epoch)
    return refuse(BadKind::kConflict, revision + ": the session, placed in this epoch, is not placed in it");
  CorrectionDecision d;
  d.correction = {message->epoch, message->revision, session, entry->placed != 0, core::SE3{}, -1, std::nullopt, -1,
                  context.sender, context.now_utime};
  if (entry->last_match_utime > 0) d.correction.last_match_time = from_utime(entry->last_match_utime);
  if (entry->covariance_keyframe >= 0) {  // map_error checked it
    d.correction.keyframe_covariance = matrix6_from_message(entry->keyframe_covariance);
    d.correction.covariance_keyframe = entry->covariance_keyframe;
  }
  if (d.correction.placed) {
    const core::SE3 C = *from_message(entry->correction, nullptr);  // a rigid transform: map_error checked it
    d.correction.T_map_odom = C;
    const std::string bad = was_placed ? implausible_jump(last.T_map_odom, C, limits)
                                       : loop_disagreement(*message, session, C, limits, context);
    if (!bad.empty()) return refuse(BadKind::kImplausible, revision + ": " + bad);
  }
  d.apply = true;
  return d;
}

}  // namespace cvo::lcm
