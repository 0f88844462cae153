#include "drivers/v4l2_source.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "drivers/depth_registration.hpp"
#include "drivers/frame_gaps.hpp"
#include "drivers/read_result.hpp"
#include "drivers/stream_pairing.hpp"
#include "drivers/usb_cameras.hpp"
#include "drivers/v4l2_formats.hpp"

namespace cvo::drivers {
namespace {

using Clock = std::chrono::steady_clock;

constexpr unsigned kBuffers = 4;  // in flight per node: enough for the driver never to starve at 30 Hz

int xioctl(int fd, unsigned long request, void* arg) {
  int r = 0;
  do r = ::ioctl(fd, request, arg);
  while (r == -1 && errno == EINTR);
  return r;
}

std::string errno_text(int error) { return std::strerror(error); }

// A device error on an open node: these mean the device itself went away.
bool device_gone(int error) { return error == ENODEV || error == ENXIO || error == EBADF; }

struct Dequeued {
  int error = 0;  // errno of VIDIOC_DQBUF; EAGAIN: nothing yet
  unsigned index = 0;
  std::span<const std::uint8_t> data;
  double timestamp = 0;  // seconds, system clock
  std::uint32_t sequence = 0;
  bool corrupt = false;
};

// Closes the descriptor, also when the constructor that opened it throws.
class UniqueFd {
 public:
  explicit UniqueFd(int fd) : fd_(fd) {}
  ~UniqueFd() {
    if (fd_ >= 0) ::close(fd_);
  }
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  [[nodiscard]] int get() const { return fd_; }

 private:
  int fd_;
};

// One streaming capture node; the destructor stops streaming and unmaps (fd_ then closes).
class V4l2Node {
 public:
  V4l2Node(const std::string& path, const char* role)
      : path_(path), fd_(::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC)) {
    if (fd_.get() < 0) {
      const int error = errno;
      throw SourceError(path, std::string(role) + " node: " +
                                  (error == ENOENT ? "no such device node" : "cannot open: " + errno_text(error)) +
                                  "; " + usb_open_hint("v4l2:" + path));
    }
    v4l2_capability cap{};
    if (xioctl(fd_.get(), VIDIOC_QUERYCAP, &cap) != 0) fail(std::string(role) + " node: not a V4L2 device");
    const auto caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
    if ((caps & V4L2_CAP_VIDEO_CAPTURE) == 0 || (caps & V4L2_CAP_STREAMING) == 0)
      fail(std::string(role) + " node: not a streaming video capture device");
  }
  ~V4l2Node() {
    if (streaming_) {
      v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      xioctl(fd_.get(), VIDIOC_STREAMOFF, &type);
    }
    for (const auto& b : buffers_) ::munmap(b.start, b.length);
  }
  V4l2Node(const V4l2Node&) = delete;
  V4l2Node& operator=(const V4l2Node&) = delete;

  /// The first of `formats` the device takes at exactly width x height; fps as a request.
  void set_format(std::span<const std::uint32_t> formats, int width, int height, int fps) {
    std::string tried;
    for (const auto fourcc : formats) {
      v4l2_format f{};
      f.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      f.fmt.pix.width = static_cast<std::uint32_t>(width);
      f.fmt.pix.height = static_cast<std::uint32_t>(height);
      f.fmt.pix.pixelformat = fourcc;
      f.fmt.pix.field = V4L2_FIELD_NONE;
      if (xioctl(fd_.get(), VIDIOC_S_FMT, &f) == 0 && f.fmt.pix.pixelformat == fourcc &&
          f.fmt.pix.width == static_cast<std::uint32_t>(width) &&
          f.fmt.pix.height == static_cast<std::uint32_t>(height)) {
        fourcc_ = fourcc;
        bytes_per_line_ = static_cast<int>(std::max(f.fmt.pix.bytesperline, f.fmt.pix.width * 2));
        break;
      }
      tried += (tried.empty() ? "" : ", ") + fourcc_text(fourcc);
    }
    if (fourcc_ == 0) fail("does not stream " + tried + " at " + std::to_string(width) + "x" + std::to_string(height));
    // A request: some drivers have fixed rates, and the pairing only needs the real one.
    v4l2_streamparm parm{};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    parm.parm.capture.timeperframe = {1, static_cast<std::uint32_t>(std::max(fps, 1))};
    xioctl(fd_.get(), VIDIOC_S_PARM, &parm);
  }

