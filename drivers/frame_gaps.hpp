#pragma once
// Counting frames that never arrived, from the numbers a sender gives its frames (CVO_RGBD's
// frame_index, an OpenNI frame index, a V4L2 buffer sequence): a jump from n to n + k loses k - 1
// frames. Messages that arrived but could not be read carry no usable number; they are already
// counted as bad input, so they are taken off the next gap instead of being counted twice.
#include <cstdint>
#include <optional>

namespace cvo::drivers {

class FrameGaps {
 public:
  /// A message arrived whose number is unknown (it did not decode).
  void unreadable() { ++unreadable_; }

  /// A frame numbered `index` arrived. A number not above the last one starts a new stream (the
  /// sender restarted, or a log was replayed again): nothing is counted lost.
  void arrived(std::int64_t index) {
    if (last_ && index > *last_) {
      const auto missing = static_cast<std::uint64_t>(index - *last_ - 1);
      lost_ += missing > unreadable_ ? missing - unreadable_ : 0;
    }
    last_ = index;
    unreadable_ = 0;
  }

  [[nodiscard]] std::uint64_t lost() const { return lost_; }

 private:
  std::optional<std::int64_t> last_;
  std::uint64_t unreadable_ = 0;
  std::uint64_t lost_ = 0;
};

}  // namespace cvo::drivers
