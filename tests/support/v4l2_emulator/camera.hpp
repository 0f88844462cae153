#pragma once
// One emulated UVC RGB-D camera: a colour and a depth capture node answering V4L2 ioctls as the
// uvcvideo driver (with videobuf2 underneath) does, and a device thread that "captures" frames.
//
// Time: the camera's frames lie on a grid of its own clock, CLOCK_MONOTONIC: when the first node
// starts streaming, frame k of a node at r Hz is due start + k / r, and is stamped with that time
// (V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE), even when the thread makes
// it late. Nodes at the same rate thus have equal timestamps, as a hardware-synchronised camera.
// Content: frame k shows the recording's entry floor(k * play_fps / r), counted from where the
// last streaming ended (a camera keeps looking at the world while nobody reads it, but a test
// wants the recording to go on, not to skip).
//
// Buffers: REQBUFS makes real shared memory (a memfd), which the reader maps; the device fills
// the oldest queued buffer and moves it to the done list with the node's sequence number. With no
// queued buffer the frame is dropped and the sequence still advances (a gap, as uvcvideo). The
// sequence counts from 0 at each plug.
//
// Unplug: every open file of the camera then answers ENODEV (poll: POLLERR | POLLHUP | POLLPRI,
// as an unregistered video device) and opening a node fails with ENOENT (udev removed it) until
// the camera is back; after that, open succeeds on a fresh device while old files stay dead.
#include <sys/types.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "tests/support/v4l2_emulator/config.hpp"
#include "tests/support/v4l2_emulator/scene.hpp"

namespace cvo::drivers::v4l2_emulator {

class Camera;

/// An open file of an emulated node. Its descriptor is a real eventfd, readable exactly when
/// poll() should report something for the file, so a real poll() waits on it.
struct OpenFile {
  Camera* camera = nullptr;
  int role = 0;                  // 0 colour, 1 depth
  std::uint64_t generation = 0;  // the plug it was opened on
  bool nonblocking = false;
  int fd = -1;
  bool signalled = false;
};

/// What a test may ask of a node (cvo_v4l2_emulator_stats).
struct NodeStats {
  std::uint64_t produced = 0;   // frames the device made, this plug (sequence numbers used)
  std::uint64_t delivered = 0;  // into a buffer
  std::uint64_t dropped = 0;    // no buffer queued: a sequence gap
  std::uint64_t unplugs = 0;    // of the camera, in this process
};

class Camera {
 public:
  /// Throws io::InputError when the recording does not open. `first_frame` is called (once, from
  /// the device thread) after the camera's first frame is encoded: from then on the device thread
  /// uses OpenCV, so it must be stopped before OpenCV's own statics go at exit (see stop()).
  Camera(CameraConfig config, void (*first_frame)());
  ~Camera();
  /// Ends the device thread (waiting for a frame it is making); the camera makes no more frames.
  void stop_thread();
  Camera(const Camera&) = delete;
  Camera& operator=(const Camera&) = delete;

  [[nodiscard]] const CameraConfig& config() const { return config_; }
  /// 0 colour, 1 depth, -1 not one of this camera's nodes.
  [[nodiscard]] int role_of(const char* path) const;

  /// A new open file (an eventfd); nullptr with errno set (ENOENT while unplugged).
  std::shared_ptr<OpenFile> open(int role, int flags);
  void close(OpenFile& file);
  /// 0, or -errno.
  int ioctl(OpenFile& file, unsigned long request, void* arg);
  /// mmap of a buffer's offset; MAP_FAILED with errno as vb2_mmap would set it.
  void* mmap(OpenFile& file, void* addr, std::size_t length, int prot, int flags, off_t offset);
  /// The poll events of the file now.
  short events(const OpenFile& file);
  /// read(): uvcvideo has no read() I/O; ENODEV once unplugged.
  int read_error(const OpenFile& file);
  NodeStats stats(int role);

 private:
  struct Buffer {
    std::size_t offset = 0;
    enum State { kDequeued, kQueued, kDone } state = kDequeued;
    std::uint32_t bytesused = 0, sequence = 0, flags = 0;
    double timestamp = 0;
  };
  struct Node {
    const NodeConfig* config = nullptr;
    std::uint32_t fourcc = 0;
    FrameSize size;
    std::uint32_t rate = 0;
    // The videobuf2 queue.
    const OpenFile* owner = nullptr;
    std::vector<Buffer> buffers;
    std::size_t length = 0;  // of each buffer (sizeimage)
    int memfd = -1;
    std::uint8_t* memory = nullptr;  // the device's own mapping of the memfd
    std::size_t memory_size = 0;
    std::deque<unsigned> queued, done;
    bool streaming = false;
    std::uint64_t next_frame = 0;  // on the camera's grid
    NodeStats stats;
  };

  // ioctls, each as uvcvideo answers it; 0 or -errno.
  int querycap(void* arg) const;
  int enum_fmt(const Node& n, void* arg) const;
  int get_fmt(const Node& n, void* arg) const;
  int try_fmt(Node& n, void* arg, bool set);
  int enum_framesizes(const Node& n, void* arg) const;
  int enum_frameintervals(const Node& n, void* arg) const;
  int parm(Node& n, void* arg, bool set);
  int reqbufs(Node& n, const OpenFile& file, void* arg);
  int querybuf(const Node& n, void* arg) const;
  int qbuf(Node& n, void* arg);
  int dqbuf(Node& n, const OpenFile& file, void* arg, std::unique_lock<std::mutex>& lock);
  int streamon(Node& n, void* arg);
  int streamoff(Node& n, void* arg);
  int dispatch(Node& n, OpenFile& file, unsigned long request, void* arg, std::unique_lock<std::mutex>& lock);

  void fill(const Node& n, unsigned index, void* arg) const;
  void free_queue(Node& n);
  void stop(Node& n);
  void refresh();  // every open file's eventfd to its poll state
  short events_locked(const OpenFile& file) const;
  [[nodiscard]] bool alive(const OpenFile& file) const { return !gone_ && file.generation == generation_; }
  void reset_nodes();

  // The device thread.
  void run();
  Node* due_node();
  double due_time(const Node& n) const;
  void produce(Node& n, std::unique_lock<std::mutex>& lock);
  void unplug(std::unique_lock<std::mutex>& lock, bool for_good);

  const CameraConfig config_;
  Scene scene_;
  std::mutex mutex_;
  std::condition_variable changed_;
  Node nodes_[2];
  std::vector<OpenFile*> files_;
  std::uint64_t generation_ = 0;
  bool gone_ = false;
  std::optional<double> back_at_;  // while gone: when the nodes reappear (nullopt: never)
  bool unplugged_once_ = false;
  double start_ = 0;                 // the grid's origin, seconds of CLOCK_MONOTONIC
  std::size_t scene_base_ = 0;       // the entry shown at start_
  std::size_t next_scene_ = 0;       // where the next streaming will start
  std::uint64_t colour_frames_ = 0;  // made since the camera was first plugged in
  std::uint64_t unplugs_ = 0;
  bool shutdown_ = false;
  void (*first_frame_)() = nullptr;
  bool encoded_ = false;
  std::thread thread_;
};

}  // namespace cvo::drivers::v4l2_emulator
