// libcvo_v4l2_emulator.so: emulated V4L2 cameras at the system-call boundary, for LD_PRELOAD.
//
// It defines the C library's open/openat (and their 64-bit and _FORTIFY_SOURCE names), close,
// ioctl, mmap, poll and read. Calls on the nodes the environment names (config.hpp) are answered
// by an emulated camera (camera.hpp); every other call goes on to the C library unchanged. The
// process-wide state is one Emulator, made when the library loads and only if a camera is
// configured: in any other process the library only passes calls on.
//
// Not emulated: dup/dup2/fcntl(F_DUPFD) of a node's descriptor, select/ppoll/epoll on it (poll
// only), USERPTR and DMABUF buffers, controls. A process that forks keeps the cameras but not
// their threads: only the exec that usually follows is supported.
#include <dlfcn.h>
#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "tests/support/v4l2_emulator/camera.hpp"
#include "tests/support/v4l2_emulator/libc.hpp"
#include "tests/support/v4l2_emulator/stats.h"

namespace cvo::drivers::v4l2_emulator {

const Libc& libc() {
  static const Libc functions = [] {
    Libc f{};
    const auto next = [](const char* name) {
      void* symbol = ::dlsym(RTLD_NEXT, name);
      if (symbol == nullptr) {
        std::fprintf(stderr, "cvo-v4l2-emulator: no %s after this library\n", name);
        std::abort();
      }
      return symbol;
    };
    f.open = reinterpret_cast<decltype(f.open)>(next("open"));
    f.openat = reinterpret_cast<decltype(f.openat)>(next("openat"));
    f.close = reinterpret_cast<decltype(f.close)>(next("close"));
    f.ioctl = reinterpret_cast<decltype(f.ioctl)>(next("ioctl"));
    f.mmap = reinterpret_cast<decltype(f.mmap)>(next("mmap"));
    f.munmap = reinterpret_cast<decltype(f.munmap)>(next("munmap"));
    f.poll = reinterpret_cast<decltype(f.poll)>(next("poll"));
    f.read = reinterpret_cast<decltype(f.read)>(next("read"));
    return f;
  }();
  return functions;
}

namespace {

void stop_cameras();

// A camera's first frame: its device thread now uses OpenCV, whose statics made on that first
// use are destroyed at exit before this library's destructor runs. An exit handler registered
// now runs before theirs and stops the device threads first.
void first_frame() {
  static std::once_flag once;
  std::call_once(once, [] { std::atexit(stop_cameras); });
}

class Emulator {
 public:
  explicit Emulator(std::vector<CameraConfig> configs) {
    for (auto& c : configs) {
      try {
        cameras_.push_back(std::make_unique<Camera>(std::move(c), first_frame));
      } catch (const std::exception& e) {
        std::fprintf(stderr, "cvo-v4l2-emulator: camera not emulated: %s\n", e.what());
      }
    }
  }

  /// The new descriptor, -1 with errno, or nullopt when `path` is not an emulated node.
  std::optional<int> open(const char* path, int flags) {
    if (path == nullptr) return std::nullopt;
    for (auto& camera : cameras_) {
      const int role = camera->role_of(path);
      if (role < 0) continue;
      auto file = camera->open(role, flags);
      if (!file) return -1;
      const std::lock_guard lock(mutex_);
      files_[file->fd] = file;
      open_files_ = files_.size();
      return file->fd;
    }
    return std::nullopt;
  }

  /// The open file behind `fd`, or nullptr: not an emulated node's descriptor.
  std::shared_ptr<OpenFile> file(int fd) {
    if (open_files_.load(std::memory_order_relaxed) == 0) return nullptr;
    const std::lock_guard lock(mutex_);
    const auto it = files_.find(fd);
    return it == files_.end() ? nullptr : it->second;
  }

  /// Forgets `fd`; the caller closes the descriptor itself.
  std::shared_ptr<OpenFile> release(int fd) {
    if (open_files_.load(std::memory_order_relaxed) == 0) return nullptr;
    const std::lock_guard lock(mutex_);
    const auto it = files_.find(fd);
    if (it == files_.end()) return nullptr;
    auto file = it->second;
    files_.erase(it);
    open_files_ = files_.size();
    return file;
  }

