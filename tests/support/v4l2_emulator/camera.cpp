#include "tests/support/v4l2_emulator/camera.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/mman.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "tests/support/v4l2_emulator/libc.hpp"

namespace cvo::drivers::v4l2_emulator {
namespace {

constexpr unsigned kMaxBuffers = 32;  // VB2_MAX_FRAME (uvcvideo's UVC_MAX_VIDEO_BUFFERS too)
constexpr double kStartDelay = 0.25;  // s from the first STREAMON to the first frame (real cameras take longer)
constexpr std::uint32_t kTimestampFlags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE;

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

template <std::size_t N>
void copy_text(std::uint8_t (&to)[N], const std::string& text) {
  std::memset(to, 0, N);
  std::memcpy(to, text.data(), std::min(text.size(), N - 1));
}

std::uint32_t kernel_version() {
  utsname u{};
  unsigned a = 0, b = 0, c = 0;
  if (::uname(&u) == 0) std::sscanf(u.release, "%u.%u.%u", &a, &b, &c);
  return (a << 16) | (b << 8) | std::min(c, 255u);
}

std::string description(std::uint32_t fourcc) {  // the V4L2 core's names (v4l_fill_fmtdesc)
  if (fourcc == V4L2_PIX_FMT_YUYV) return "YUYV 4:2:2";
  if (fourcc == V4L2_PIX_FMT_MJPEG) return "Motion-JPEG";
  return "16-bit Depth";
}

// Every format here has 16 bits per pixel when uncompressed; uvcvideo gives MJPEG no line length
// and the camera's largest frame (two bytes a pixel, as UVC descriptors of such cameras say).
void describe_format(v4l2_pix_format& p, std::uint32_t fourcc, FrameSize size) {
  p.width = size.width;
  p.height = size.height;
  p.pixelformat = fourcc;
  p.field = V4L2_FIELD_NONE;
  p.bytesperline = fourcc == V4L2_PIX_FMT_MJPEG ? 0 : size.width * 2;
  p.sizeimage = size.width * size.height * 2;
  p.colorspace = V4L2_COLORSPACE_SRGB;
  p.priv = V4L2_PIX_FMT_PRIV_MAGIC;
  p.flags = 0;
  p.ycbcr_enc = V4L2_YCBCR_ENC_DEFAULT;
  p.quantization = V4L2_QUANTIZATION_DEFAULT;
  p.xfer_func = V4L2_XFER_FUNC_DEFAULT;
}

// uvcvideo's closest frame size: the least area not shared by the two rectangles.
FrameSize closest(const std::vector<FrameSize>& sizes, std::uint32_t width, std::uint32_t height) {
  FrameSize best = sizes.front();
  std::uint64_t best_d = UINT64_MAX;
  for (const auto& s : sizes) {
    const std::uint64_t common = std::uint64_t(std::min(s.width, width)) * std::min(s.height, height);
    const std::uint64_t d = std::uint64_t(s.width) * s.height + std::uint64_t(width) * height - 2 * common;
    if (d < best_d) best_d = d, best = s;
  }
  return best;
}

}  // namespace

Camera::Camera(CameraConfig config, void (*first_frame)())
    : config_(std::move(config)), scene_(config_.tum, config_.depth_units_per_metre), first_frame_(first_frame) {
  nodes_[0].config = &config_.colour;
  nodes_[1].config = &config_.depth;
  reset_nodes();
  thread_ = std::thread([this] { run(); });
}

Camera::~Camera() {
  stop_thread();
  for (auto& n : nodes_) free_queue(n);
}

void Camera::stop_thread() {
  {
    const std::lock_guard lock(mutex_);
    shutdown_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

int Camera::role_of(const char* path) const {
  if (config_.colour.path == path) return 0;
  if (config_.depth.path == path) return 1;
  return -1;
}

void Camera::reset_nodes() {
  for (auto& n : nodes_) {
    free_queue(n);
    n.fourcc = n.config->formats.front();
    n.size = n.config->sizes.front();
    n.rate = n.config->rates.front();
    n.owner = nullptr;
    n.streaming = false;
    n.stats = NodeStats{};
  }
}

std::shared_ptr<OpenFile> Camera::open(int role, int flags) {
  const std::lock_guard lock(mutex_);
  if (gone_) {
    if (!back_at_ || now() < *back_at_) {
      errno = ENOENT;
      return nullptr;
    }
    gone_ = false;  // plugged in again: a new device
    ++generation_;
    reset_nodes();
  }
  const int fd = ::eventfd(0, EFD_NONBLOCK | ((flags & O_CLOEXEC) != 0 ? EFD_CLOEXEC : 0));
  if (fd < 0) return nullptr;
  auto file = std::make_shared<OpenFile>();
  *file = OpenFile{this, role, generation_, (flags & O_NONBLOCK) != 0, fd, false};
  files_.push_back(file.get());
  refresh();
  return file;
}

void Camera::close(OpenFile& file) {
  {
    const std::lock_guard lock(mutex_);
    std::erase(files_, &file);
    Node& n = nodes_[file.role];
    if (alive(file) && n.owner == &file) {  // vb2_fop_release: the owner's queue goes with it
      stop(n);
      free_queue(n);
      n.owner = nullptr;
    }
    refresh();
  }
  changed_.notify_all();
}

int Camera::ioctl(OpenFile& file, unsigned long request, void* arg) {
  std::unique_lock lock(mutex_);
  if (!alive(file)) return -ENODEV;  // v4l2_ioctl on an unregistered device
  if (arg == nullptr && request != VIDIOC_LOG_STATUS) return -EFAULT;
  const int r = dispatch(nodes_[file.role], file, request, arg, lock);
  lock.unlock();
  changed_.notify_all();
  return r;
}

int Camera::dispatch(Node& n, OpenFile& file, unsigned long request, void* arg, std::unique_lock<std::mutex>& lock) {
  const bool other_owner = n.owner != nullptr && n.owner != &file;
  switch (request) {
    case VIDIOC_QUERYCAP: return querycap(arg);
    case VIDIOC_ENUM_FMT: return enum_fmt(n, arg);
    case VIDIOC_G_FMT: return get_fmt(n, arg);
    case VIDIOC_TRY_FMT: return try_fmt(n, arg, false);
    case VIDIOC_S_FMT: return other_owner ? -EBUSY : try_fmt(n, arg, true);
    case VIDIOC_ENUM_FRAMESIZES: return enum_framesizes(n, arg);
    case VIDIOC_ENUM_FRAMEINTERVALS: return enum_frameintervals(n, arg);
    case VIDIOC_G_PARM: return parm(n, arg, false);
    case VIDIOC_S_PARM: return other_owner ? -EBUSY : parm(n, arg, true);
    case VIDIOC_REQBUFS: return other_owner ? -EBUSY : reqbufs(n, file, arg);
    case VIDIOC_QUERYBUF: return querybuf(n, arg);
    case VIDIOC_QBUF: return other_owner ? -EBUSY : qbuf(n, arg);
    case VIDIOC_DQBUF: return other_owner ? -EBUSY : dqbuf(n, file, arg, lock);
    case VIDIOC_STREAMON: return other_owner ? -EBUSY : streamon(n, arg);
    case VIDIOC_STREAMOFF: return other_owner ? -EBUSY : streamoff(n, arg);
    case VIDIOC_G_INPUT: *static_cast<int*>(arg) = 0; return 0;
    case VIDIOC_S_INPUT: return *static_cast<int*>(arg) == 0 ? 0 : -EINVAL;
    default: return -ENOTTY;  // what the V4L2 core says of an ioctl the driver does not implement
  }
}

int Camera::querycap(void* arg) const {
  auto& c = *static_cast<v4l2_capability*>(arg);
  std::memset(&c, 0, sizeof c);
  copy_text(c.driver, "uvcvideo");
  copy_text(c.card, config_.card);
  copy_text(c.bus_info, "usb-0000:00:14.0-1");
  c.version = kernel_version();
  c.device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING | V4L2_CAP_EXT_PIX_FORMAT;
  c.capabilities = c.device_caps | V4L2_CAP_META_CAPTURE | V4L2_CAP_DEVICE_CAPS;  // the metadata node too
  return 0;
}

int Camera::enum_fmt(const Node& n, void* arg) const {
  auto& f = *static_cast<v4l2_fmtdesc*>(arg);
  if (f.type != V4L2_BUF_TYPE_VIDEO_CAPTURE || f.index >= n.config->formats.size()) return -EINVAL;
  const auto fourcc = n.config->formats[f.index];
  const auto index = f.index;
  std::memset(&f, 0, sizeof f);
  f.index = index;
  f.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  f.flags = fourcc == V4L2_PIX_FMT_MJPEG ? V4L2_FMT_FLAG_COMPRESSED : 0;
  copy_text(f.description, description(fourcc));
  f.pixelformat = fourcc;
  return 0;
}

int Camera::get_fmt(const Node& n, void* arg) const {
  auto& f = *static_cast<v4l2_format*>(arg);
  if (f.type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return -EINVAL;
  describe_format(f.fmt.pix, n.fourcc, n.size);
  return 0;
}

int Camera::try_fmt(Node& n, void* arg, bool set) {
  auto& f = *static_cast<v4l2_format*>(arg);
  if (f.type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return -EINVAL;
  const auto& formats = n.config->formats;
  // An unknown format becomes the default one; the size the closest the camera has.
  const auto fourcc = std::find(formats.begin(), formats.end(), f.fmt.pix.pixelformat) != formats.end()
                          ? f.fmt.pix.pixelformat
                          : formats.front();
  const auto size = closest(n.config->sizes, f.fmt.pix.width, f.fmt.pix.height);
  if (set && !n.buffers.empty()) return -EBUSY;  // uvc_v4l2_set_format: buffers allocated
  describe_format(f.fmt.pix, fourcc, size);
  if (set) n.fourcc = fourcc, n.size = size;
  return 0;
}

int Camera::enum_framesizes(const Node& n, void* arg) const {
  auto& s = *static_cast<v4l2_frmsizeenum*>(arg);
  const auto& formats = n.config->formats;
  if (std::find(formats.begin(), formats.end(), s.pixel_format) == formats.end() || s.index >= n.config->sizes.size())
    return -EINVAL;
  s.type = V4L2_FRMSIZE_TYPE_DISCRETE;
  s.discrete = {n.config->sizes[s.index].width, n.config->sizes[s.index].height};
  return 0;
}

int Camera::enum_frameintervals(const Node& n, void* arg) const {
  auto& i = *static_cast<v4l2_frmivalenum*>(arg);
  const auto& formats = n.config->formats;
  const auto& sizes = n.config->sizes;
  if (std::find(formats.begin(), formats.end(), i.pixel_format) == formats.end() ||
      std::find(sizes.begin(), sizes.end(), FrameSize{i.width, i.height}) == sizes.end() ||
      i.index >= n.config->rates.size())
    return -EINVAL;
  i.type = V4L2_FRMIVAL_TYPE_DISCRETE;
  i.discrete = {1, n.config->rates[i.index]};
  return 0;
}

int Camera::parm(Node& n, void* arg, bool set) {
  auto& p = *static_cast<v4l2_streamparm*>(arg);
  if (p.type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return -EINVAL;
  if (set) {
    if (n.streaming) return -EBUSY;
    const auto& t = p.parm.capture.timeperframe;
    if (t.numerator != 0 && t.denominator != 0) {  // else the current one stays
      const double wanted = double(t.denominator) / t.numerator;
      n.rate = *std::min_element(n.config->rates.begin(), n.config->rates.end(), [&](auto a, auto b) {
        return std::abs(1 / double(a) - 1 / wanted) < std::abs(1 / double(b) - 1 / wanted);
      });
    }
  }
  std::memset(&p.parm, 0, sizeof p.parm);
  p.parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
  p.parm.capture.timeperframe = {1, n.rate};
  return 0;
}

int Camera::reqbufs(Node& n, const OpenFile& file, void* arg) {
  auto& r = *static_cast<v4l2_requestbuffers*>(arg);
  if (r.type != V4L2_BUF_TYPE_VIDEO_CAPTURE || r.memory != V4L2_MEMORY_MMAP) return -EINVAL;  // MMAP only here
  if (n.streaming) return -EBUSY;
  free_queue(n);  // mappings the reader still holds stay valid: vb2 orphans such buffers
  r.capabilities = V4L2_BUF_CAP_SUPPORTS_MMAP | V4L2_BUF_CAP_SUPPORTS_ORPHANED_BUFS;
  if (r.count == 0) {
    n.owner = nullptr;
    return 0;
  }
  r.count = std::min(r.count, kMaxBuffers);
  n.length = std::size_t(n.size.width) * n.size.height * 2;
  const auto page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
  const std::size_t stride = (n.length + page - 1) / page * page;
  n.memory_size = stride * r.count;
  n.memfd = ::memfd_create("cvo-v4l2-emulator", MFD_CLOEXEC);
  if (n.memfd < 0 || ::ftruncate(n.memfd, static_cast<off_t>(n.memory_size)) != 0) {
    free_queue(n);
    return -ENOMEM;
  }
  void* memory = libc().mmap(nullptr, n.memory_size, PROT_READ | PROT_WRITE, MAP_SHARED, n.memfd, 0);
  if (memory == MAP_FAILED) {
    free_queue(n);
    return -ENOMEM;
  }
  n.memory = static_cast<std::uint8_t*>(memory);
  n.buffers.resize(r.count);
  for (unsigned i = 0; i < r.count; ++i) n.buffers[i].offset = stride * i;
  n.owner = &file;
  return 0;
}

void Camera::fill(const Node& n, unsigned index, void* arg) const {
  auto& b = *static_cast<v4l2_buffer*>(arg);
  const Buffer& buffer = n.buffers[index];
  std::memset(&b, 0, sizeof b);
  b.index = index;
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  b.m.offset = static_cast<std::uint32_t>(buffer.offset);
  b.length = static_cast<std::uint32_t>(n.length);
  b.field = V4L2_FIELD_NONE;
  b.flags = kTimestampFlags | buffer.flags | (buffer.state == Buffer::kQueued ? V4L2_BUF_FLAG_QUEUED : 0u) |
            (buffer.state == Buffer::kDone ? V4L2_BUF_FLAG_DONE : 0u);
  if (buffer.state != Buffer::kQueued) {
    b.bytesused = buffer.bytesused;
    b.sequence = buffer.sequence;
    const double whole = std::floor(buffer.timestamp);
    b.timestamp.tv_sec = static_cast<time_t>(whole);
    b.timestamp.tv_usec = static_cast<suseconds_t>(std::lround((buffer.timestamp - whole) * 1e6));
    if (b.timestamp.tv_usec >= 1000000) ++b.timestamp.tv_sec, b.timestamp.tv_usec -= 1000000;
  }
}

int Camera::querybuf(const Node& n, void* arg) const {
  auto& b = *static_cast<v4l2_buffer*>(arg);
  if (b.type != V4L2_BUF_TYPE_VIDEO_CAPTURE || b.index >= n.buffers.size()) return -EINVAL;
  fill(n, b.index, arg);
  return 0;
}

int Camera::qbuf(Node& n, void* arg) {
  auto& b = *static_cast<v4l2_buffer*>(arg);
  if (b.type != V4L2_BUF_TYPE_VIDEO_CAPTURE || b.memory != V4L2_MEMORY_MMAP || b.index >= n.buffers.size())
    return -EINVAL;
  Buffer& buffer = n.buffers[b.index];
  if (buffer.state != Buffer::kDequeued) return -EINVAL;  // "buffer already queued"
  buffer.state = Buffer::kQueued;
  buffer.flags = 0;
  n.queued.push_back(b.index);
  fill(n, b.index, arg);
  return 0;
}

int Camera::dqbuf(Node& n, const OpenFile& file, void* arg, std::unique_lock<std::mutex>& lock) {
  auto& b = *static_cast<v4l2_buffer*>(arg);
  if (b.type != V4L2_BUF_TYPE_VIDEO_CAPTURE || b.memory != V4L2_MEMORY_MMAP) return -EINVAL;
  for (;;) {
    if (!alive(file)) return -ENODEV;
    if (!n.streaming) return -EINVAL;  // "streaming off"
    if (!n.done.empty()) break;
    if (file.nonblocking) return -EAGAIN;
    changed_.wait(lock);
  }
  const unsigned index = n.done.front();
  n.done.pop_front();
  n.buffers[index].state = Buffer::kDequeued;
  fill(n, index, arg);
  refresh();
  return 0;
}

int Camera::streamon(Node& n, void* arg) {
  if (*static_cast<int*>(arg) != V4L2_BUF_TYPE_VIDEO_CAPTURE || n.buffers.empty()) return -EINVAL;
  if (n.streaming) return 0;
  const double t = now();
  if (!nodes_[0].streaming && !nodes_[1].streaming) {  // the camera starts capturing
    start_ = t + kStartDelay;
    scene_base_ = next_scene_;
  }
  n.next_frame = t <= start_ ? 0 : static_cast<std::uint64_t>(std::ceil((t - start_) * n.rate));
  n.streaming = true;
  refresh();
  return 0;
}

int Camera::streamoff(Node& n, void* arg) {
  if (*static_cast<int*>(arg) != V4L2_BUF_TYPE_VIDEO_CAPTURE) return -EINVAL;
  stop(n);
  return 0;
}

// vb2_core_streamoff: every buffer back to the reader, dequeued, whatever it held.
void Camera::stop(Node& n) {
  n.streaming = false;
  n.queued.clear();
  n.done.clear();
  for (auto& b : n.buffers) b.state = Buffer::kDequeued;
  refresh();
}

void Camera::free_queue(Node& n) {
  n.queued.clear();
  n.done.clear();
  n.buffers.clear();
  if (n.memory != nullptr) libc().munmap(n.memory, n.memory_size);
  if (n.memfd >= 0) libc().close(n.memfd);
  n.memory = nullptr;
  n.memfd = -1;
  n.memory_size = 0;
}

void* Camera::mmap(OpenFile& file, void* addr, std::size_t length, int prot, int flags, off_t offset) {
  const std::lock_guard lock(mutex_);
  if (!alive(file)) {
    errno = ENODEV;
    return MAP_FAILED;
  }
  const Node& n = nodes_[file.role];
  // vb2_mmap: a shared mapping of one whole buffer, found by its offset.
  const auto it = std::find_if(n.buffers.begin(), n.buffers.end(),
                               [&](const Buffer& b) { return static_cast<off_t>(b.offset) == offset; });
  if (it == n.buffers.end() || (flags & MAP_SHARED) == 0 || length > n.length || length == 0) {
    errno = EINVAL;
    return MAP_FAILED;
  }
  return libc().mmap(addr, length, prot, flags, n.memfd, offset);
}

short Camera::events_locked(const OpenFile& file) const {
  if (!alive(file)) return POLLERR | POLLHUP | POLLPRI;  // v4l2_poll of an unregistered device
  const Node& n = nodes_[file.role];
  if (!n.streaming) return POLLERR;  // vb2_poll
  return n.done.empty() ? 0 : POLLIN | POLLRDNORM;
}

short Camera::events(const OpenFile& file) {
  const std::lock_guard lock(mutex_);
  return events_locked(file);
}

int Camera::read_error(const OpenFile& file) {
  const std::lock_guard lock(mutex_);
  return alive(file) ? EINVAL : ENODEV;
}

void Camera::refresh() {
  for (OpenFile* f : files_) {
    const bool ready = events_locked(*f) != 0;
    if (ready == f->signalled) continue;
    eventfd_t value = 0;
    if (ready)
      ::eventfd_write(f->fd, 1);
    else
      ::eventfd_read(f->fd, &value);
    f->signalled = ready;
  }
}

NodeStats Camera::stats(int role) {
  const std::lock_guard lock(mutex_);
  NodeStats s = nodes_[role].stats;
  s.unplugs = unplugs_;
  return s;
}

}  // namespace cvo::drivers::v4l2_emulator
