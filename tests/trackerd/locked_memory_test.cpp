// lock_all_memory (daemon/common/realtime.hpp) locks the working set, not the address space: memory
// the process touches after the call stays resident and locked; memory it only maps is not faulted
// in. Its own program: mlockall holds for the whole process.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "daemon/common/realtime.hpp"

// Under AddressSanitizer (GCC defines __SANITIZE_ADDRESS__, clang has the feature) the test cannot
// hold: the runtime maps terabytes of shadow memory and touches its own pages, so what mlockall pins
// is not the program's working set.
#if defined(__SANITIZE_ADDRESS__)
#define CVO_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CVO_UNDER_ASAN 1
#endif
#endif

namespace cvo::daemon {
namespace {

constexpr std::size_t kBytes = std::size_t{32} << 20;

// An anonymous mapping of its own, as the tracker's large buffers are (malloc maps them).
struct Mapping {
  Mapping()
      : data(static_cast<std::uint8_t*>(
            mmap(nullptr, kBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0))) {}
  ~Mapping() { munmap(data, kBytes); }
  Mapping(const Mapping&) = delete;
  Mapping& operator=(const Mapping&) = delete;
  std::uint8_t* data;
};

std::size_t resident_bytes_of(const Mapping& m) {
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  std::vector<unsigned char> in_core(kBytes / page);
  if (mincore(m.data, kBytes, in_core.data()) != 0) return 0;
  std::size_t pages = 0;
  for (const unsigned char c : in_core) pages += c & 1U;
  return pages * page;
}

// "Locked:" of the mapping that holds `address` (/proc/self/smaps: locked resident bytes).
std::size_t locked_bytes_at(const void* address) {
  std::ifstream smaps("/proc/self/smaps");
  const auto a = reinterpret_cast<std::uintptr_t>(address);
  bool inside = false;
  for (std::string line; std::getline(smaps, line);) {
    unsigned long long begin = 0, end = 0;
    if (std::sscanf(line.c_str(), "%llx-%llx ", &begin, &end) == 2) {  // a mapping's first line
      inside = begin <= a && a < end;
    } else if (inside && line.rfind("Locked:", 0) == 0) {
      std::istringstream fields(line.substr(7));
      std::size_t kib = 0;
      fields >> kib;
      return kib * 1024;
    }
  }
  return 0;
}

TEST(LockAllMemory, KeepsWhatTheProcessTouchesLockedAndDoesNotFaultInWhatItOnlyMaps) {
#ifdef CVO_UNDER_ASAN
  GTEST_SKIP() << "under AddressSanitizer: its shadow memory and runtime make what mlockall locks and faults in "
                  "differ from the program's own working set";
#endif
  if (const std::string why = lock_all_memory(); !why.empty()) GTEST_SKIP() << why;
  const Mapping touched, untouched;
  ASSERT_NE(touched.data, MAP_FAILED);
  ASSERT_NE(untouched.data, MAP_FAILED);
  std::memset(touched.data, 1, kBytes);

  EXPECT_EQ(resident_bytes_of(touched), kBytes);
  EXPECT_GE(locked_bytes_at(touched.data), kBytes) << "the buffer the process wrote is not locked";
  EXPECT_EQ(resident_bytes_of(untouched), 0U) << "mapped memory was faulted in: every mapping is pinned whole";
  munlockall();
}

}  // namespace
}  // namespace cvo::daemon
