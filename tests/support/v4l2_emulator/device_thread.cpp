// The emulated camera's device thread: makes each node's frames at their times (camera.hpp).
#include <linux/videodev2.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>

#include "tests/support/v4l2_emulator/camera.hpp"

namespace cvo::drivers::v4l2_emulator {
namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

std::chrono::steady_clock::time_point at(double seconds) {
  return std::chrono::steady_clock::time_point(
      std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds)));
}

}  // namespace

double Camera::due_time(const Node& n) const { return start_ + double(n.next_frame) / n.rate; }

Camera::Node* Camera::due_node() {
  Node* due = nullptr;
  for (auto& n : nodes_)
    if (n.streaming && (due == nullptr || due_time(n) < due_time(*due))) due = &n;
  return due;
}

void Camera::run() {
  std::unique_lock lock(mutex_);
  while (!shutdown_) {
    Node* n = gone_ ? nullptr : due_node();
    if (n == nullptr) {
      changed_.wait(lock);
      continue;
    }
    if (now() < due_time(*n)) {
      changed_.wait_until(lock, at(due_time(*n)));  // woken early by any change: decide again
      continue;
    }
    if (config_.lossless && n->queued.empty()) {
      changed_.wait(lock);
      continue;
    }
    produce(*n, lock);
  }
}

void Camera::produce(Node& n, std::unique_lock<std::mutex>& lock) {
  const double played = double(n.next_frame) * config_.play_fps / n.rate;  // recording entries since the start
  const std::size_t raw = scene_base_ + static_cast<std::size_t>(std::floor(played + 1e-9));
  const bool colour = &n == &nodes_[0];
  if (raw >= scene_.size() && config_.at_end == AtEnd::kUnplug) return unplug(lock, true);
  // After N colour frames, when the next one is due: the depth frame of the Nth was made too.
  if (colour && config_.unplug_after != 0 && colour_frames_ == config_.unplug_after && !unplugged_once_)
    return unplug(lock, false);
  const std::size_t entry = raw % scene_.size();
  std::uint32_t flags = 0;
  if (!n.queued.empty()) {
    // Encoded without the lock: a reader may dequeue meanwhile. Only the state checked after it
    // decides whether the frame is still wanted (no STREAMOFF, unplug or new queue in between).
    const auto generation = generation_;
    const auto* memory = n.memory;
    const auto fourcc = n.fourcc;
    const auto size = n.size;
    std::vector<std::uint8_t> bytes;
    lock.unlock();
    try {
      bytes = scene_.encode(entry, fourcc, size);
    } catch (const std::exception& e) {  // an unreadable image: a corrupt frame, as a camera's
      std::fprintf(stderr, "cvo-v4l2-emulator: %s\n", e.what());
      flags = V4L2_BUF_FLAG_ERROR;
    }
    lock.lock();
    if (!encoded_ && first_frame_ != nullptr) first_frame_();
    encoded_ = true;
    if (generation != generation_ || gone_ || !n.streaming || n.memory != memory || n.queued.empty()) return;
    if (bytes.size() > n.length) bytes.resize(n.length), flags = V4L2_BUF_FLAG_ERROR;
    if (colour && config_.error_every != 0 && (colour_frames_ + 1) % config_.error_every == 0)
      flags = V4L2_BUF_FLAG_ERROR;
    const unsigned index = n.queued.front();
    n.queued.pop_front();
    Buffer& b = n.buffers[index];
    if (!bytes.empty()) std::memcpy(n.memory + b.offset, bytes.data(), bytes.size());
    b = Buffer{
        b.offset, Buffer::kDone, static_cast<std::uint32_t>(bytes.size()), static_cast<std::uint32_t>(n.stats.produced),
        flags,    due_time(n)};
    n.done.push_back(index);
    ++n.stats.delivered;
  } else {
    ++n.stats.dropped;  // no buffer: uvcvideo drops the frame, its sequence number is not reused
  }
  ++n.stats.produced;
  ++n.next_frame;
  next_scene_ = raw + 1;
  if (colour) ++colour_frames_;
  refresh();
  changed_.notify_all();  // a blocking DQBUF waits for this
}

// The camera leaves the bus, for a while or (at the end of the recording) for good. Lossless, it
// first waits for the reader to take what it made.
void Camera::unplug(std::unique_lock<std::mutex>& lock, bool for_good) {
  if (config_.lossless)
    changed_.wait(lock, [&] {
      const auto taken = [](const Node& n) { return n.done.empty() || !n.streaming; };
      return shutdown_ || (taken(nodes_[0]) && taken(nodes_[1]));
    });
  unplugged_once_ = true;
  gone_ = true;
  ++unplugs_;
  back_at_.reset();
  if (!for_good && config_.replug_after_s >= 0) back_at_ = now() + config_.replug_after_s;
  for (auto& n : nodes_) {
    n.streaming = false;
    n.queued.clear();
    n.done.clear();
  }
  if (next_scene_ >= scene_.size()) next_scene_ %= scene_.size();
  refresh();
}

}  // namespace cvo::drivers::v4l2_emulator
