#pragma once
// The records cvo-receive hands to cvo-backend, bounded: the back end's memory must not grow with
// a tracker (or an attacker) that outruns it. Live input that finds the queue full is queued by
// the caller as a reference to where it lies in the store (a few bytes; read back in its turn),
// so a back end slower than its trackers loses nothing; a log can wait for room instead
// (wait_for_room), since nothing is lost by reading it slower. What a restart replays from the
// store is on disk and in memory already: it enters unbounded.
// One producer and one consumer; either may wait.
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <optional>
#include <utility>

namespace cvo::daemon::backendd {

template <class T>
class WorkQueue {
 public:
  explicit WorkQueue(std::size_t capacity) : capacity_(capacity) {}

  /// Room for one more item now. With one producer it stays so until that producer pushes: the
  /// producer checks, does what must come first (the store), then pushes.
  [[nodiscard]] bool has_room() const {
    const std::lock_guard lock(mutex_);
    return items_.size() < capacity_;
  }

  /// Waits for room, checking `give_up()` every `poll`; false when it gave up.
  template <class GiveUp>
  bool wait_for_room(GiveUp give_up, std::chrono::milliseconds poll = std::chrono::milliseconds(100)) {
    std::unique_lock lock(mutex_);
    while (items_.size() >= capacity_) {
      if (give_up()) return false;
      room_.wait_for(lock, poll);
    }
    return true;
  }

  /// Appends; the bound is the producer's to keep (has_room, wait_for_room), and a replay from the
  /// store is let past it (see the header).
  void push(T item) {
    {
      const std::lock_guard lock(mutex_);
      items_.push_back(std::move(item));
    }
    ready_.notify_one();
  }

  /// The oldest item, waiting up to `wait` for one; nullopt when none came.
  std::optional<T> pop(std::chrono::milliseconds wait) {
    std::optional<T> item;
    {
      std::unique_lock lock(mutex_);
      if (!ready_.wait_for(lock, wait, [&] { return !items_.empty(); })) return std::nullopt;
      item = std::move(items_.front());
      items_.pop_front();
    }
    room_.notify_one();
    return item;
  }

  [[nodiscard]] std::size_t size() const {
    const std::lock_guard lock(mutex_);
    return items_.size();
  }
  [[nodiscard]] std::size_t capacity() const { return capacity_; }

 private:
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable ready_, room_;
  std::deque<T> items_;
};

}  // namespace cvo::daemon::backendd
