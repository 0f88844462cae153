#include "daemon/trackerd/outbox.hpp"

#include <algorithm>

#include <opencv2/core.hpp>

namespace cvo::daemon::trackerd {

namespace {

// Written once now: with lock_memory (MCL_ONFAULT) their pages are then resident and locked before
// the tracking thread first copies a keyframe into them.
void create_images(KeyframeSlot& k, int width, int height) {
  k.frame.bgr.create(height, width, CV_8UC3);
  k.frame.depth.create(height, width, CV_16UC1);
  k.frame.bgr.setTo(0);
  k.frame.depth.setTo(0);
}

}  // namespace

Outbox::Outbox(std::size_t capacity, std::size_t pool_size, int width, int height, std::size_t cloud_capacity,
               std::size_t graph_capacity)
    : events_(capacity), keyframes_(pool_size), keyframe_used_(pool_size, 0), graph_used_(pool_size, 0) {
  for (auto& k : keyframes_) {  // full-size images and clouds now, so that copies into them never allocate
    create_images(k, width, height);
    k.cloud = registration::PointCloud(cloud_capacity);
  }
  graphs_.reserve(pool_size);
  for (std::size_t i = 0; i < pool_size; ++i) graphs_.push_back({0, odometry::LocalGraph(graph_capacity)});
}

int Outbox::acquire(std::vector<char>& used, bool wait) {
  std::unique_lock lock(mutex_);
  const auto free_slot = [&] { return std::find(used.begin(), used.end(), 0); };
  if (wait) room_.wait(lock, [&] { return free_slot() != used.end(); });
  const auto slot = free_slot();
  if (slot == used.end()) {
    ++lost_;
    return -1;
  }
  *slot = 1;
  return static_cast<int>(slot - used.begin());
}

int Outbox::acquire_keyframe_slot(bool wait) { return acquire(keyframe_used_, wait); }
int Outbox::acquire_graph_slot(bool wait) { return acquire(graph_used_, wait); }

bool Outbox::push(const Event& event, bool wait) {
  std::unique_lock lock(mutex_);
  if (wait) room_.wait(lock, [&] { return closed_ || count_ < events_.size(); });
  if (closed_ || count_ == events_.size()) {
    ++dropped_;
    lost_ += (event.keyframe_slot >= 0 ? 1 : 0) + (event.graph_slot >= 0 ? 1 : 0);
    if (event.keyframe_slot >= 0) keyframe_used_[static_cast<std::size_t>(event.keyframe_slot)] = 0;
    if (event.graph_slot >= 0) graph_used_[static_cast<std::size_t>(event.graph_slot)] = 0;
    return false;
  }
  events_[(head_ + count_) % events_.size()] = event;
  ++count_;
  lock.unlock();
  ready_.notify_one();
  return true;
}

void Outbox::close() {
  {
    const std::lock_guard lock(mutex_);
    closed_ = true;
  }
  ready_.notify_all();
  room_.notify_all();
}

void Outbox::resize_keyframe_images(int width, int height) {
  std::unique_lock lock(mutex_);
  room_.wait(lock, [&] { return std::find(keyframe_used_.begin(), keyframe_used_.end(), 1) == keyframe_used_.end(); });
  for (auto& k : keyframes_) create_images(k, width, height);  // no slot in use: the publisher reads none
}

bool Outbox::pop(Event& event, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!ready_.wait_for(lock, timeout, [&] { return count_ > 0 || closed_; }) || count_ == 0) return false;
  event = events_[head_];
  head_ = (head_ + 1) % events_.size();
  --count_;
  lock.unlock();
  room_.notify_one();
  return true;
}

void Outbox::release(const Event& event) {
  {
    const std::lock_guard lock(mutex_);
    if (event.keyframe_slot >= 0) keyframe_used_[static_cast<std::size_t>(event.keyframe_slot)] = 0;
    if (event.graph_slot >= 0) graph_used_[static_cast<std::size_t>(event.graph_slot)] = 0;
  }
  room_.notify_all();  // a tracker waiting for a slot
}

bool Outbox::finished() const {
  const std::lock_guard lock(mutex_);
  return closed_ && count_ == 0;
}

std::int64_t Outbox::dropped() const {
  const std::lock_guard lock(mutex_);
  return dropped_;
}

std::int64_t Outbox::lost() const {
  const std::lock_guard lock(mutex_);
  return lost_;
}

}  // namespace cvo::daemon::trackerd
