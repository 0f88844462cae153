#pragma once
// What the tracking thread hands to the publisher thread, one event per tracked frame: the pose,
// and when the frame closed a local graph or made a keyframe, a slot of the matching pool. All
// storage is preallocated; the tracking thread only copies into it (cv::Mat::copyTo into a
// same-sized image and vector assignment within capacity do not allocate).
//
// The tracking thread never waits on the publisher unless asked to (deterministic replay): when
// the outbox is full the event is dropped and counted, the frame's pose is still tracked; a
// keyframe or local graph that finds no slot, or whose event is dropped, is counted lost.
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <optional>
#include <vector>

#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/lcm/tracker_messages.hpp"
#include "libcvo/odometry/local_graph.hpp"
#include "libcvo/odometry/track_result.hpp"
#include "libcvo/registration/point_cloud.hpp"

namespace cvo::daemon::trackerd {

// A tracked frame (what CVO_POSE says, lcm::pose_message), and when it arrived for its latency.
struct PoseEvent : lcm::TrackedPose {
  std::chrono::steady_clock::time_point received;
  // The tracked odometry pose of the keyframe this frame made (frame n-1 or n itself), which the
  // map places: odom_pose is the smooth pose a controller reads, not the keyframe's anchor.
  std::optional<core::SE3> keyframe_odom_pose;
};

struct KeyframeSlot {
  std::int64_t id = 0;
  core::SE3 pose;
  core::RgbdFrame frame;
  registration::PointCloud cloud;  // the tracker's own points of the keyframe
};

struct LocalGraphSlot {
  std::int64_t keyframe_id = 0;
  odometry::LocalGraph graph;
};

struct Event {
  std::int64_t session = 0;  // the tracker session everything in the event belongs to
  bool has_pose = true;      // false: only a local graph (a session's open one, at its end)
  PoseEvent pose;
  int keyframe_slot = -1;  // index into keyframes(), or -1
  int graph_slot = -1;     // index into graphs(), or -1
};

class Outbox {
 public:
  /// capacity events; pool_size keyframe and local-graph slots, images width x height, clouds of
  /// cloud_capacity points, local graphs of graph_capacity nodes.
  Outbox(std::size_t capacity, std::size_t pool_size, int width, int height, std::size_t cloud_capacity,
         std::size_t graph_capacity);

  // Tracking thread: reserve pool slots (-1 when the pool is exhausted, counted in lost(), unless
  // `wait` is set: then it waits for the publisher to release one), fill them, then push the
  // event. push() returns false (counted in dropped(), its slots in lost()) when full, unless
  // `wait` is set: then it waits for room.
  int acquire_keyframe_slot(bool wait);
  int acquire_graph_slot(bool wait);
  [[nodiscard]] KeyframeSlot& keyframe(int slot) { return keyframes_[static_cast<std::size_t>(slot)]; }
  [[nodiscard]] LocalGraphSlot& graph(int slot) { return graphs_[static_cast<std::size_t>(slot)]; }
  bool push(const Event& event, bool wait);
  void close();
  /// Tracking thread, when the camera changed size: waits until the publisher has released every
  /// keyframe slot, then gives each slot images of the new size (the one allocation of a camera
  /// change, so that the copies after it again never allocate).
  void resize_keyframe_images(int width, int height);  // no more events: pop() returns false once the outbox is empty

  // Publisher thread: the oldest event, waiting up to `timeout`. Release its slots when done.
  bool pop(Event& event, std::chrono::milliseconds timeout);
  void release(const Event& event);

  [[nodiscard]] bool finished() const;  // closed and empty
  [[nodiscard]] std::int64_t dropped() const;
  [[nodiscard]] std::int64_t lost() const;  // keyframes and local graphs that could not go out

 private:
  int acquire(std::vector<char>& used, bool wait);

  std::vector<Event> events_;  // circular
  std::size_t head_ = 0, count_ = 0;
  std::vector<KeyframeSlot> keyframes_;
  std::vector<LocalGraphSlot> graphs_;
  std::vector<char> keyframe_used_, graph_used_;
  bool closed_ = false;
  std::int64_t dropped_ = 0, lost_ = 0;
  mutable std::mutex mutex_;
  std::condition_variable ready_, room_;
};

}  // namespace cvo::daemon::trackerd