  void start() {
    v4l2_requestbuffers req{};
    req.count = kBuffers;
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_.get(), VIDIOC_REQBUFS, &req) != 0 || req.count < 2) fail("no mmap streaming buffers");
    for (unsigned i = 0; i < req.count; ++i) {
      v4l2_buffer b{};
      b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      b.memory = V4L2_MEMORY_MMAP;
      b.index = i;
      if (xioctl(fd_.get(), VIDIOC_QUERYBUF, &b) != 0) fail("VIDIOC_QUERYBUF");
      void* start = ::mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_.get(), b.m.offset);
      if (start == MAP_FAILED) fail("mmap");
      buffers_.push_back({start, b.length});
      if (!requeue(i)) fail("VIDIOC_QBUF");
    }
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd_.get(), VIDIOC_STREAMON, &type) != 0) fail("VIDIOC_STREAMON");
    streaming_ = true;
  }

  Dequeued dequeue() {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    Dequeued d;
    if (xioctl(fd_.get(), VIDIOC_DQBUF, &b) != 0) {
      d.error = errno;
      return d;
    }
    d.index = b.index;
    const auto& mapped = buffers_.at(b.index);
    d.data = {static_cast<const std::uint8_t*>(mapped.start), std::min<std::size_t>(b.bytesused, mapped.length)};
    d.sequence = b.sequence;
    d.corrupt = (b.flags & V4L2_BUF_FLAG_ERROR) != 0;
    d.timestamp = system_time(b);
    return d;
  }

  bool requeue(unsigned index) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = index;
    return xioctl(fd_.get(), VIDIOC_QBUF, &b) == 0;
  }

  [[nodiscard]] int fd() const { return fd_.get(); }
  [[nodiscard]] std::uint32_t fourcc() const { return fourcc_; }
  [[nodiscard]] int bytes_per_line() const { return bytes_per_line_; }
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    const int error = errno;
    throw SourceError(path_, what + (error != 0 ? " (" + errno_text(error) + ")" : ""));
  }

  // Capture time on the system clock. Drivers stamp buffers with CLOCK_MONOTONIC; one that does
  // not is stamped with the time the buffer was taken.
  static double system_time(const v4l2_buffer& b) {
    const double now_wall = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
    if ((b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) != V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) return now_wall;
    timespec mono{};
    ::clock_gettime(CLOCK_MONOTONIC, &mono);
    const double now_mono = static_cast<double>(mono.tv_sec) + static_cast<double>(mono.tv_nsec) * 1e-9;
    const double stamp = static_cast<double>(b.timestamp.tv_sec) + static_cast<double>(b.timestamp.tv_usec) * 1e-6;
    return now_wall - (now_mono - stamp);
  }

  struct Mapped {
    void* start;
    std::size_t length;
  };

  std::string path_;
  UniqueFd fd_;
  std::vector<Mapped> buffers_;
  bool streaming_ = false;
  std::uint32_t fourcc_ = 0;
  int bytes_per_line_ = 0;
};

// The newest unpaired frame of one node.
struct Waiting {
  cv::Mat image;
  double timestamp = 0;
  bool fresh = false;
};

class V4l2Source final : public FrameSource {
 public:
  // depth_sensor: the depth node is a separate sensor of its own size, registered to colour.
  V4l2Source(const std::string& colour, const std::string& depth, const core::Intrinsics& intrinsics,
             const std::optional<core::DepthSensor>& depth_sensor, int fps)
      : colour_(colour, "colour"),
        depth_(depth, "depth"),
        intrinsics_(intrinsics),
        depth_size_(depth_sensor ? depth_sensor->intrinsics : intrinsics),
        max_dt_(0.5 / std::max(fps, 1)) {
    static constexpr std::array<std::uint32_t, 2> kColour{V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_MJPEG};
    static constexpr std::array<std::uint32_t, 1> kDepth{V4L2_PIX_FMT_Z16};
    colour_.set_format(kColour, intrinsics.width, intrinsics.height, fps);
    depth_.set_format(kDepth, depth_size_.width, depth_size_.height, fps);
    if (depth_sensor) registration_.emplace(*depth_sensor, intrinsics);
    colour_.start();
    depth_.start();
  }

