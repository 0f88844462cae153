#pragma once
// The C library's own functions behind the ones the emulator interposes (the next definition in
// the lookup order: libc, or a sanitizer runtime loaded before it). The emulator's own memory,
// eventfds and memfds go through these, never through its interposers.
#include <poll.h>
#include <sys/types.h>

#include <cstddef>

namespace cvo::drivers::v4l2_emulator {

struct Libc {
  int (*open)(const char*, int, ...);
  int (*openat)(int, const char*, int, ...);
  int (*close)(int);
  int (*ioctl)(int, unsigned long, ...);
  void* (*mmap)(void*, std::size_t, int, int, int, off_t);
  int (*munmap)(void*, std::size_t);
  int (*poll)(pollfd*, nfds_t, int);
  ssize_t (*read)(int, void*, std::size_t);
};

/// Resolved once (dlsym RTLD_NEXT), from any thread.
const Libc& libc();

}  // namespace cvo::drivers::v4l2_emulator