  [[nodiscard]] bool any_open() const { return open_files_.load(std::memory_order_relaxed) != 0; }

  void stop() {
    for (auto& camera : cameras_) camera->stop_thread();
  }

  Camera* camera_of(const char* path, int& role) {
    for (auto& camera : cameras_)
      if ((role = camera->role_of(path)) >= 0) return camera.get();
    return nullptr;
  }

 private:
  std::vector<std::unique_ptr<Camera>> cameras_;
  std::mutex mutex_;  // of files_ only; never held while calling out
  std::unordered_map<int, std::shared_ptr<OpenFile>> files_;
  std::atomic<std::size_t> open_files_{0};
};

// The one process-wide pointer an LD_PRELOAD library needs: null until the library's
// constructor has run, and in processes without emulated cameras.
std::atomic<Emulator*> emulator{nullptr};

__attribute__((constructor)) void load() {
  auto configs = cameras_from_environment();
  if (!configs.empty()) emulator = new Emulator(std::move(configs));
}

void stop_cameras() {
  if (Emulator* e = emulator.load()) e->stop();
}

// Before the libraries it uses unload.
__attribute__((destructor)) void unload() { delete emulator.exchange(nullptr); }

// (openat's path relative to a directory is never a node: the nodes are absolute paths.)
std::optional<int> open_node(const char* path, int flags) {
  Emulator* e = emulator.load();
  return e == nullptr || path == nullptr || path[0] != '/' ? std::nullopt : e->open(path, flags);
}

std::shared_ptr<OpenFile> node_file(int fd) {
  Emulator* e = emulator.load();
  return e == nullptr ? nullptr : e->file(fd);
}

int failed(int error) {
  errno = error;
  return -1;
}

mode_t mode_argument(int flags, va_list& args) {
  return (flags & O_CREAT) != 0 || (flags & O_TMPFILE) == O_TMPFILE ? va_arg(args, mode_t) : 0;
}

// poll() over emulated and real descriptors: a real poll on the emulated files' eventfds (readable
// while they have something to report), then their events from the camera's state.
int poll_files(pollfd* fds, nfds_t count, int timeout_ms, const std::vector<std::shared_ptr<OpenFile>>& files) {
  std::vector<pollfd> real(fds, fds + count);
  for (nfds_t i = 0; i < count; ++i)
    if (files[i]) real[i].events = POLLIN;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  for (;;) {
    int wait = timeout_ms;
    if (timeout_ms > 0)
      wait = static_cast<int>(std::max<long long>(
          0, std::chrono::ceil<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count()));
    const int r = libc().poll(real.data(), count, wait);
    if (r < 0) return r;
    int ready = 0;
    for (nfds_t i = 0; i < count; ++i) {
      const short always = POLLERR | POLLHUP | POLLNVAL;
      fds[i].revents = files[i] ? static_cast<short>(files[i]->camera->events(*files[i]) & (fds[i].events | always))
                                : real[i].revents;
      ready += fds[i].revents != 0;
    }
    if (ready > 0 || r == 0) return ready;
    // An eventfd was ready but its file's state changed since: wait again for the rest.
  }
}

}  // namespace
}  // namespace cvo::drivers::v4l2_emulator

using namespace cvo::drivers::v4l2_emulator;

