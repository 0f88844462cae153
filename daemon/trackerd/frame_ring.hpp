#pragma once
// The hand-over from acquisition to tracking: a fixed set of preallocated frame slots. The
// acquisition thread fills a slot and commits it; the tracking thread takes the oldest committed
// one. At most `depth` frames wait; when a new frame arrives with the ring full the oldest
// waiting frame is dropped (counted), so the tracker always works on recent data and latency
// stays bounded. In blocking mode (deterministic replay) the producer waits instead.
//
// The consumer keeps the frame it tracked last until it has tracked the next one: a keyframe
// made at frame n is frame n-1 (the paper's rule), whose images the tracker shares rather than
// copies, so that slot goes back only one frame later (end_read()).
//
// Slots are reused for the life of the ring, so a steady stream of same-sized frames does not
// allocate; no method allocates after construction.
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <vector>

#include "libcvo/core/rgbd_frame.hpp"

namespace cvo::daemon::trackerd {

using Clock = std::chrono::steady_clock;

struct RingSlot {
  core::RgbdFrame frame;
  Clock::time_point received;  // when the driver handed the frame over: latency starts here
  // Which connection of the source the frame came from: 0, then one more each time frames come
  // again after a disconnection. A count rather than a flag on the first frame back, which the
  // ring may drop: the tracker starts a new session whenever it changes (trackerd.hpp).
  std::uint64_t connection = 0;
};

class FrameRing {
 public:
  enum class Overflow { kDropOldest, kBlock };

  FrameRing(std::size_t depth, Overflow overflow);

  // Producer. begin_write() returns a free slot, or nullptr once close() was called.
  RingSlot* begin_write();
  void commit_write();  // the slot from begin_write() becomes the newest frame
  void abort_write();   // the slot was not filled (a bad read): give it back

  // Consumer. begin_read() returns the oldest frame, waiting up to `timeout`; nullptr on timeout
  // or when the ring is closed and empty (see drained()). end_read(): the frame read is kept as
  // the previous one and the previous one before it goes back; skip_read(): the frame read goes
  // straight back (it was not tracked; the previous one stays); release_previous(): the previous
  // frame goes back too (a new session: nothing refers to it any more).
  RingSlot* begin_read(std::chrono::milliseconds timeout);
  void end_read();
  void skip_read();
  void release_previous();

  /// No more frames will come: the consumer gets the ones waiting, then nullptr; a producer
  /// blocked in begin_write() returns nullptr.
  void close();
  [[nodiscard]] bool drained() const;

  [[nodiscard]] std::int64_t dropped() const;
  [[nodiscard]] std::size_t waiting() const;

 private:
  std::size_t depth_;
  Overflow overflow_;
  void give_back(int& slot);  // with the mutex held

  std::vector<RingSlot> slots_;  // depth + 3: the waiting frames, one being written, one read, the previous
  std::vector<int> free_;        // reserved to slots_.size(): push/pop never allocate
  std::vector<int> queue_;       // circular FIFO of waiting slot indices
  std::size_t head_ = 0, count_ = 0;
  int writing_ = -1, reading_ = -1, previous_ = -1;
  bool closed_ = false;
  std::int64_t dropped_ = 0;
  mutable std::mutex mutex_;
  std::condition_variable frame_ready_, slot_free_;
};

}  // namespace cvo::daemon::trackerd
