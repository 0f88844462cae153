#pragma once
// cvo-backendd's wiring: two named threads around libcvo's SLAM mapper (slam::Mapper, the same
// back end cvo-run --mode slam uses).
//
//   cvo-receive   LCM CVO_KEYFRAME / CVO_LOCAL_GRAPH (or their slices, CVO_KEYFRAME_CHUNK, put
//                 together first: slice_intake.hpp) -> decoded once and checked -> the door (each
//                 keyframe (session, id) and local graph once; a repeat with other content is
//                 refused, libcvo/store/message_door.hpp) -> appended to the keyframe store (durable before
//                 anything else happens) -> work queue, the decoded value (when it is full,
//                 only where the record lies in the store is queued, and it is read back and
//                 decoded in its turn); what never came of a session (a gap in its keyframe ids,
//                 a local graph or CVO_POSE naming an unknown keyframe) is asked for again on
//                 CVO_KEYFRAME_REQUEST (keyframe_gaps.hpp)
//   cvo-backend   work queue -> slam::Mapper (loop detection across every session, joins,
//                 keyframe-graph optimisation) -> after each change CVO_MAP_CORRECTION for each
//                 session whose entry changed (O(1) bytes each), each live session's again once a
//                 status period, a session's at once when the store holds more of it than it was
//                 told (held_prefix.hpp; between two records), and the full CVO_MAP at most once
//                 backendd.map_period_s while it changes, at once after a join, within a second
//                 after a loop closure (map_schedule.hpp); beside it
//                 mapping::Mapping, each keyframe's local map placed at the poses of each full map
//                 -> CVO_GRID (the poses of a CVO_MAP sent) at most once a second while it changes,
//                 at once with a loop's map when it moved keyframes; CVO_STATUS once a period
//
// At start-up the store is read back and every record goes through the same door and path, so a
// restart resumes every session received before; what they make goes out once every one is in
// (the full CVO_MAP and each session's CVO_MAP_CORRECTION), not after each: a tracker sees the
// restarted back end's revisions leap once, in its new epoch.
//
// A signal stop ends within backendd.stop_timeout_s (below the unit's TimeoutStopSec), whatever
// waits: records are applied during its first half; what still waits then is left, since every
// record is in the store before it is queued, and the next start's replay applies it (in
// localization mode a live session's records are never stored: they are a visitor's, and it
// localizes again). The final global optimisation gets the time up to the last quarter, cut short
// at its last accepted step (or skipped) when that runs out; the last quarter publishes the final
// corrections, map and grid. A log that ended (exit_on_eof) is worked through whole.
//
// Localization (backendd.mode localization): the store is only read (read_store, as cvo-map reads
// it: never written, renamed or cut back), its records are the map; once they are applied the
// final global optimisation runs and the mapper becomes read only (slam::Mapper::localize_only).
// Every new session is localized in it; its keyframes are never stored and make no grid, and the
// grid published is the stored map's. A CVO_POSE whose state is LOST marks its session lost (and any
// CVO_POSE keeps its session live for the re-sent corrections). On SIGTERM/SIGINT/SIGHUP: what is
// already in the socket is taken in, the queue is drained, a final global optimisation runs, the
// changed corrections and the final CVO_MAP are published, then the final CVO_GRID, exit 0. No
// record can stop the daemon: what the mapper cannot apply is noted and skipped, and so is a
// record or step it fails on (record_guard.hpp), never the process or the map. CVO_STATUS counts
// them: records the mapper refused in bad_messages[BAD_CONTENT], records and steps skipped after a
// failure of the back end's own in failed_frames.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "cvo_lcm/keyframe_request_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "daemon/backendd/held_prefix.hpp"
#include "daemon/backendd/keyframe_gaps.hpp"
#include "daemon/backendd/record_guard.hpp"
#include "daemon/backendd/record_quota.hpp"
#include "daemon/backendd/slice_intake.hpp"
#include "daemon/backendd/work_queue.hpp"
#include "daemon/common/bus_auth.hpp"
#include "daemon/common/heartbeat.hpp"
#include "daemon/common/notes.hpp"
#include "daemon/common/systemd_notify.hpp"
#include "libcvo/config/config.hpp"
#include "libcvo/lcm/chunks.hpp"
#include "libcvo/store/keyframe_store.hpp"
#include "libcvo/store/message_door.hpp"
#include "libcvo/store/replay.hpp"

