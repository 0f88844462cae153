#pragma once
// What cvo-backendd's two threads share, and who writes each part. Everything else belongs to one
// thread's class: Receiving (receiving.hpp, cvo-receive) and MapBuilding (map_building.hpp,
// cvo-backend, which publishes through its Publishing, publishing.hpp); Backendd (backendd.hpp)
// owns this and supervises them.
//
//   config                    made before the threads start, read only
//   notes, bus, systemd       thread-safe (the key ring and signer; READY from the supervisor,
//                             STATUS from cvo-backend)
//   store                     made before the threads start (none in localization mode); thread-safe:
//                             cvo-receive appends, cvo-backend reads back, discards, reads health()
//   held                      thread-safe: cvo-receive marks, cvo-backend reads (held_prefix.hpp)
//   queue                     cvo-receive (and the replay before the threads start) -> cvo-backend
//   posed                     cvo-receive marks sessions live, cvo-backend takes them
//   counters                  each written by one thread (the bad messages by cvo-receive), read by
//                             cvo-backend for CVO_STATUS; waiting_in_store by both (atomic)
//   heartbeats, flags         one writer each; stop_deadline by the supervisor
#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <variant>

#include "cvo_lcm/status_t.hpp"
#include "daemon/backendd/held_prefix.hpp"
#include "daemon/backendd/work_queue.hpp"
#include "daemon/common/bus_auth.hpp"
#include "daemon/common/heartbeat.hpp"
#include "daemon/common/notes.hpp"
#include "daemon/common/systemd_notify.hpp"
#include "libcvo/config/config.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/slam/mapper.hpp"
#include "libcvo/store/keyframe_store.hpp"
#include "libcvo/store/message_door.hpp"

namespace cvo::daemon::backendd {

using Clock = std::chrono::steady_clock;

/// Whether `url` is a recording (file://): it ends, and it cannot be asked again.
inline bool is_log(const std::string& url) { return url.starts_with("file://"); }
/// Where CVO_MAP_CORRECTION, CVO_MAP and CVO_STATUS go: the input's provider unless told otherwise
/// (a file:// log that is read cannot take them).
std::string publish_url(const config::BackenddParameters& b);
/// "keyframe 12 of session 0x…", for notes.
std::string keyframe_name(core::SessionId session, std::int64_t id);

// A tracker said its session's odometry failed (CVO_POSE state LOST).
struct LostSession {
  core::SessionId session = 0;
};

// A record decoded once: received, its value (decoded and checked at the door); replayed from the
// store, its message (decoded at the door, its images decoded in its turn, so that a long store is
// not held decoded) or its merge; waiting in the store (the queue was full), only where it lies
// (read back and decoded in its turn: what waits there is not held in memory at all).
struct QueuedRecord {
  std::variant<store::RecordValue, store::Identified, store::RecordRef, LostSession, slam::KeyframeMerge,
               slam::SettledEdge, slam::SessionTally>
      content;
  std::optional<Clock::time_point> arrived;  // nullopt: replayed from the store
  std::optional<store::RecordRef> stored{};  // where its record lies in the store (garbage once merged)
};

// Sessions whose CVO_POSE or CVO_STATUS came since cvo-backend last looked: live.
class PosedSessions {
 public:
  void live(core::SessionId session, Clock::time_point at) {
    const std::lock_guard lock(mutex_);
    posed_[session] = at;
  }
  void lost(core::SessionId session) {  // its tracker has moved on to a new session
    const std::lock_guard lock(mutex_);
    posed_.erase(session);
  }
  [[nodiscard]] std::map<core::SessionId, Clock::time_point> take() {
    const std::lock_guard lock(mutex_);
    return std::exchange(posed_, {});
  }

 private:
  std::mutex mutex_;
  std::map<core::SessionId, Clock::time_point> posed_;
};

struct Counters {
  std::atomic<std::int64_t> bad_messages[cvo_lcm::status_t::NUM_BAD_KINDS]{};
  std::atomic<std::int64_t> queue_drops{0};
  std::atomic<std::int64_t> replayed_pending{0};  // records of the store not applied yet
  // Records that found the queue full and wait in the store instead (queued by reference), now
  // and in all: a back end slower than its trackers loses nothing and holds no more in memory.
  std::atomic<std::int64_t> waiting_in_store{0}, waited_in_store{0};
  // Keyframes lost in transport (KeyframeGaps's counts): asked for, recovered, given up.
  std::atomic<std::int64_t> keyframes_requested{0}, keyframes_recovered{0}, keyframes_lost{0};
};

struct Shared {
  explicit Shared(config::Config c);

  [[nodiscard]] bool localization() const { return config.backendd.mode == "localization"; }
  // Seconds left of a signal stop's budget (backendd.stop_timeout_s from the signal); infinity when
  // no signal stop is under way (a log that ended is worked through whole).
  [[nodiscard]] double stop_time_left() const;

  const config::Config config;
  Notes notes{"cvo-backendd"};  // the journal and CVO_STATUS's detail, at one log-rate policy
  BusAuth bus;                  // the key ring (auth.key_file) and signer
  SystemdNotifier systemd;
  std::unique_ptr<store::KeyframeStore> store;  // none in localization mode: the store is only read
  HeldPrefix held;                              // what is acknowledged of each session
  WorkQueue<QueuedRecord> queue;
  PosedSessions posed;
  Counters counters;
  Heartbeat receive_heartbeat, work_heartbeat;
  std::atomic<bool> stop{false}, receiver_done{false};
  std::atomic<bool> input_ended{false};  // a file:// input log was read to its end
  // When a signal stop must be over (steady clock ticks); max: no signal stop.
  std::atomic<Clock::rep> stop_deadline{Clock::time_point::max().time_since_epoch().count()};
};

}  // namespace cvo::daemon::backendd
