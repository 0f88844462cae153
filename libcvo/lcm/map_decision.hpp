#pragma once
// What a tracker makes of a received CVO_MAP, without LCM or threads: whether it may move the map
// poses of the tracker's running session, and to what. A map is trusted only when
//   - it decodes and every pose in it is a rigid transform (decode.hpp, map_check.hpp),
//   - it is newer than the last map applied: a newer epoch (a restarted back end, whose revisions
//     count afresh), or the same epoch and a higher revision (a replayed or reordered map, or one
//     of an older epoch, is stale: kStale),
//   - it has an entry for the session (a map of other trackers only: kForeign),
//   - that entry's correction is finite (kNotFinite),
//   - and, while the session is placed, the new correction moves the map frame by at most
//     max_jump_m and max_jump_deg from the correction applied last (kImplausible): a back end's
//     loop closure corrects drift, it does not teleport the camera.
// An entry that is not placed is applied too (map pose = odometry pose again).
#include <cstdint>
#include <optional>
#include <string>

#include "libcvo/core/bad_kind.hpp"
#include "libcvo/core/se3.hpp"

namespace cvo::lcm {

/// The correction a tracker applies; the state the next decision compares with.
struct AppliedCorrection {
  std::int64_t epoch = -1;      // of the map it came from (map_t.epoch); -1: none applied yet
  std::int64_t revision = -1;   // of the map it came from
  std::int64_t session = 0;     // the session it is for (0: none)
  bool placed = false;          // the map places the session: T_map_odom applies
  core::SE3 T_map_odom;         // identity when not placed
  double last_match_time = -1;  // sensor time of the session's newest verified match (-1: none)
  // The back end's covariance of keyframe covariance_keyframe's map pose, when it gives one.
  std::optional<core::Matrix6d> keyframe_covariance;
  std::int64_t covariance_keyframe = -1;
};

struct CorrectionLimits {
  double max_jump_m = 1.0;
  double max_jump_deg = 30.0;
};

struct CorrectionDecision {
  bool apply = false;
  AppliedCorrection correction;                     // when apply: the new state
  core::BadKind refusal = core::BadKind::kContent;  // when refused: CVO_STATUS's bad_messages index
  std::string why;                                  // when refused: for the daemon's note
};

/// The decision for the CVO_MAP bytes `data` (as received) for `session`, given the correction
/// applied last (`last`).
CorrectionDecision decide_map_correction(const void* data, int size, std::int64_t session,
                                         const AppliedCorrection& last, const CorrectionLimits& limits);

}  // namespace cvo::lcm