namespace lcm {
class LCM;
}
namespace cvo::slam {
struct Map;
}

namespace cvo::daemon::backendd {

class Backendd {
 public:
  /// Opens the store (recovering its records) and the LCM provider, loads the vocabulary; throws
  /// io::InputError naming what is wrong.
  explicit Backendd(config::Config config);
  ~Backendd();
  Backendd(const Backendd&) = delete;
  Backendd& operator=(const Backendd&) = delete;

  /// Runs until SIGTERM/SIGINT; returns the exit status. block_stop_signals() must have been
  /// called before.
  int run();

 private:
  struct Work;
  // A tracker said its session's odometry failed (CVO_POSE state LOST).
  struct LostSession {
    core::SessionId session = 0;
  };
  // A record decoded once: received, its value (decoded and checked at the door); replayed from
  // the store, its message (decoded at the door, its images decoded in its turn, so that a long
  // store is not held decoded) or its merge; waiting in the store (the queue was full), only where
  // it lies (read back and decoded in its turn: what waits there is not held in memory at all).
  struct QueuedRecord {
    std::variant<store::RecordValue, store::Identified, store::RecordRef, LostSession, slam::KeyframeMerge,
                 slam::SettledEdge, slam::SessionTally>
        content;
    std::optional<std::chrono::steady_clock::time_point> arrived;  // nullopt: replayed from the store
    std::optional<store::RecordRef> stored{};  // where its record lies in the store (garbage once merged)
  };

  void let_in_recovered(std::vector<store::StoredRecord> recovered);
  void receive_loop();
  // `sender`: the verified sender (auth_t; 0 on an open bus), for
  // what is said of a refusal and for per-sender bounds.
  void receive(store::RecordKind kind, const std::uint8_t* data, std::size_t size, std::int64_t sender);
  // The verified sender of an authentic, new buffer (cvo-receive); nullopt, counted by kind, when not.
  std::optional<std::int64_t> authentic(auth::Verifier& verifier, const std::string& channel, const void* data,
                                        std::size_t size);
  template <class Message>
  std::optional<Message> decoded(const void* data, std::size_t size, const char* channel);
  void receive_slice(const void* data, std::size_t size, std::int64_t sender);
  void count_strangers_dropped();
  [[nodiscard]] cvo_lcm::keyframe_request_t request_message(const KeyframeGaps::Request& request) const;
  void saw_pose(const void* data, std::size_t size);
  void saw_status(const void* data, std::size_t size);
  void ask_for_missing(::lcm::LCM& lcm, bool stopping);
  static GapPolicy gap_policy(const config::Config& config);
  void note_store_change();
  void retry_store(bool final);
  void work_loop();
  void process(QueuedRecord& queued);
  void process_record(QueuedRecord& queued);
  void localize_when_stored();
  void settle();
  void replayed();
  void read_map_store();
  std::optional<store::RecordValue> value_of(QueuedRecord& queued, std::string* error);
  void apply_keyframe(const lcm::Keyframe& keyframe, const QueuedRecord& queued);
  void apply_merge(const slam::KeyframeMerge& merge, const std::optional<store::RecordRef>& stored);
  void apply_settled(const slam::SettledEdge& edge, const std::optional<store::RecordRef>& stored);
  // A keyframe the mapper merged: its merge into the store, its own record discarded (libcvo/store/store_merges.hpp).
  void store_merge(const slam::KeyframeMerge& merge, bool replayed);
  void apply_local_graph(const store::LocalGraphRecord& record, const QueuedRecord& queued);
  // After a change that may have touched `touched` only (nullopt: every session): the corrections
  // that changed, the full map when due (map_schedule.hpp).
  void publish_changes(std::optional<core::SessionId> touched, const std::vector<std::int64_t>& joined,
                       bool after_loop);
  // Those of `sessions` whose entry changed (`again`: each, changed or not).
  void publish_corrections(const std::vector<core::SessionId>& sessions, bool again);
  void publish_due();  // the full map once its period has passed, corrections again: live or newly held sessions'
  void publish_map(const std::vector<std::int64_t>& joined, bool after_loop);
  void place_in_grid(const slam::Map& map, bool after_loop);
  void publish_grid(bool after_loop);
  void publish_status(std::int8_t state);
  void finish();
  void final_optimisation();
  void closing_notes();
  // Seconds left of a signal stop's budget (backendd.stop_timeout_s from the signal); infinity when
  // no signal stop is under way (a log that ended is worked through whole).
  [[nodiscard]] double stop_time_left() const;
  void leave_waiting_records();
  void start_localizing();
  [[nodiscard]] bool localization() const { return config_.backendd.mode == "localization"; }

