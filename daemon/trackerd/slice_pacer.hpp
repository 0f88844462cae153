#pragma once
// cvo-trackerd's keyframe slices (CVO_KEYFRAME_CHUNK) out at a bounded rate: at most kBurst slices,
// then at least kTick before the next burst.
//
// Why: an LCM receiver queues at most 30 messages per subscription unless it asks for more, and
// drops the rest (lcm-logger, lcm-spy and most programs never ask); a keyframe's ~210 slices sent at
// once arrive within a fraction of a millisecond, and such a receiver keeps a seventh of them. 8
// slices a millisecond is ~10 MB/s, a keyframe in ~27 ms (a keyframe comes every few frames), and
// the publisher's poses go out between bursts, not after a keyframe. Slices go out in the order they were added (a
// keyframe's local graph before the next keyframe, as the back end expects). Used by the publisher thread only.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <vector>

#include "cvo_lcm/keyframe_chunk_t.hpp"
#include "libcvo/lcm/chunks.hpp"

namespace cvo::daemon::trackerd {

class SlicePacer {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr std::size_t kBurst = 8;
  static constexpr std::chrono::microseconds kTick{1000};

  /// Slices `range` of `message` (a keyframe's or local graph's encoded message, its trailer zero;
  /// crc: its content CRC) to go out after those added before.
  void add(const lcm::SlicedName& name, std::shared_ptr<const std::vector<std::uint8_t>> message, std::uint32_t crc,
           lcm::SliceRange range);

  using Send = std::function<void(const cvo_lcm::keyframe_chunk_t& slice)>;
  /// The next burst through `send`, when kTick has passed since the last one at `now`; the number sent.
  std::size_t send_due(Clock::time_point now, const Send& send);

  [[nodiscard]] bool idle() const { return jobs_.empty(); }
  [[nodiscard]] std::size_t waiting() const;  // slices not sent yet

 private:
  struct Job {
    lcm::SlicedName name;
    std::shared_ptr<const std::vector<std::uint8_t>> message;
    std::uint32_t crc = 0;
    std::int32_t next = 0, end = 0;  // slices [next, end) still to go
  };
  std::deque<Job> jobs_;
  Clock::time_point last_burst_{};
};

}  // namespace cvo::daemon::trackerd
