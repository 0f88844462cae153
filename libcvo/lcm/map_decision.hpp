#pragma once
// What a tracker makes of the back end's word on its session, without LCM or threads: whether it
// may move the map poses of the tracker's running session, and to what. The word comes two ways,
// and both go through one decision: a CVO_MAP (the whole map: the session's entry among all, its
// loops among all loops, the other keyframes' poses among all keyframes) and a CVO_MAP_CORRECTION
// (that entry alone, with the session's newest loops and the other keyframes' poses: small, O(1)
// per update). A word is trusted only when
//   - it decodes and every pose in it is a rigid transform (decode.hpp, map_check.hpp),
//   - it is newer than the last word applied: a newer epoch (a restarted back end, whose revisions
//     count afresh), or the same epoch and a higher revision (a replayed or reordered one, or one
//     of an older epoch, is stale: kStale); the revision is the map's on both channels,
//   - it has an entry for the session (a map of other trackers only: kForeign),
//   - that entry's correction is finite (kNotFinite),
//   - and, while the session is placed, the new correction moves the map frame by at most
//     max_jump_m and max_jump_deg from the correction applied last (kImplausible): a back end's
//     loop closure corrects drift, it does not teleport the camera.
// Guards that hold even against a peer that may send maps (a faulty, stale or restarted back end,
// or anyone on an open bus; authentication, libcvo/auth, keeps strangers out):
//   - the epoch (its back end's start) lies at most epoch_slack_s in the future of the receiver's
//     clock (kImplausible): a newer epoch always wins over an older one, so one from the future
//     would lock out every real back end until it had been running that long;
//   - within an epoch the revision leaps at most revisions_per_s times the seconds since the word
//     applied last (at least one second's worth) (kImplausible): a back end makes revisions at a
//     bounded rate, and one leap to a huge revision would make every real map stale;
//   - within an epoch, words come from the one sender whose word was applied (kConflict): a back
//     end has one identity (the verified sender id; 0 on an open bus, where all senders are one);
//   - within an epoch a placed session stays placed (kConflict): a back end's sessions join the
//     map for good, so "unplaced, then placed elsewhere" cannot sidestep the jump bound;
//   - a placement (the session not placed by this epoch's words yet) agrees with the session's own
//     loops that the word carries (kImplausible): for a loop edge T_a^b between keyframe a of this
//     session, whose odometry pose O_a the tracker holds, and keyframe b of another session, C · O_a
//     and M_b · (T_a^b)⁻¹ are the same map pose of a up to the jump bound.
// An entry that is not placed is applied (map pose = odometry pose again) while the session has
// not been placed in this epoch.
// Neither applied nor refused (ignored: nothing is wrong with it): the word applied last again, from
// its sender (the back end re-sends corrections, and a CVO_MAP repeats the CVO_MAP_CORRECTION of its
// revision), and another session's CVO_MAP_CORRECTION (every tracker hears every session's; that
// check comes first, before any other).
// What a CVO_MAP_CORRECTION acknowledges (the keyframes the back end holds, which the tracker then
// deletes from its spool) is taken only from a word the tracker trusts (issue 48): of its session,
// one applied or the applied one again; of another session (one it handed over from its spool, or
// left at a camera re-initialisation), one that passes the epoch and sender rules above against the
// word applied last (not of an older epoch, nor from the future, nor a revision leap, nor another
// sender within its epoch). Anything else acknowledges nothing, so that a forger on an open bus
// deletes no keyframe with a word the tracker would not apply.
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include "libcvo/core/bad_kind.hpp"
#include "libcvo/core/se3.hpp"

namespace cvo::lcm {

/// The correction a tracker applies; the state the next decision compares with.
struct AppliedCorrection {
  std::int64_t epoch = -1;      // of the word it came from (the map's: map_t.epoch); -1: none yet
  std::int64_t revision = -1;   // of the word it came from (the map's revision)
  std::int64_t session = 0;     // the session it is for (0: none)
  bool placed = false;          // the map places the session: T_map_odom applies
  core::SE3 T_map_odom;         // identity when not placed
  double last_match_time = -1;  // sensor time of the session's newest verified match (-1: none)
  // The back end's covariance of keyframe covariance_keyframe's map pose, when it gives one.
  std::optional<core::Matrix6d> keyframe_covariance = std::nullopt;
  std::int64_t covariance_keyframe = -1;
  std::int64_t sender = 0;         // the verified sender of the word it came from (0: an open bus)
  std::int64_t applied_utime = 0;  // the receiver's clock when it was applied
};

struct CorrectionLimits {
  double max_jump_m = 1.0;
  double max_jump_deg = 30.0;
  double epoch_slack_s = 10.0;
  double revisions_per_s = 100.0;
};

/// A keyframe of the tracker's running session and its odometry pose (what the loop check needs).
struct OwnKeyframe {
  std::int64_t id = -1;
  core::SE3 odometry_pose;
};

/// What the receiver knows besides the bytes.
struct MapContext {
  std::int64_t now_utime = 0;              // the receiver's wall clock (µs since 1970)
  std::int64_t sender = 0;                 // the word's verified sender (0: an open bus)
  std::span<const OwnKeyframe> keyframes;  // of the running session, any order
};

struct CorrectionDecision {
  bool apply = false;
  bool ignored = false;                             // neither applied nor a fault (see the header)
  AppliedCorrection correction;                     // when apply: the new state
  core::BadKind refusal = core::BadKind::kContent;  // when refused: CVO_STATUS's bad_messages index
  std::string why;                                  // when refused or ignored: for the daemon's note
  // A CVO_MAP_CORRECTION the tracker trusts (see the header): its session and what the back end
  // acknowledged of it (map_correction_t.acknowledged), for the tracker's delivery (any session of
  // its own, the running one or one it handed over).
  std::optional<std::pair<std::int64_t, std::int64_t>> acknowledged;
  // Another session's CVO_MAP_CORRECTION whose acknowledgement the epoch and sender rules refuse:
  // that session (`refusal` and `why` say why), for a tracker that counts it when the session is
  // one of its own. Its own session's refused word is refused whole, and counted as such.
  std::optional<std::int64_t> acknowledgement_refused;
};

/// The decision for the CVO_MAP bytes `data` (as received) for `session`, given the correction
/// applied last (`last`).
CorrectionDecision decide_map_correction(const void* data, int size, std::int64_t session,
                                         const AppliedCorrection& last, const CorrectionLimits& limits,
                                         const MapContext& context);

/// The same decision for the CVO_MAP_CORRECTION bytes `data`: ignored when it is another
/// session's.
CorrectionDecision decide_session_correction(const void* data, int size, std::int64_t session,
                                             const AppliedCorrection& last, const CorrectionLimits& limits,
                                             const MapContext& context);

}  // namespace cvo::lcm
