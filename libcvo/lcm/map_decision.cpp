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

}  // namespace

CorrectionDecision decide_map_correction(const void* data, int size, std::int64_t session,
                                         const AppliedCorrection& last, const CorrectionLimits& limits) {
  std::string error;
  auto failure = BadKind::kBody;
  const auto message = decode<cvo_lcm::map_t>(data, size, &error, &failure);
  if (!message) return refuse(failure, error);
  const std::string revision =
      "revision " + std::to_string(message->revision) + " of epoch " + std::to_string(message->epoch);
  if (message->epoch < last.epoch || (message->epoch == last.epoch && message->revision <= last.revision))
    return refuse(BadKind::kStale, revision + ", not newer than the applied revision " + std::to_string(last.revision) +
                                       " of epoch " + std::to_string(last.epoch));
  const auto entry = std::find_if(message->sessions.begin(), message->sessions.end(),
                                  [&](const cvo_lcm::map_session_t& s) { return s.session == session; });
  if (entry == message->sessions.end()) return refuse(BadKind::kForeign, revision + " has no entry for this session");
  if (!is_finite(entry->correction))
    return refuse(BadKind::kNotFinite, revision + ": the session's correction is not finite");
  if (std::string bad = map_error(*message); !bad.empty()) return refuse(BadKind::kContent, bad);

  CorrectionDecision d;
  d.correction = {message->epoch, message->revision, session, entry->placed != 0, core::SE3{}, -1, std::nullopt, -1};
  if (entry->last_match_utime > 0) d.correction.last_match_time = from_utime(entry->last_match_utime);
  if (entry->covariance_keyframe >= 0) {  // map_error checked it
    d.correction.keyframe_covariance = matrix6_from_message(entry->keyframe_covariance);
    d.correction.covariance_keyframe = entry->covariance_keyframe;
  }
  if (d.correction.placed) {
    d.correction.T_map_odom =
        *from_message(entry->correction, nullptr);  // a rigid transform: map_error checked it above
    if (last.placed && last.session == session)
      if (std::string bad = implausible_jump(last.T_map_odom, d.correction.T_map_odom, limits); !bad.empty())
        return refuse(BadKind::kImplausible, revision + ": " + bad);
  }
  d.apply = true;
  return d;
}

}  // namespace cvo::lcm