  config::Config config_;
  Notes notes_{"cvo-backendd"};                // the journal and CVO_STATUS's detail, at one log-rate policy
  RecordGuard guard_{notes_};                  // cvo-backend only: each record and step costs at most itself
  BusAuth bus_{config_.auth, "cvo-backendd"};  // the key ring (auth.key_file) and signer, all threads
  SystemdNotifier systemd_;
  std::unique_ptr<store::KeyframeStore> store_;  // none in localization mode: the store is only read
  std::vector<store::StoredRecord> recovered_;
  // cvo-receive only: whether the store was failing when last noted, and when held records were
  // last retried.
  bool store_failing_ = false;
  std::chrono::steady_clock::time_point store_retried_{};
  store::MessageDoor door_;  // cvo-receive only (filled from the store before it starts)
  RecordQuota quota_{config_.backendd.max_records_per_session, config_.backendd.max_records_per_sender};  // the same
  KeyframeGaps gaps_{gap_policy(config_)};  // cvo-receive only (filled from the store as well)
  HeldPrefix held_;     // what is acknowledged of each session: cvo-receive marks, cvo-backend reads
  SliceIntake slices_;  // cvo-receive only: messages that came in part (CVO_KEYFRAME_CHUNK)
  // cvo-receive only: local graphs put together before their keyframe, let in after it.
  struct EarlyGraph {
    std::vector<std::uint8_t> message;
    std::int64_t sender = 0;
  };
  using KeyframeName = std::pair<std::int64_t, std::int64_t>;  // session, id
  static constexpr std::size_t kMaxEarlyGraphs = 64;
  std::map<KeyframeName, EarlyGraph> early_graphs_;
  std::unique_ptr<Work> work_;  // the mapper and what the daemon reports of it; cvo-backend only

  WorkQueue<QueuedRecord> queue_;  // cvo-receive -> cvo-backend
  std::atomic<bool> stop_{false}, receiver_done_{false};
  std::atomic<bool> input_ended_{false};  // a file:// input log was read to its end
  // When a signal stop must be over (steady clock ticks); max: no signal stop. Set by run().
  std::atomic<std::chrono::steady_clock::rep> stop_deadline_{
      std::chrono::steady_clock::time_point::max().time_since_epoch().count()};
  std::atomic<std::int64_t> queue_drops_{0};
  std::atomic<std::int64_t> replayed_pending_{0};  // records of the store not applied yet
  // Records that found the queue full and wait in the store instead (queued by reference), now
  // and in all: a back end slower than its trackers loses nothing and holds no more in memory.
  std::atomic<std::int64_t> waiting_in_store_{0}, waited_in_store_{0};
  std::atomic<std::int64_t> bad_messages_[cvo_lcm::status_t::NUM_BAD_KINDS]{};
  // Keyframes lost in transport (gaps_'s counts, for CVO_STATUS): asked for, recovered, given up.
  std::atomic<std::int64_t> keyframes_requested_{0}, keyframes_recovered_{0}, keyframes_lost_{0};
  // Sessions whose CVO_POSE came since cvo-backend last looked (cvo-receive -> cvo-backend): live.
  std::mutex posed_mutex_;
  std::map<core::SessionId, std::chrono::steady_clock::time_point> posed_;
  Heartbeat receive_heartbeat_, work_heartbeat_;
};

}  // namespace cvo::daemon::backendd