extern "C" {

__attribute__((visibility("default"))) int open(const char* path, int flags, ...) {
  va_list args;
  va_start(args, flags);
  const mode_t mode = mode_argument(flags, args);
  va_end(args);
  if (const auto fd = open_node(path, flags)) return *fd;
  return libc().open(path, flags, mode);
}

// On 64-bit glibc open64 is open: the same node or the same call.
__attribute__((visibility("default"))) int open64(const char* path, int flags, ...) {
  va_list args;
  va_start(args, flags);
  const mode_t mode = mode_argument(flags, args);
  va_end(args);
  return open(path, flags, mode);
}

__attribute__((visibility("default"))) int openat(int dir, const char* path, int flags, ...) {
  va_list args;
  va_start(args, flags);
  const mode_t mode = mode_argument(flags, args);
  va_end(args);
  if (const auto fd = open_node(path, flags)) return *fd;
  return libc().openat(dir, path, flags, mode);
}

__attribute__((visibility("default"))) int openat64(int dir, const char* path, int flags, ...) {
  va_list args;
  va_start(args, flags);
  const mode_t mode = mode_argument(flags, args);
  va_end(args);
  if (const auto fd = open_node(path, flags)) return *fd;
  return libc().openat(dir, path, flags, mode);
}

// _FORTIFY_SOURCE's names for open without a mode.
__attribute__((visibility("default"))) int __open_2(const char* path, int flags) { return open(path, flags); }
__attribute__((visibility("default"))) int __open64_2(const char* path, int flags) { return open(path, flags); }
__attribute__((visibility("default"))) int __openat_2(int dir, const char* path, int flags) {
  return openat(dir, path, flags);
}
__attribute__((visibility("default"))) int __openat64_2(int dir, const char* path, int flags) {
  return openat(dir, path, flags);
}

__attribute__((visibility("default"))) int close(int fd) {
  Emulator* e = emulator.load();
  if (e != nullptr)
    if (const auto file = e->release(fd)) file->camera->close(*file);
  return libc().close(fd);
}

__attribute__((visibility("default"))) int ioctl(int fd, unsigned long request, ...) noexcept {
  va_list args;
  va_start(args, request);
  void* arg = va_arg(args, void*);
  va_end(args);
  const auto file = node_file(fd);
  if (!file) return libc().ioctl(fd, request, arg);
  try {
    const int r = file->camera->ioctl(*file, request, arg);
    return r < 0 ? failed(-r) : r;
  } catch (const std::exception&) {
    return failed(ENOMEM);
  }
}

__attribute__((visibility("default"))) void* mmap(void* addr, size_t length, int prot, int flags, int fd,
                                                  off_t offset) noexcept {
  const auto file = node_file(fd);
  return file ? file->camera->mmap(*file, addr, length, prot, flags, offset)
              : libc().mmap(addr, length, prot, flags, fd, offset);
}

__attribute__((visibility("default"))) void* mmap64(void* addr, size_t length, int prot, int flags, int fd,
                                                    off_t offset) noexcept {
  return mmap(addr, length, prot, flags, fd, offset);
}

__attribute__((visibility("default"))) int poll(pollfd* fds, nfds_t count, int timeout_ms) {
  Emulator* e = emulator.load();
  if (e == nullptr || !e->any_open()) return libc().poll(fds, count, timeout_ms);
  std::vector<std::shared_ptr<OpenFile>> files(count);
  bool any = false;
  for (nfds_t i = 0; i < count; ++i) any |= (files[i] = e->file(fds[i].fd)) != nullptr;
  if (!any) return libc().poll(fds, count, timeout_ms);
  try {
    return poll_files(fds, count, timeout_ms, files);
  } catch (const std::exception&) {
    return failed(ENOMEM);
  }
}

__attribute__((visibility("default"))) int __poll_chk(pollfd* fds, nfds_t count, int timeout_ms, size_t) {
  return poll(fds, count, timeout_ms);
}

__attribute__((visibility("default"))) ssize_t read(int fd, void* buffer, size_t size) {
  if (const auto file = node_file(fd)) return failed(file->camera->read_error(*file));
  return libc().read(fd, buffer, size);
}

__attribute__((visibility("default"))) ssize_t __read_chk(int fd, void* buffer, size_t size, size_t) {
  return read(fd, buffer, size);
}

__attribute__((visibility("default"))) int cvo_v4l2_emulator_stats(const char* node,
                                                                   cvo_v4l2_emulator_node_stats* out) {
  Emulator* e = emulator.load();
  int role = -1;
  Camera* camera = e == nullptr || node == nullptr ? nullptr : e->camera_of(node, role);
  if (camera == nullptr || out == nullptr) return -1;
  const NodeStats s = camera->stats(role);
  *out = {s.produced, s.delivered, s.dropped, s.unplugs};
  return 0;
}

}  // extern "C"