  ReadResult read(core::RgbdFrame& frame, std::chrono::milliseconds timeout) override {
    const auto deadline = Clock::now() + timeout;
    for (;;) {
      if (waiting_[0].fresh && waiting_[1].fresh) {
        const auto action = pair_action(waiting_[0].timestamp, waiting_[1].timestamp, max_dt_);
        if (action == PairAction::kPair) return emit(frame);
        waiting_[action == PairAction::kDropColour ? 0 : 1].fresh = false;
        ++unpaired_;
      }
      if (!gone_.empty()) return disconnected(gone_);  // once what arrived before it is paired
      std::array<pollfd, 2> fds{pollfd{colour_.fd(), POLLIN, 0}, pollfd{depth_.fd(), POLLIN, 0}};
      const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()).count();
      const int n = ::poll(fds.data(), fds.size(), static_cast<int>(std::clamp<long long>(left, 0, INT_MAX)));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) return disconnected("v4l2: poll: " + errno_text(errno));
      if (n == 0) return result(ReadStatus::kTimeout);
      for (std::size_t k = 0; k < 2; ++k) {
        V4l2Node& node = k == 0 ? colour_ : depth_;
        if ((fds[k].revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) {
          gone_ = node.path() + ": device error (unplugged?)";
          break;
        }
        if ((fds[k].revents & POLLIN) == 0) continue;
        if (const auto stop = take(node, k); stop) return *stop;
        if (!gone_.empty()) break;
      }
    }
  }

  [[nodiscard]] std::string describe() const override {
    const std::string depth = registration_ ? ", depth " + std::to_string(depth_size_.width) + "x" +
                                                  std::to_string(depth_size_.height) + " registered to colour"
                                            : "";
    return "v4l2:" + colour_.path() + "," + depth_.path() + " (" + std::to_string(intrinsics_.width) + "x" +
           std::to_string(intrinsics_.height) + ", colour " + fourcc_text(colour_.fourcc()) + depth + ")";
  }

  [[nodiscard]] std::uint64_t lost_frames() const override {
    return unpaired_ + replaced_ + gaps_[0].lost() + gaps_[1].lost();
  }

 private:
  // Dequeues one buffer of node k into waiting_[k] and gives the buffer back to the driver at
  // once. A result only when read() must return it (bad frame). A device that went away sets
  // gone_: a frame dequeued before that is whole and still paired (the camera may go between
  // DQBUF and QBUF), and read() reports the disconnection after it.
  std::optional<ReadResult> take(V4l2Node& node, std::size_t k) {
    const Dequeued d = node.dequeue();
    if (d.error == EAGAIN) return std::nullopt;
    if (d.error != 0 && device_gone(d.error)) {
      gone_ = node.path() + ": " + errno_text(d.error);
      return std::nullopt;
    }
    if (d.error != 0) return bad_input(core::BadKind::kContent, node.path() + ": VIDIOC_DQBUF: " + errno_text(d.error));
    std::string bad;
    if (d.corrupt) {
      bad = "the driver marks the frame corrupt";
    } else if (k == 1) {
      bad = z16_to_depth(d.data, depth_size_.width, depth_size_.height, node.bytes_per_line(), 1.0, waiting_[k].image);
    } else if (node.fourcc() == V4L2_PIX_FMT_MJPEG) {
      bad = mjpeg_to_bgr(d.data, intrinsics_.width, intrinsics_.height, waiting_[k].image);
    } else {
      bad = yuyv_to_bgr(d.data, intrinsics_.width, intrinsics_.height, node.bytes_per_line(), waiting_[k].image);
    }
    if (!node.requeue(d.index) && device_gone(errno)) gone_ = node.path() + ": " + errno_text(errno);
    if (!bad.empty()) {
      if (waiting_[k].fresh) ++replaced_;  // its image may be half written now
      waiting_[k].fresh = false;
      return bad_input(core::BadKind::kContent, node.path() + ": " + bad);
    }
    if (waiting_[k].fresh) ++replaced_;
    waiting_[k].fresh = true;
    waiting_[k].timestamp = d.timestamp;
    gaps_[k].arrived(d.sequence);
    return std::nullopt;
  }

  ReadResult emit(core::RgbdFrame& frame) {
    // Swapped, not copied: the caller's old images become the next frames' buffers.
    std::swap(frame.bgr, waiting_[0].image);
    if (registration_)
      registration_->apply(waiting_[1].image, frame.depth);  // into the caller's buffer: no allocation
    else
      std::swap(frame.depth, waiting_[1].image);
    frame.timestamp = waiting_[0].timestamp;
    frame.depth_timestamp = waiting_[1].timestamp;
    frame.index = next_index_++;
    frame.intrinsics = intrinsics_;
    waiting_[0].fresh = waiting_[1].fresh = false;
    return result(ReadStatus::kFrame);
  }

  static ReadResult disconnected(std::string why) { return result(ReadStatus::kDisconnected, std::move(why)); }

  V4l2Node colour_, depth_;
  const core::Intrinsics intrinsics_;
  const core::Intrinsics depth_size_;  // the depth node's camera: the colour one unless separate
  std::optional<DepthRegistration> registration_;
  const double max_dt_;
  std::array<Waiting, 2> waiting_;  // [0] colour, [1] depth
  std::array<FrameGaps, 2> gaps_;
  std::uint64_t unpaired_ = 0, replaced_ = 0, next_index_ = 0;
  std::string gone_;  // why the device is gone; empty while it is there
};

}  // namespace

std::unique_ptr<FrameSource> open_v4l2(std::string_view nodes, const SourceOptions& options) {
  const std::string spec = "v4l2:" + std::string(nodes);
  const auto comma = nodes.find(',');
  if (comma == std::string_view::npos || comma == 0 || comma + 1 == nodes.size() ||
      nodes.find(',', comma + 1) != std::string_view::npos)
    throw SourceError(spec, "needs a colour and a depth device node: v4l2:COLOUR,DEPTH");
  if (!options.intrinsics) throw SourceError(spec, "v4l2 needs intrinsics (--camera ...)");
  if (const auto bad = options.intrinsics->validate(); !bad.empty()) throw SourceError(spec, "intrinsics: " + bad);
  if (options.depth_sensor)
    if (const auto bad = options.depth_sensor->intrinsics.validate(); !bad.empty())
      throw SourceError(spec, "depth sensor intrinsics: " + bad);
  return std::make_unique<V4l2Source>(std::string(nodes.substr(0, comma)), std::string(nodes.substr(comma + 1)),
                                      *options.intrinsics, options.depth_sensor, options.fps);
}

}  // namespace cvo::drivers
