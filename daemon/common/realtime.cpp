#include "daemon/common/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace cvo::daemon {

void name_this_thread(const char* name) { pthread_setname_np(pthread_self(), name); }

std::string make_this_thread_realtime(int priority) {
  sched_param param{};
  param.sched_priority = priority;
  if (const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param); error != 0)
    return "SCHED_FIFO priority " + std::to_string(priority) + ": " + std::strerror(error) +
           " (needs CAP_SYS_NICE or LimitRTPRIO >= the priority)";
  return {};
}

std::string pin_this_thread(int cpu) {
  if (cpu < 0 || cpu >= CPU_SETSIZE) return "CPU " + std::to_string(cpu) + " is out of range";
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  if (const int error = pthread_setaffinity_np(pthread_self(), sizeof set, &set); error != 0)
    return "affinity to CPU " + std::to_string(cpu) + ": " + std::strerror(error);
  return {};
}

std::string lock_all_memory() {
  if (mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT) != 0 &&
      (errno != EINVAL || mlockall(MCL_CURRENT | MCL_FUTURE) != 0))
    return std::string("mlockall: ") + std::strerror(errno) + " (needs CAP_IPC_LOCK or LimitMEMLOCK=infinity)";
  return {};
}

long long resident_bytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0;
  long long pages_total = 0, pages_resident = 0;
  const bool ok = std::fscanf(f, "%lld %lld", &pages_total, &pages_resident) == 2;
  std::fclose(f);
  return ok ? pages_resident * sysconf(_SC_PAGESIZE) : 0;
}

}  // namespace cvo::daemon
