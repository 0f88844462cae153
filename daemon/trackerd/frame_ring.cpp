#include "daemon/trackerd/frame_ring.hpp"

#include <stdexcept>
#include <utility>

namespace cvo::daemon::trackerd {

FrameRing::FrameRing(std::size_t depth, Overflow overflow)
    : depth_(depth), overflow_(overflow), slots_(depth + 3), queue_(depth) {
  if (depth == 0) throw std::invalid_argument("FrameRing: depth must be at least 1");
  free_.reserve(slots_.size());
  for (int i = static_cast<int>(slots_.size()) - 1; i >= 0; --i) free_.push_back(i);
}

RingSlot* FrameRing::begin_write() {
  std::unique_lock lock(mutex_);
  if (overflow_ == Overflow::kBlock) slot_free_.wait(lock, [&] { return closed_ || count_ < depth_; });
  if (closed_) return nullptr;
  if (count_ == depth_) {  // drop the oldest waiting frame and reuse its slot
    free_.push_back(queue_[head_]);
    head_ = (head_ + 1) % depth_;
    --count_;
    ++dropped_;
  }
  writing_ = free_.back();
  free_.pop_back();
  return &slots_[static_cast<std::size_t>(writing_)];
}

void FrameRing::commit_write() {
  {
    const std::lock_guard lock(mutex_);
    if (writing_ < 0) return;
    queue_[(head_ + count_) % depth_] = writing_;
    ++count_;
    writing_ = -1;
  }
  frame_ready_.notify_one();
}

void FrameRing::abort_write() {
  const std::lock_guard lock(mutex_);
  if (writing_ < 0) return;
  free_.push_back(writing_);
  writing_ = -1;
}

RingSlot* FrameRing::begin_read(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!frame_ready_.wait_for(lock, timeout, [&] { return count_ > 0 || closed_; }) || count_ == 0) return nullptr;
  reading_ = queue_[head_];
  head_ = (head_ + 1) % depth_;
  --count_;
  slot_free_.notify_one();  // a producer blocked on a full queue may go on
  return &slots_[static_cast<std::size_t>(reading_)];
}

void FrameRing::give_back(int& slot) {
  if (slot < 0) return;
  free_.push_back(slot);
  slot = -1;
}

void FrameRing::end_read() {
  {
    const std::lock_guard lock(mutex_);
    if (reading_ < 0) return;
    give_back(previous_);
    previous_ = std::exchange(reading_, -1);
  }
  slot_free_.notify_one();
}

void FrameRing::skip_read() {
  {
    const std::lock_guard lock(mutex_);
    give_back(reading_);
  }
  slot_free_.notify_one();
}

void FrameRing::release_previous() {
  {
    const std::lock_guard lock(mutex_);
    give_back(previous_);
  }
  slot_free_.notify_one();
}

void FrameRing::close() {
  {
    const std::lock_guard lock(mutex_);
    closed_ = true;
  }
  frame_ready_.notify_all();
  slot_free_.notify_all();
}

bool FrameRing::drained() const {
  const std::lock_guard lock(mutex_);
  return closed_ && count_ == 0;
}

std::int64_t FrameRing::dropped() const {
  const std::lock_guard lock(mutex_);
  return dropped_;
}

std::size_t FrameRing::waiting() const {
  const std::lock_guard lock(mutex_);
  return count_;
}

}  // namespace cvo::daemon::trackerd
