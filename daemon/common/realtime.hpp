#pragma once
// Thread and process set-up of a realtime daemon. Each call reports failure as a message rather
// than failing: a daemon without the privilege for SCHED_FIFO or mlockall still works, just with
// weaker timing guarantees, and says so once.
#include <string>

namespace cvo::daemon {

/// Names the calling thread (pthread_setname_np; at most 15 characters), so profilers, top -H
/// and allocation counters attribute its work: "cvo-acquire", "cvo-track", "cvo-publish".
void name_this_thread(const char* name);

/// SCHED_FIFO at `priority` (1..99) for the calling thread; "" on success, else why not
/// (typically EPERM: no CAP_SYS_NICE and RLIMIT_RTPRIO below the priority).
std::string make_this_thread_realtime(int priority);

/// Pins the calling thread to one CPU; "" on success, else why not.
std::string pin_this_thread(int cpu);

/// mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT): every page this process touches stays
/// resident from then on, so the tracking path, once it has run, never waits for a page to come
/// back from swap or disk; "" on success, else why not (RLIMIT_MEMLOCK too small without
/// CAP_IPC_LOCK).
/// Why on fault: without MCL_ONFAULT, mlockall faults in and pins every page of every mapping,
/// including all of each shared library's code, most of which the process never runs, and each
/// thread's whole stack reservation; the daemon's resident size becomes the size of its address
/// space. With it, what is locked is the working set: the code and data the tracking path has
/// touched, which the warm-up frames (trackerd.warmup_frames) fault in before allocations and
/// deadlines count; after warm-up the tracking thread allocates nothing, so it meets no new
/// memory. A kernel without MCL_ONFAULT (before Linux 4.4) gets the old lock-everything call.
std::string lock_all_memory();

/// Resident set size of this process in bytes (from /proc/self/statm), 0 when unknown.
long long resident_bytes();

}  // namespace cvo::daemon
