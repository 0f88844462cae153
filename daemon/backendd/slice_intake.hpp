#pragma once
// cvo-receive's slices (CVO_KEYFRAME_CHUNK) before they are put together: whose they may be.
//
// On an open bus anyone may send a slice of any name. A slice of a session whose tracker is heard
// (a CVO_POSE or CVO_STATUS of it within alive_window) is assembled with the live sessions' and
// is progress in the gaps (keyframe_gaps.hpp); when its id is at most the newest keyframe the
// session's poses named, it also tells them that its keyframe exists, so that what does not come
// is asked for. A name past that may be a forger's guess at keyframes to come: the pose naming the
// genuine one follows its slices, and tells the gaps then, so a forged name is never asked for nor
// counted lost. A slice of any other session (a forger's, or a tracker's hand-over of a killed session's
// spool, or a first keyframe that overtook its tracker's first pose) is assembled apart, among
// `strangers`, a small room of its own, and asks for nothing: a flood of them evicts its own kind,
// never a live session's keyframe, and never makes a keyframe request or a keyframe "lost". Those
// strangers' slices that are dropped unassembled could not belong to a live session: counted as
// refused (BAD_UNKNOWN_KEYFRAME) by the caller (strangers_dropped()). Among strangers the message
// holding the fewest slices goes first (chunks.hpp), so a hand-over's keyframe survives a flood as
// long as its next slice comes before strangers.max_messages forged first slices do (a tracker
// sends 8 a millisecond: a flood of over 100 000 slices a second).
//
// Memory: live.max_bytes + strangers.max_bytes for the slices (chunks.hpp: each charged its data
// and ChunkAssembly::kSliceOverhead, plus a constant per message held), and max_sessions
// heard sessions (a few dozen bytes each).
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include "daemon/backendd/keyframe_gaps.hpp"
#include "libcvo/lcm/chunks.hpp"

namespace cvo::daemon::backendd {

class SliceIntake {
 public:
  using Clock = std::chrono::steady_clock;
  struct Limits {
    lcm::ChunkAssembly::Limits live{};  // the live sessions' messages in part
    // Strangers: a hand-over's keyframes come one after another, so a few at a time will do.
    lcm::ChunkAssembly::Limits strangers{.max_messages = 16, .max_bytes = std::size_t{32} << 20, .max_per_name = 4};
    std::chrono::milliseconds alive_window{5000};  // as GapPolicy's: five CVO_STATUS periods
    std::size_t max_sessions = 1024;               // heard sessions remembered (the least recently heard goes)
  };
  explicit SliceIntake(Limits limits);
  SliceIntake() : SliceIntake(Limits{}) {}

  /// The session's tracker was heard: its CVO_POSE (naming `keyframe`) or CVO_STATUS (nullopt).
  void heard(std::int64_t session, Clock::time_point now, std::optional<std::int64_t> keyframe);
  [[nodiscard]] bool live(std::int64_t session, Clock::time_point now) const;

  /// Takes one decoded slice (see the header); a live session's is progress in `gaps`.
  lcm::ChunkAssembly::Added add(const cvo_lcm::keyframe_chunk_t& chunk, KeyframeGaps& gaps, Clock::time_point now);
  /// What is missing of a message in part (the live room's, else the strangers').
  [[nodiscard]] std::optional<std::vector<lcm::SliceRange>> missing(const lcm::SlicedName& name,
                                                                    std::size_t max_ranges) const;
  /// One message of `name` was let in: the others of that name compete in vain.
  void forget(const lcm::SlicedName& name);

  /// Strangers' slices dropped unassembled since the last call: refused, they could not belong to a
  /// live session.
  [[nodiscard]] std::int64_t strangers_dropped();
  [[nodiscard]] std::size_t bytes() const { return live_.bytes() + strangers_.bytes(); }
  [[nodiscard]] std::size_t held() const { return live_.held() + strangers_.held(); }

 private:
  Limits limits_;
  struct Heard {
    Clock::time_point when;
    std::int64_t newest_keyframe = -1;  // named by its poses; -1: none yet
  };
  std::map<std::int64_t, Heard> heard_;
  lcm::ChunkAssembly live_, strangers_;
  std::int64_t strangers_counted_ = 0;  // of strangers_.dropped_slices(), handed out already
};

}  // namespace cvo::daemon::backendd
