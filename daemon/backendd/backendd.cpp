#include "daemon/backendd/backendd.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <limits>
#include <thread>
#include <utility>
#include <variant>

#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/grid_t.hpp"
#include "cvo_lcm/keyframe_chunk_t.hpp"
#include "cvo_lcm/keyframe_request_t.hpp"
#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/local_graph_t.hpp"
#include "cvo_lcm/map_correction_t.hpp"
#include "cvo_lcm/map_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "daemon/backendd/map_schedule.hpp"
#include "daemon/common/realtime.hpp"
#include "daemon/common/signals.hpp"
#include "daemon/common/status.hpp"
#include "daemon/common/supervise.hpp"
#include "libcvo/auth/authenticator.hpp"
#include "libcvo/auth/lcm_publish.hpp"
#include "libcvo/config/mapper_parameters.hpp"
#include "libcvo/config/module_parameters.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/core/units.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/grid_conversion.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/lcm/local_graph_conversion.hpp"
#include "libcvo/lcm/map_conversion.hpp"
#include "libcvo/lcm/map_correction_conversion.hpp"
#include "libcvo/lcm/tracker_messages.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/mapping/mapping.hpp"
#include "libcvo/slam/map_robots.hpp"
#include "libcvo/slam/mapper.hpp"
#include "libcvo/store/merge_record.hpp"
#include "libcvo/store/store_merges.hpp"

namespace cvo::daemon::backendd {

namespace {

// Why the back end stopped asking for keyframes (KeyframeGaps::GivenUp::Reason), for its note.
std::string why_given_up(KeyframeGaps::GivenUp::Reason reason) {
  using Reason = KeyframeGaps::GivenUp::Reason;
  switch (reason) {
    case Reason::kSilent: return "asked again, and its tracker is no longer heard";
    case Reason::kUnanswered: return "asked again while its tracker ran, with no answer: it no longer holds them";
    case Reason::kNoAsking: return "a recording cannot be asked again";
    case Reason::kBounds: return "beyond what is waited for (a gap older than any tracker keeps, or too many)";
    case Reason::kStopped: return "the back end stopped while waiting";
  }
  return "unknown";
}

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
constexpr const char* kProcess = "cvo-backendd";
// At a stop, messages already in the socket are taken in; a tracker that is still sending must
// not keep the drain going for ever.
constexpr int kMaxDrainMessages = 10000;
// CVO_KEYFRAME_CHUNKs LCM may hold for cvo-receive: 32 keyframes' slices (~12 MB of datagrams).
constexpr int kSliceQueue = 32 * 256;
// Records that may wait in the store for the back end (each queued as a few bytes): hours of a
// tracker's keyframes; beyond it live input is refused and counted (queue_drops).
constexpr std::int64_t kMaxWaitingInStore = 16384;
// CVO_GRID at most this often while the grid changes (a loop closure's goes out at once): a grid
// is tens of kilobytes, and a planner replans on each.
constexpr auto kGridPeriod = 1s;
// A session whose tracker said nothing (no record, no CVO_POSE) for this long is no longer live: its
// correction is not sent again.
constexpr auto kLiveFor = 10s;
// A signal stop's budget (backendd.stop_timeout_s), in shares of it: records are applied while
// more than kApplyUntil of it is left, the final optimisation runs until kPublishIn is left, which
// publishes the final corrections, map and grid.
constexpr double kApplyUntil = 0.5;
constexpr double kPublishIn = 0.25;

std::string fixed(double value, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, value);
  return text;
}

// Where CVO_MAP_CORRECTION, CVO_MAP and CVO_STATUS go: the input's provider unless told otherwise
// (a file:// log that is read cannot take them).
std::string publish_url(const config::BackenddParameters& b) {
  return b.publish_url == "lcm_url" ? b.lcm_url : b.publish_url;
}

bool is_log(const std::string& url) { return url.starts_with("file://"); }

std::string keyframe_name(core::SessionId session, std::int64_t id) {
  return describe(store::MessageKey{store::RecordKind::kKeyframe, session, id});
}

// What CVO_STATUS, systemd and the closing note say of the map.
struct MapSummary {
  std::size_t sessions = 0, placed = 0, keyframes = 0, loops = 0, loops_across = 0;
  std::uint64_t revision = 0;
};

MapSummary summarise(const slam::Map& map) {
  MapSummary s;
  s.sessions = map.sessions.size();
  s.placed = static_cast<std::size_t>(
      std::count_if(map.sessions.begin(), map.sessions.end(), [](const auto& m) { return m.placed; }));
  s.keyframes = map.keyframes.size();
  s.loops = map.loops.size();
  s.loops_across = static_cast<std::size_t>(
      std::count_if(map.loops.begin(), map.loops.end(), [](const auto& l) { return l.from_session != l.to_session; }));
  s.revision = map.revision;
  return s;
}

std::string text(const MapSummary& s) {
  return std::to_string(s.sessions) + " sessions (" + std::to_string(s.placed) + " placed), " +
         std::to_string(s.keyframes) + " keyframes, " + std::to_string(s.loops) + " loops (" +
         std::to_string(s.loops_across) + " across sessions), map revision " + std::to_string(s.revision);
}

// What a channel of the map has sent: messages and their encoded bytes (the last, the largest), for
// systemd's STATUS and the closing note.
struct Sent {
  std::size_t messages = 0, bytes_last = 0, bytes_max = 0;
  void add(std::size_t bytes) {
    ++messages;
    bytes_last = bytes;
    bytes_max = std::max(bytes_max, bytes);
  }
};

std::string text(const char* channel, const Sent& s) {
  return std::to_string(s.messages) + " " + channel + " sent (" + std::to_string(s.bytes_last) + " bytes the last, " +
         std::to_string(s.bytes_max) + " at most)";
}

// What CVO_GRID has sent, and what the mapping costs, for CVO_STATUS, systemd and the closing note.
struct GridSummary {
  std::optional<Clock::time_point> last;  // when the last CVO_GRID went
  std::int64_t revision = -1;             // of the last CVO_GRID
  std::size_t published = 0, bytes = 0;   // CVO_GRIDs sent; the last one's encoded size
  std::size_t not_mapped = 0;             // keyframes the mapping refused
  std::size_t places = 0;                 // place() calls that changed the grid
  double place_ms_total = 0, place_ms_max = 0;
};

std::string text(const GridSummary& g, const mapping::MappingStatistics& s) {
  if (g.published == 0) return "no grid yet (" + std::to_string(s.keyframes) + " keyframes mapped)";
  return "grid revision " + std::to_string(g.revision) + " (" + std::to_string(s.placed) + " of " +
         std::to_string(s.keyframes) + " keyframes mapped, " + fixed(static_cast<double>(s.local_map_bytes) / 1e6, 1) +
         " MB of local maps, " + std::to_string(g.bytes) + " bytes on CVO_GRID)";
}

// How long a new session took to find its place in the map, after its first keyframe: in sensor
// time (what the robot had to see) and on this machine (what the back end took, with its queue).
std::string join_text(const slam::Map& map, core::SessionId session, std::optional<Clock::time_point> first_arrival) {
  const auto s =
      std::find_if(map.sessions.begin(), map.sessions.end(), [&](const auto& m) { return m.session == session; });
  const std::int64_t at = s != map.sessions.end() ? s->joined_at_keyframe : -1;
  if (s != map.sessions.end() && s->visitor) {  // its keyframes are in no map: arrival time only
    std::string out =
        "session " + core::session_name(session) + " localized in the stored map at its keyframe " + std::to_string(at);
    if (!first_arrival) return out;
    return out + " (" + fixed(std::chrono::duration<double>(Clock::now() - *first_arrival).count(), 2) +
           " s after its first keyframe arrived)";
  }
  double first = std::numeric_limits<double>::quiet_NaN(), joined = first;
  for (const auto& k : map.keyframes) {
    if (k.session != session) continue;
    if (std::isnan(first)) first = k.timestamp;  // by id: the session's first keyframe
    if (k.id == at) joined = k.timestamp;
  }
  // A revisit's keyframes may all be merged into the map's already: then the map lists none of its.
  const std::string sensor_time = std::isnan(joined - first)
                                      ? "its keyframes merged into the map's"
                                      : fixed(joined - first, 2) + " s of sensor time after its first keyframe";
  std::string out = "session " + core::session_name(session) + " joined the map at its keyframe " + std::to_string(at) +
                    " (" + sensor_time + ", ";
  if (!first_arrival) return out + "its first keyframe replayed from the store)";
  return out + fixed(std::chrono::duration<double>(Clock::now() - *first_arrival).count(), 2) +
         " s after its first keyframe arrived)";
}

// The sender a stored record was received from: its auth_t trailer's (verified when it came;
// zero on an open bus), for the bounds per sender across restarts.
std::int64_t stored_sender(const std::vector<std::uint8_t>& payload) {
  return payload.size() >= auth::kTrailerBytes ? auth::read_trailer(payload.data(), payload.size()).sender : 0;
}

}  // namespace

// Everything the cvo-backend thread owns.
struct Backendd::Work {
  Work(loop_closure::Vocabulary vocabulary, const config::Config& config)
      : mapper(std::move(vocabulary), config::mapper_parameters(config)),
        mapping(config.mapping),
        lcm(publish_url(config.backendd)),
        schedule({std::chrono::duration<double>(config.backendd.map_period_s),
                  std::chrono::duration<double>(config.backendd.status_period_s), kLiveFor, kGridPeriod}) {}

  slam::Mapper mapper;
  mapping::Mapping mapping;                 // the occupancy grid of the mapper's map (CVO_GRID)
  ::lcm::LCM lcm;                           // CVO_MAP_CORRECTION, CVO_MAP, CVO_GRID and CVO_STATUS
  MapSchedule schedule;                     // when which of the map goes out
  std::size_t optimisations = 0;            // the mapper's when corrections last went out
  Sent corrections, maps;                   // CVO_MAP_CORRECTION, CVO_MAP
  std::vector<std::int64_t> replay_joined;  // sessions the store's records joined, noted with its map
  // CVO_MAP's epoch: revisions count from the start of this process, and a tracker takes a newer
  // epoch's maps after a restart of the back end instead of refusing them as stale.
  const std::int64_t epoch = core::wall_utime();
  // When each session's first keyframe arrived (nullopt: it was replayed from the store).
  std::map<core::SessionId, std::optional<Clock::time_point>> first_arrival;
  std::vector<std::string> joins;  // every join noted, repeated in the closing note
  MapSummary summary;              // of the last map published
  GridSummary grid;
  std::optional<store::StoreMerges> merges;  // none in localization mode: the store is only read
  bool grid_due = false;                     // the grid changed since the last CVO_GRID
  std::int64_t local_graphs = 0, processed = 0, processed_at_last_status = 0;
  Clock::time_point last_status = Clock::now();
};

Backendd::Backendd(config::Config config) : config_(std::move(config)), queue_(config_.backendd.queue_max) {
  const auto& b = config_.backendd;
  if (b.exit_on_eof && !is_log(b.lcm_url))
    throw io::InputError("backendd.exit_on_eof", "needs a file:// lcm_url (a log that ends), not '" + b.lcm_url + "'");
  // cvo-receive opens its own provider in its thread: one that cannot open would leave it deaf for
  // good (publish_url's check below sees lcm_url only when the two are one).
  if (!::lcm::LCM(b.lcm_url).good())
    throw io::InputError("backendd.lcm_url", "cannot open LCM provider '" + b.lcm_url + "'");
  work_ = std::make_unique<Work>(loop_closure::Vocabulary::load(store::resolve_vocabulary(b.vocabulary)), config_);
  if (!work_->lcm.good())
    throw io::InputError(b.publish_url == "lcm_url" ? "backendd.lcm_url" : "backendd.publish_url",
                         "cannot open LCM provider '" + publish_url(b) + "'");
  if (localization()) {
    read_map_store();
    return;
  }
  std::string warning;
  store_ = std::make_unique<store::KeyframeStore>(b.store, recovered_, warning, b.unsaved_records_max);
  if (!warning.empty()) notes_.note("warning: " + warning);
  work_->merges.emplace(*store_);
  note_store_change();  // a new store on a full disk: started degraded
}

// The stored map, read without changing a byte of it; damage costs only the records it touches.
void Backendd::read_map_store() {
  const auto& file = config_.backendd.store;
  if (!std::filesystem::exists(file))
    throw io::InputError("backendd.store", "no keyframe store '" + file + "': localization needs a stored map");
  const store::StoreSnapshot snapshot = store::read_store(file);
  if (!snapshot.scan.clean())
    notes_.note("warning: " + store::describe_damage(file, snapshot.scan, "a write under way", "it is left out"));
  for (const auto& r : snapshot.scan.records) {
    const std::uint8_t* payload = snapshot.payload(r);
    recovered_.push_back({r.kind, {payload, payload + store::StoreSnapshot::payload_bytes(r)}});
  }
}

Backendd::~Backendd() = default;

int Backendd::run() {
  const auto recovered = recovered_.size();
  let_in_recovered(std::exchange(recovered_, {}));
  notes_.note(bus_.describe());
  notes_.note((localization() ? "localization in the map of " : "store ") + config_.backendd.store + " (" +
              std::to_string(recovered) + " records " + (localization() ? "read" : "recovered") + "), LCM " +
              config_.backendd.lcm_url);
  std::thread receive([this] { receive_loop(); });
  std::thread work([this] { work_loop(); });
  systemd_.ready();
  // The worker may be inside a long optimisation: allow it the watchdog's full interval.
  const Heartbeat* const beats[] = {&receive_heartbeat_, &work_heartbeat_};
  const auto ended = [&] { return input_ended_ && config_.backendd.exit_on_eof; };
  if (const auto signal = supervise(systemd_, {beats, 30s}, ended)) {
    const auto budget =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(config_.backendd.stop_timeout_s));
    stop_deadline_ = (Clock::now() + budget).time_since_epoch().count();
    notes_.note(std::string("stopping on ") + signal_name(*signal) + " within " +
                fixed(config_.backendd.stop_timeout_s, 1) + " s (backendd.stop_timeout_s)");
  }
  stop_ = true;
  receive.join();
  work.join();
  return 0;
}

// ---------------------------------------------------------------------------------------------
// cvo-receive: nothing but decoding, checking and storing, so that no message waits on the
// back end's work and every accepted record is on disk before it is used.

// The store's records pass the same door as received messages (replayed first, in order), so a
// store written before the door, or a damaged one, cannot feed the mapper a repeat.
void Backendd::let_in_recovered(std::vector<store::StoredRecord> recovered) {
  for (auto& record : recovered) {
    std::string why;
    // The back end's own records name no message: they do not pass the door.
    const auto queue_decoded = [&](auto decoded) {
      if (!decoded) return notes_.note_limited("stored skipped", "stored record skipped: " + why);
      ++replayed_pending_;
      queue_.push({std::move(*decoded), std::nullopt, record.where});
    };
    const auto* payload = record.payload.data();
    const auto size = record.payload.size();
    if (record.kind == store::RecordKind::kMerge) {
      auto merge = store::decode_merge(payload, size, &why);
      if (merge) held_.merged(merge->session, merge->id);
      queue_decoded(std::move(merge));
      continue;
    }
    if (record.kind == store::RecordKind::kSettled) {
      queue_decoded(store::decode_settled(payload, size, &why));
      continue;
    }
    if (record.kind == store::RecordKind::kTally) {
      queue_decoded(store::decode_tally(payload, size, &why));
      continue;
    }
    // A record of an older schema (another fingerprint or version), or a repeat, is skipped, said here.
    auto message = store::let_in_stored(door_, record.kind, record.payload.data(), record.payload.size(), &why);
    const std::int64_t sender = stored_sender(record.payload);
    record.payload = {};  // decoded: the message holds what the bytes did
    if (!message) {
      notes_.note_limited("stored skipped", why);
      continue;
    }
    const store::MessageKey key = message->key;
    quota_.count(key.session, sender);
    held_.held(key.session, key.id, key.kind == store::RecordKind::kLocalGraph);
    gaps_.seen(
        record.kind == store::RecordKind::kKeyframe ? KeyframeGaps::Seen::kKeyframe : KeyframeGaps::Seen::kLocalGraph,
        key.session, key.id, Clock::now());  // a gap in the store is asked for too
    ++replayed_pending_;
    queue_.push({std::move(*message), std::nullopt, record.where});
  }
}

void Backendd::receive_loop() {
  name_this_thread("cvo-receive");
  ::lcm::LCM lcm(config_.backendd.lcm_url);
  auth::Verifier verifier = bus_.verifier(config_.backendd.lcm_url);  // every buffer, before decoding
  struct Verified {  // every channel: its buffers verified first, then handed on with their sender
    Backendd* self;
    auth::Verifier* verifier;
    std::function<void(const void*, std::size_t, std::int64_t sender)> then;
    void handle(const ::lcm::ReceiveBuffer* buffer, const std::string& channel) {
      if (const auto sender = self->authentic(*verifier, channel, buffer->data, buffer->data_size))
        then(buffer->data, buffer->data_size, *sender);
    }
  };
  const auto record = [this](store::RecordKind kind) {
    return [this, kind](const void* data, std::size_t size, std::int64_t sender) {
      receive(kind, static_cast<const std::uint8_t*>(data), size, sender);
    };
  };
  Verified keyframes{this, &verifier, record(store::RecordKind::kKeyframe)},
      local_graphs{this, &verifier, record(store::RecordKind::kLocalGraph)},
      slices{this, &verifier, [this](const void*d, std::size_t n, std::int64_t s) { receive_slice(d, n, s); }},
      poses{this, &verifier, [this](const void*d, std::size_t n, std::int64_t) { saw_pose(d, n); }},
      statuses{this, &verifier, [this](const void*d, std::size_t n, std::int64_t) { saw_status(d, n); }};
  lcm.subscribe("CVO_KEYFRAME", &Verified::handle, &keyframes);
  lcm.subscribe("CVO_LOCAL_GRAPH", &Verified::handle, &local_graphs);
  // LCM drops what arrives for a subscription whose queue is full (30 messages by default): a
  // keyframe is a burst of ~200 slices, and several trackers' bursts may meet while a keyframe
  // completed is being stored.
  lcm.subscribe("CVO_KEYFRAME_CHUNK", &Verified::handle, &slices)->setQueueCapacity(kSliceQueue);
  lcm.subscribe("CVO_POSE", &Verified::handle, &poses);  // what the back end learns of a session
  lcm.subscribe("CVO_STATUS", &Verified::handle, &statuses);
  const bool log = is_log(config_.backendd.lcm_url);
  while (!stop_) {
    receive_heartbeat_.beat();
    retry_store(false);
    ask_for_missing(lcm, false);
    if (input_ended_) {  // a log that ended: nothing more will come; wait for the stop
      std::this_thread::sleep_for(50ms);
      continue;
    }
    if (lcm.handleTimeout(100) >= 0) continue;
    if (log) {
      notes_.note("end of " + config_.backendd.lcm_url + (config_.backendd.exit_on_eof ? ": finishing" : ""));
      input_ended_ = true;
      continue;
    }
    notes_.note_limited("receive failed", "LCM receive failed; retrying");
    std::this_thread::sleep_for(100ms);
  }
  // What is in the socket was sent before the stop (a tracker's last keyframe and local graph):
  // it is taken in and used too.
  for (int n = 0; !log && n < kMaxDrainMessages && lcm.handleTimeout(0) > 0; ++n) {
  }
  retry_store(true);
  ask_for_missing(lcm, true);
  receiver_done_ = true;
}

std::optional<std::int64_t> Backendd::authentic(auth::Verifier& verifier, const std::string& channel, const void* data,
                                                std::size_t size) {
  const auto v = verifier.verify(channel, data, size);
  if (v.verdict == auth::Verdict::kOk) return v.sender;
  const auto why = static_cast<std::size_t>(bad_kind(v.verdict));
  ++bad_messages_[why];
  notes_.note_limited("refused " + std::to_string(why), "skipped " + channel + ": " + v.why + " (never decoded)");
  return std::nullopt;
}

void Backendd::receive(store::RecordKind kind, const std::uint8_t* data, std::size_t size, std::int64_t sender) {
  const std::string channel = kind == store::RecordKind::kKeyframe ? "CVO_KEYFRAME" : "CVO_LOCAL_GRAPH";
  const auto refuse = [&](std::size_t why, const std::string& detail) {
    ++bad_messages_[why];
    notes_.note_limited("refused " + std::to_string(why), detail);
  };
  try {
    std::string error;
    std::size_t bad = cvo_lcm::status_t::BAD_BODY;
    const auto message = store::identify(kind, data, size, &error, &bad);
    if (!message) return refuse(bad, "skipped " + channel + ": " + error);
    const store::MessageKey key = message->key;
    const auto crc = store::content_crc(data, size);  // a re-send, signed afresh, is a repeat
    switch (door_.check(key, crc)) {
      case store::Admission::kRepeat:
        return notes_.note_limited("repeat", describe(key) + " received again: stored already, not used twice");
      case store::Admission::kConflict:
        return refuse(cvo_lcm::status_t::BAD_CONFLICT,
                      describe(key) + " repeats an existing one with other content" +
                          (sender != 0 ? " (sender " + auth::key_name(sender) + ")" : "") + ": refused");
      case store::Admission::kNew: break;
    }
    if (const std::string over = quota_.refusal(key.session, sender); !over.empty())
      return refuse(cvo_lcm::status_t::BAD_QUOTA, describe(key) + " refused: " + over);
    auto value = store::usable(*message, &error, &bad);
    if (!value) return refuse(bad, "skipped " + channel + ": " + error);
    // A graph is applied to its keyframe: one that never came is asked for again (a gap), and the
    // tracker sends the keyframe, then the graph.
    if (kind == store::RecordKind::kLocalGraph && !door_.knows({store::RecordKind::kKeyframe, key.session, key.id})) {
      gaps_.seen(KeyframeGaps::Seen::kGraphWithoutKeyframe, key.session, key.id, Clock::now());
      return refuse(cvo_lcm::status_t::BAD_UNKNOWN_KEYFRAME, "skipped " + describe(key) + ": its keyframe never came");
    }
    // Room first (a log waits for it). Live input that finds the queue full waits in the store
    // (only its place is queued), unless the store cannot take it now or too many wait there
    // already. A record refused here is neither stored nor let in, so its re-send is new.
    const bool log = is_log(config_.backendd.lcm_url);
    const bool room = log ? queue_.wait_for_room([&] { return stop_.load(); }) : queue_.has_room();
    const bool to_store =
        store_ && !room && !log && !store_->health().failing && waiting_in_store_ < kMaxWaitingInStore;
    if (!room && !to_store) {
      ++queue_drops_;
      return notes_.note_limited("queue full", describe(key) + " refused: " + std::to_string(queue_.size()) +
                                                   " records wait for the back end already");
    }
    // Used in any case; what the store cannot write now it holds and writes later, within a bound.
    store::RecordRef where;
    const auto appended =
        store_ ? store_->append(kind, std::vector<std::uint8_t>(data, data + size), &where) : store::Appended::kStored;
    if (store_ && appended == store::Appended::kNotDurable)
      notes_.note_limited("not stored", "warning: " + describe(key) + " used but not stored (lost on restart): " +
                                            describe(store_->health()) + " (backendd.unsaved_records_max)");
    note_store_change();
    door_.admit(key, crc);
    if (appended == store::Appended::kStored) held_.held(key.session, key.id, kind == store::RecordKind::kLocalGraph);
    quota_.count(key.session, sender);
    gaps_.seen(kind == store::RecordKind::kKeyframe ? KeyframeGaps::Seen::kKeyframe : KeyframeGaps::Seen::kLocalGraph,
               key.session, key.id, Clock::now());
    // Had the store failed just now, the record is queued whole, past the bound by this one.
    QueuedRecord queued{std::move(*value), Clock::now()};
    if (appended == store::Appended::kStored && store_) queued.stored = where;
    if (to_store && appended == store::Appended::kStored) {
      queued.content = where;
      ++waiting_in_store_;
      ++waited_in_store_;
      notes_.note_limited("waiting in the store", describe(key) +
                                                      " waits in the store: " + std::to_string(queue_.size()) +
                                                      " records wait for the back end already");
    }
    queue_.push(std::move(queued));
  } catch (const std::exception& e) {  // out of memory, most likely: this message is lost, not the daemon
    notes_.note_limited("receive failure", "skipped " + channel + ": " + e.what());
  }
}

// CVO_KEYFRAME_CHUNK: a slice of a keyframe's or local graph's message (libcvo/lcm/chunks.hpp). A
// slice of a message let in already is a repeat (or, with another CRC, a conflict); the others are
// put together (competing messages of one name apart, by CRC), and a message complete goes through
// the door as if it had come whole, from the sender of its last slice (every slice was verified);
// once one of a name is let in, the others of it are dropped. A slice of a live session says its
// keyframe exists: should the rest not come, it is asked for (keyframe_gaps.hpp); one of a session
// whose tracker is not heard asks for nothing, and is counted refused if it goes unassembled
// (slice_intake.hpp).
void Backendd::receive_slice(const void* data, std::size_t size, std::int64_t sender) {
  const auto chunk = decoded<cvo_lcm::keyframe_chunk_t>(data, size, "CVO_KEYFRAME_CHUNK");
  if (!chunk) return;
  const bool graph = chunk->message == cvo_lcm::keyframe_chunk_t::LOCAL_GRAPH;
  const store::MessageKey key{graph ? store::RecordKind::kLocalGraph : store::RecordKind::kKeyframe, chunk->session,
                              chunk->id};
  const auto refuse = [&](std::size_t why, const std::string& detail) {
    ++bad_messages_[why];
    notes_.note_limited("refused " + std::to_string(why), detail);
  };
  if (door_.knows(key)) {
    if (door_.check(key, static_cast<std::uint32_t>(chunk->message_crc)) == store::Admission::kConflict)
      refuse(cvo_lcm::status_t::BAD_CONFLICT, "a slice of " + describe(key) + " with other content: refused");
    return;  // a repeat: a slice re-sent for another, or late
  }
  auto added = slices_.add(*chunk, gaps_, Clock::now());
  count_strangers_dropped();
  using Outcome = lcm::ChunkAssembly::Added::Outcome;
  if (added.outcome == Outcome::kRefused)
    return refuse(static_cast<std::size_t>(added.refusal),
                  "skipped CVO_KEYFRAME_CHUNK of " + describe(key) + ": " + added.why);
  if (added.outcome != Outcome::kComplete) return;
  const KeyframeName keyframe{key.session, key.id};
  if (graph && !door_.knows({store::RecordKind::kKeyframe, key.session, key.id})) {
    // Complete before its keyframe (whose slices are still missing some): kept for it, not refused
    // and asked for again; past kMaxEarlyGraphs the first by name goes (asked for as any lost graph).
    if (early_graphs_.size() >= kMaxEarlyGraphs) early_graphs_.erase(early_graphs_.begin());
    early_graphs_[keyframe] = {std::move(added.message), sender};
    return;
  }
  receive(key.kind, added.message.data(), added.message.size(), sender);
  if (door_.knows(key)) slices_.forget({chunk->session, chunk->id, chunk->message});
  if (const auto early = early_graphs_.find(keyframe); !graph && early != early_graphs_.end()) {
    const EarlyGraph g = std::move(early->second);
    early_graphs_.erase(early);
    receive(store::RecordKind::kLocalGraph, g.message.data(), g.message.size(), g.sender);
    if (door_.knows({store::RecordKind::kLocalGraph, key.session, key.id}))
      slices_.forget({chunk->session, chunk->id, cvo_lcm::keyframe_chunk_t::LOCAL_GRAPH});
  }
}

// Slices of sessions whose tracker is not heard, dropped unassembled: they could not belong to a
// live session (a forger's flood, most likely), refused as naming no keyframe the back end knows.
void Backendd::count_strangers_dropped() {
  const std::int64_t dropped = slices_.strangers_dropped();
  if (dropped == 0) return;
  bad_messages_[cvo_lcm::status_t::BAD_UNKNOWN_KEYFRAME] += dropped;
  notes_.note_limited("refused " + std::to_string(cvo_lcm::status_t::BAD_UNKNOWN_KEYFRAME),
                      std::to_string(dropped) +
                          " CVO_KEYFRAME_CHUNK of sessions whose tracker is not heard dropped unassembled: refused");
}

// A message heard on `channel` (authentic already), decoded; one that does not decode is counted by
// kind and noted.
template <class Message>
std::optional<Message> Backendd::decoded(const void* data, std::size_t size, const char* channel) {
  std::string error;
  auto failure = lcm::DecodeFailure::kBody;
  auto message = lcm::decode<Message>(data, static_cast<int>(size), &error, &failure);
  if (!message) {
    const auto why = static_cast<std::size_t>(failure);
    ++bad_messages_[why];
    notes_.note_limited("refused " + std::to_string(why), std::string("skipped ") + channel + ": " + error);
  }
  return message;
}

// CVO_POSE names the keyframe each frame was tracked against: a keyframe lost in transport is
// noticed while its tracker still runs, even a session's newest one.
void Backendd::saw_pose(const void* data, std::size_t size) {
  const auto pose = decoded<cvo_lcm::pose_t>(data, size, "CVO_POSE");
  if (!pose) return;
  gaps_.seen(KeyframeGaps::Seen::kPose, pose->session, pose->keyframe_id, Clock::now());
  slices_.heard(pose->session, Clock::now(), pose->keyframe_id);
  const bool lost = pose->state == cvo_lcm::pose_t::STATE_LOST;
  {
    const std::lock_guard lock(posed_mutex_);
    if (lost)
      posed_.erase(pose->session);  // its tracker has moved on to a new session
    else
      posed_[pose->session] = Clock::now();  // live: its correction goes again once a status period
  }
  if (lost) queue_.push({LostSession{pose->session}, Clock::now()});
}

// A tracker's CVO_STATUS says its session is alive though it sends no pose (its camera ended or
// paused): the keyframes it lost in transport are still asked for (keyframe_gaps.hpp), and what is
// acknowledged of it is said again.
void Backendd::saw_status(const void* data, std::size_t size) {
  const auto status = decoded<cvo_lcm::status_t>(data, size, "CVO_STATUS");
  if (!status || status->process != "cvo-trackerd") return;
  gaps_.heard(status->session, Clock::now());
  slices_.heard(status->session, Clock::now(), std::nullopt);
  // Live: its correction, with what is acknowledged, goes again once a status period (a tracker that
  // lingers at its exit until its keyframes are acknowledged sends no pose).
  const std::lock_guard lock(posed_mutex_);
  posed_[status->session] = Clock::now();
}

// A log cannot answer: what it lacks is lost as soon as it is noticed.
GapPolicy Backendd::gap_policy(const config::Config& config) {
  GapPolicy policy;
  if (is_log(config.backendd.lcm_url)) policy.requests = 0;
  policy.ids_per_round = std::min<std::size_t>(policy.ids_per_round, cvo_lcm::keyframe_request_t::MAX_IDS);
  return policy;
}

// What a request asks of the tracker: of a keyframe nothing of which came, all of it (`ids`: the
// keyframe, then its local graph); of one that came in part, the slices missing and all of its
// local graph; of a local graph alone, its missing slices, or all of it. The ranges of one keyframe
// are the closest holes merged, so that all fit the request (MAX_RANGES).
cvo_lcm::keyframe_request_t Backendd::request_message(const KeyframeGaps::Request& request) const {
  using Chunk = cvo_lcm::keyframe_chunk_t;
  cvo_lcm::keyframe_request_t m{};
  m.version = cvo_lcm::keyframe_request_t::SCHEMA_VERSION;
  m.utime = core::wall_utime();
  m.session = request.session;
  const auto add_range = [&m](std::int64_t id, std::int8_t message, lcm::SliceRange r) {
    m.range_ids.push_back(id);
    m.range_messages.push_back(message);
    m.range_first.push_back(r.first);
    m.range_count.push_back(r.count);
  };
  const lcm::SliceRange all{0, std::numeric_limits<std::int32_t>::max()};
  const std::size_t per_keyframe =
      std::max<std::size_t>(2, cvo_lcm::keyframe_request_t::MAX_RANGES / std::max<std::size_t>(1, request.ids.size()));
  for (const auto id : request.ids) {
    const bool graph_only =
        std::find(request.graphs_only.begin(), request.graphs_only.end(), id) != request.graphs_only.end();
    const auto keyframe =
        graph_only ? std::nullopt : slices_.missing({request.session, id, Chunk::KEYFRAME}, per_keyframe - 1);
    if (!graph_only && !keyframe) {
      m.ids.push_back(id);
      continue;
    }
    for (const auto& r : keyframe.value_or(std::vector<lcm::SliceRange>{})) add_range(id, Chunk::KEYFRAME, r);
    if (early_graphs_.contains({request.session, id})) continue;  // its graph came already
    const auto graph = slices_.missing({request.session, id, Chunk::LOCAL_GRAPH}, 1);
    add_range(id, Chunk::LOCAL_GRAPH, graph ? graph->front() : all);
  }
  m.num_ids = static_cast<std::int32_t>(m.ids.size());
  m.num_ranges = static_cast<std::int32_t>(m.range_ids.size());
  return m;
}

// cvo-receive: the requests due go out on CVO_KEYFRAME_REQUEST, what was given up is noted; at the
// stop everything still waited for is given up. The counts go to CVO_STATUS.
void Backendd::ask_for_missing(::lcm::LCM& lcm, bool stopping) {
  const auto round = stopping ? KeyframeGaps::Round{{}, gaps_.give_up_all()} : gaps_.due(Clock::now());
  for (const auto& request : round.requests) {
    const cvo_lcm::keyframe_request_t m = request_message(request);
    auth::publish(lcm, bus_.signer(), "CVO_KEYFRAME_REQUEST", m);
    std::string ids;
    for (const auto id : request.ids) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
    notes_.note_limited("keyframe request", "asking session " + core::session_name(request.session) +
                                                " again for keyframes " + ids + " (lost in transport)");
  }
  for (const auto& g : round.given_up) {
    const std::string which = g.first == g.last ? "keyframe " + std::to_string(g.first)
                                                : "keyframes " + std::to_string(g.first) + "-" + std::to_string(g.last);
    notes_.note_limited("keyframes lost", "gave up on " + which + " of session " + core::session_name(g.session) +
                                              ": never came (lost): " + why_given_up(g.reason));
  }
  if (gaps_.recovered() > keyframes_recovered_)
    notes_.note_limited("keyframes recovered",
                        std::to_string(gaps_.recovered()) + " keyframes recovered after a loss in transport");
  keyframes_requested_ = gaps_.requested();
  keyframes_recovered_ = gaps_.recovered();
  keyframes_lost_ = gaps_.lost();
  if (stopping && gaps_.requested() + gaps_.lost() > 0)
    notes_.note("keyframes lost in transport: " + std::to_string(gaps_.requested()) + " asked for again, " +
                std::to_string(gaps_.recovered()) + " recovered, " + std::to_string(gaps_.lost()) + " lost");
}

// The store's state after an append or a retry, noted when it changes (cvo-receive).
void Backendd::note_store_change() {
  if (!store_) return;
  const auto health = store_->health();
  if (health.failing && !store_failing_)
    notes_.note("warning: " + describe(health) + ": accepted records are used and held in memory (at most " +
                std::to_string(config_.backendd.unsaved_records_max) +
                "), and stored in order when the store works again");
  else if (!health.failing && store_failing_)
    notes_.note("store " + store_->file().string() + " works again: every held record is stored (" +
                std::to_string(store_->records()) + " records)");
  store_failing_ = health.failing;
}

// Held records are written as soon as the store works again: tried once a second, and at the
// stop, where what is still unsaved is said.
void Backendd::retry_store(bool final) {
  const auto now = Clock::now();
  if (!store_ || (!final && now - store_retried_ < 1s)) return;
  store_retried_ = now;
  store_->retry();
  note_store_change();
  if (const auto health = store_->health(); final && health.degraded())
    notes_.note("warning: stopping with the " + describe(health) + "; what is unsaved is lost on restart");
}

// ---------------------------------------------------------------------------------------------
// cvo-backend

void Backendd::work_loop() {
  name_this_thread("cvo-backend");
  const auto status_period = std::chrono::duration<double>(config_.backendd.status_period_s);
  while (true) {
    work_heartbeat_.beat();
    const bool receiver_done = receiver_done_;  // read first: it pushes nothing after setting it
    if (stop_time_left() < kApplyUntil * config_.backendd.stop_timeout_s) {
      leave_waiting_records();
      break;
    }
    auto queued = queue_.pop(50ms);
    if (queued)
      process(*queued);
    else if (receiver_done && queue_.size() == 0)
      break;
    try {  // what the map cannot describe now is noted, and described again later: the daemon goes on
      publish_due();
      if (work_->grid_due && (!work_->grid.last || Clock::now() - *work_->grid.last >= kGridPeriod))
        publish_grid(false);
    } catch (const std::exception& e) {
      notes_.note_limited("publish failure", std::string("map not published after a failure: ") + e.what());
    }
    if (Clock::now() - work_->last_status >= status_period)
      publish_status(work_->summary.keyframes == 0 ? cvo_lcm::status_t::STATE_WAITING_FOR_INPUT
                                                   : cvo_lcm::status_t::STATE_RUNNING);
  }
  finish();
}

// One record into the mapper, and what follows it, each a step of its own (record_guard.hpp): a
// record the mapper refuses changed nothing (slam::Mapper's promise), one it fails on costs that
// record, and either way settling and the next record go on.
void Backendd::process(QueuedRecord& queued) {
  if (queued.arrived) guard_.run("the start of localization", [&] { localize_when_stored(); });
  guard_.run("record", [&] { process_record(queued); });
  // A service for months: merged keyframes older than their session's newest are forgotten
  // (slam::Mapper::settle), and their records become settled records (libcvo/store/store_merges.hpp).
  if (!work_->mapper.localizing_only()) guard_.run("settling", [&] { settle(); });
  if (!queued.arrived && --replayed_pending_ == 0) guard_.run("the store's map", [&] { replayed(); });
  ++work_->processed;
}

// Localization starts once the stored map is in: its records are queued before any live one.
void Backendd::localize_when_stored() {
  if (localization() && !work_->mapper.localizing_only() && replayed_pending_ == 0) start_localizing();
}

void Backendd::settle() {
  if (const auto settlement = work_->mapper.settle(); work_->merges && !settlement.empty())
    work_->merges->settled(settlement, waiting_in_store_ == 0);
}

// The store's last record is applied: localization starts, or the store's map goes out at once with
// each session's correction.
void Backendd::replayed() {
  if (work_->merges) work_->merges->replay_done(waiting_in_store_ == 0);
  if (localization())
    localize_when_stored();
  else
    publish_changes(std::nullopt, std::exchange(work_->replay_joined, {}), true);
}

// Throws what the mapper throws: process() guards it.
void Backendd::process_record(QueuedRecord& queued) {
  if (const auto* lost = std::get_if<LostSession>(&queued.content)) {
    work_->mapper.mark_lost(lost->session);
    notes_.note("session " + core::session_name(lost->session) + " lost: its tracker's odometry failed");
    publish_changes(lost->session, {}, false);
    return work_->schedule.lost(lost->session);
  }
  if (const auto* merge = std::get_if<slam::KeyframeMerge>(&queued.content)) return apply_merge(*merge, queued.stored);
  if (const auto* edge = std::get_if<slam::SettledEdge>(&queued.content)) return apply_settled(*edge, queued.stored);
  if (const auto* tally = std::get_if<slam::SessionTally>(&queued.content)) {
    work_->mapper.apply_tally(*tally);
    if (work_->merges) work_->merges->tally_replayed(*tally, queued.stored, waiting_in_store_ == 0);
    return publish_changes(tally->session, {}, false);
  }
  std::string error;
  const auto value = value_of(queued, &error);
  if (!value) return notes_.note_limited("unreadable", error);
  if (queued.arrived)  // live input: its session is live
    work_->schedule.seen(std::visit([](const auto& v) { return v.session; }, *value), *queued.arrived);
  if (const auto* keyframe = std::get_if<lcm::Keyframe>(&*value))
    apply_keyframe(*keyframe, queued);
  else
    apply_local_graph(std::get<store::LocalGraphRecord>(*value), queued);
}

// The stored map, optimised as a whole once, becomes read only; sessions from now on are localized.
void Backendd::start_localizing() {
  Work& w = *work_;
  if (w.mapper.backend().local_graphs() > 0) w.mapper.finish();
  w.mapper.localize_only();
  const auto map = w.mapper.map();
  notes_.note("localizing new sessions in the stored map: " + std::to_string(map.keyframes.size()) + " keyframes of " +
              std::to_string(map.sessions.size()) + " sessions, " + std::to_string(map.loops.size()) + " loops" +
              (map.keyframes.empty() ? " (an empty map: nothing can be localized)" : ""));
  publish_corrections(w.mapper.sessions(), false);
  w.optimisations = w.mapper.optimisations();
  w.schedule.changed();
  publish_map({}, false);
}

// The record's value, decoded here only if it was not at the door: a replayed message's images, a
// record that waited in the store whole.
std::optional<store::RecordValue> Backendd::value_of(QueuedRecord& queued, std::string* error) {
  if (auto* value = std::get_if<store::RecordValue>(&queued.content)) return std::move(*value);
  std::optional<store::Identified> message;
  if (auto* replayed = std::get_if<store::Identified>(&queued.content)) {
    message = std::move(*replayed);
  } else {
    --waiting_in_store_;
    const auto record = store_->read(std::get<store::RecordRef>(queued.content), error);
    if (record) message = store::identify(record->kind, record->payload.data(), record->payload.size(), error, nullptr);
    if (!message) {
      *error = "a record that waited in the store is lost: " + *error;
      return std::nullopt;
    }
  }
  auto value = store::usable(*message, error, nullptr);
  if (!value) *error = "stored " + describe(message->key) + " unreadable: " + *error;
  return value;
}

void Backendd::apply_keyframe(const lcm::Keyframe& k, const QueuedRecord& queued) {
  Work& w = *work_;
  const auto outcome = store::apply(w.mapper, k);
  if (outcome.duplicate) return;
  w.first_arrival.try_emplace(k.session, queued.arrived);
  if (w.merges) w.merges->keyframe(k.session, k.id, queued.stored);
  for (const auto& merge : outcome.merges) store_merge(merge, !queued.arrived);
  for (const auto& loop : outcome.loops) {
    const auto to = w.mapper.robot(loop.to_session), from = w.mapper.robot(loop.from_session);
    notes_.note("loop accepted: " + keyframe_name(loop.to_session, loop.to_id) + " to " +
                keyframe_name(loop.from_session, loop.from_id) + ", alpha " + fixed(loop.loop.alpha, 3) +
                (to != from ? ", between robots " + to + " and " + from : ""));
  }
  // The keyframe is in the SLAM map whether or not the occupancy grid can use it; a visitor's is in
  // no map.
  try {
    if (!w.mapper.localizing_only()) w.mapping.add_keyframe({k.session, k.id}, k.frame);
  } catch (const std::invalid_argument& e) {
    ++w.grid.not_mapped;
    notes_.note_limited("not mapped", keyframe_name(k.session, k.id) + " left out of the grid: " + e.what());
  }
  publish_changes(k.session, outcome.joined, !outcome.loops.empty() || !outcome.joined.empty());
}

// Compaction waits while records wait in the store: their references must not age past two.
void Backendd::store_merge(const slam::KeyframeMerge& merge, bool replayed) {
  if (!work_->merges) return;
  const auto compactions = work_->merges->compactions();
  if (work_->merges->merged(merge, replayed, waiting_in_store_ == 0) == store::Appended::kNotDurable)
    notes_.note_limited("not stored", "warning: the merge of " + keyframe_name(merge.session, merge.id) +
                                          " not stored: its keyframe's record stays (" + describe(store_->health()) +
                                          ")");
  if (work_->merges->compactions() != compactions)
    notes_.note("store compacted: merged keyframes' records dropped, " + std::to_string(store_->records()) +
                " records left");
}

// A stored merge record: the keyframe's own replay merged it already, or (its record compacted
// away) it is registered from the merge alone.
void Backendd::apply_merge(const slam::KeyframeMerge& merge, const std::optional<store::RecordRef>& stored) {
  work_->mapper.apply_merge(merge);
  if (work_->merges) work_->merges->record_replayed(merge, stored, waiting_in_store_ == 0);
  publish_changes(merge.session, {}, true);
}

// A stored settled record (libcvo/store/store_merges.hpp): what settled revisits left to its pair of keyframes.
void Backendd::apply_settled(const slam::SettledEdge& edge, const std::optional<store::RecordRef>& stored) {
  work_->mapper.apply_settled(edge);
  if (work_->merges) work_->merges->settled_replayed(edge, stored, waiting_in_store_ == 0);
  publish_changes(std::nullopt, {}, true);
}

void Backendd::apply_local_graph(const store::LocalGraphRecord& record, const QueuedRecord& queued) {
  const auto joined = store::apply(work_->mapper, record);
  if (work_->merges)
    work_->merges->local_graph(record.session, record.keyframe_id, queued.stored,
                               work_->mapper.merged(record.session, record.keyframe_id));
  ++work_->local_graphs;
  publish_changes(record.session, joined, !joined.empty());
}

// A change that optimised the keyframe graph may have moved every session; any other, only its own.
void Backendd::publish_changes(std::optional<core::SessionId> touched, const std::vector<std::int64_t>& joined,
                               bool after_loop) {
  Work& w = *work_;
  w.schedule.changed(after_loop);
  if (replayed_pending_ > 0) {  // a record of the store: what they make goes out once all are in (process())
    w.replay_joined.insert(w.replay_joined.end(), joined.begin(), joined.end());
    return;
  }
  // After the store's replay every session's correction (their trackers may be live, not heard yet);
  // after an optimisation the live ones' (map_schedule.hpp); else the touched session's.
  const bool optimised = w.mapper.optimisations() != w.optimisations;
  w.optimisations = w.mapper.optimisations();
  std::vector<core::SessionId> offered;
  if (!touched)
    offered = w.mapper.sessions();
  else if (optimised)
    offered = w.schedule.live(w.mapper.sessions(), Clock::now());
  if (touched && std::find(offered.begin(), offered.end(), *touched) == offered.end()) offered.push_back(*touched);
  publish_corrections(offered, false);
  if (w.schedule.map_due(Clock::now(), !joined.empty())) publish_map(joined, w.schedule.loop_waiting());
}

void Backendd::publish_corrections(const std::vector<core::SessionId>& sessions, bool again) {
  Work& w = *work_;
  for (const core::SessionId session : sessions) {
    const auto message = lcm::to_message(w.mapper.correction(session, cvo_lcm::map_correction_t::MAX_LOOPS),
                                         core::wall_utime(), w.epoch, held_.acknowledged(session));
    auto entry = lcm::encode(message.session);
    if (!again && !w.schedule.differs(session, entry)) continue;
    auth::publish(w.lcm, bus_.signer(), "CVO_MAP_CORRECTION", message);
    w.corrections.add(static_cast<std::size_t>(message.getEncodedSize()));
    w.schedule.sent(session, std::move(entry), Clock::now(), message.acknowledged);
  }
}

// From cvo-backend's loop: the full map once its period has passed while a change waited, the
// corrections of live sessions (a CVO_POSE or a record of theirs came lately) again, and those of
// sessions the store holds more of than they were told: between two records, so a tracker lingering
// for its acknowledgement waits for one record of the mapper's, not for its backlog.
void Backendd::publish_due() {
  Work& w = *work_;
  const auto now = Clock::now();
  {
    const std::lock_guard lock(posed_mutex_);
    for (const auto& [session, at] : posed_) w.schedule.seen(session, at);
    posed_.clear();
  }
  if (replayed_pending_ > 0) return;  // the store's map goes once it is in
  if (w.schedule.map_due(now, false)) publish_map({}, w.schedule.loop_waiting());
  if (const auto due = w.schedule.resends_due(now); !due.empty()) publish_corrections(due, true);
  // A session the mapper has not reached gets its default entry (unplaced, at the map's revision):
  // the first correction its tracker applies, or a handed-over session's word (map_decision.hpp).
  if (const auto due = w.schedule.acknowledgements_due(held_.take_grown()); !due.empty())
    publish_corrections(due, true);
}

void Backendd::publish_map(const std::vector<std::int64_t>& joined, bool after_loop) {
  Work& w = *work_;
  const slam::Map map = w.mapper.map();
  const auto message = lcm::to_message(map, core::wall_utime(), w.epoch);
  auth::publish(w.lcm, bus_.signer(), "CVO_MAP", message);
  w.maps.add(static_cast<std::size_t>(message.getEncodedSize()));
  w.schedule.map_sent(Clock::now());
  w.summary = summarise(map);
  for (const auto session : joined) {
    const auto arrived = w.first_arrival.find(session);
    w.joins.push_back(join_text(map, session, arrived != w.first_arrival.end() ? arrived->second : std::nullopt));
    notes_.note(w.joins.back());
  }
  place_in_grid(map, after_loop);
}

// The map's keyframes into the grid at their new poses. A changed grid goes out at once when it is
// the first, or a loop closure moved keyframes so that they were re-placed (some cell of theirs
// moved by a quarter cell: a robot must not plan on the grid of before the loop); else when a
// second has passed since the last (work_loop).
void Backendd::place_in_grid(const slam::Map& map, bool after_loop) {
  Work& w = *work_;
  if (!w.mapping.place(map)) return;
  const auto s = w.mapping.statistics();
  ++w.grid.places;
  w.grid.place_ms_total += s.place_ms_last;
  w.grid.place_ms_max = std::max(w.grid.place_ms_max, s.place_ms_last);
  w.grid_due = true;
  const bool moved = after_loop && s.moved_last > 0;
  if (!w.grid.last || moved || Clock::now() - *w.grid.last >= kGridPeriod) publish_grid(moved);
}

void Backendd::publish_grid(bool after_loop) {
  Work& w = *work_;
  const auto grid = w.mapping.grid();
  if (!grid) return;
  const auto message = lcm::to_message(*grid, core::wall_utime(), w.epoch);
  auth::publish(w.lcm, bus_.signer(), "CVO_GRID", message);
  const bool first = w.grid.published == 0;
  w.grid.last = Clock::now();
  w.grid.revision = message.revision;
  w.grid.bytes = static_cast<std::size_t>(message.getEncodedSize());
  ++w.grid.published;
  w.grid_due = false;
  const auto s = w.mapping.statistics();
  if (first)
    notes_.note("first CVO_GRID: " + std::to_string(grid->grid.width) + " x " + std::to_string(grid->grid.height) +
                " cells of " + fixed(grid->grid.resolution, 3) + " m, up from the " +
                std::string(mapping::up_source_name(grid->frame.up)));
  else if (after_loop)
    notes_.note_limited("grid after loop", "CVO_GRID revision " + std::to_string(grid->revision) +
                                               " after a loop: " + std::to_string(s.replaced_last) +
                                               " keyframes re-placed in " + fixed(s.place_ms_last, 1) + " ms" +
                                               (s.rebuilt_last ? " (rebuilt)" : ""));
}

void Backendd::publish_status(std::int8_t state) {
  Work& w = *work_;
  const auto now = Clock::now();
  lcm::ProcessStatus s;
  s.process = kProcess;
  s.robot = config::robot_name(config::kHostName);  // its host
  s.session = 0;                                    // the back end is no tracker session
  // A store that does not keep every record is the daemon's degraded state (the stop says itself).
  const auto store = store_ ? store_->health() : store::StoreHealth{};
  s.state = store.degraded() && state != cvo_lcm::status_t::STATE_STOPPING ? cvo_lcm::status_t::STATE_DEGRADED : state;
  s.unsaved_records = static_cast<std::int64_t>(store.unsaved);
  const double elapsed = std::chrono::duration<double>(now - w.last_status).count();
  s.rate_hz = elapsed > 0 ? static_cast<double>(w.processed - w.processed_at_last_status) / elapsed : 0;
  s.queue_depth = static_cast<std::int32_t>(queue_.size());
  for (std::size_t k = 0; k < s.bad_messages.size(); ++k) s.bad_messages[k] = bad_messages_[k];
  s.bad_messages[cvo_lcm::status_t::BAD_CONTENT] += guard_.refused();  // records the mapper refused
  s.failed_frames = guard_.failed();                                   // records and steps it failed on
  s.queue_drops = queue_drops_;
  s.keyframes_requested = keyframes_requested_;
  s.keyframes_recovered = keyframes_recovered_;
  s.keyframes_lost = keyframes_lost_;
  s.bus = bus_.status_bus();
  s.sender = bus_.sender();
  const cvo_lcm::status_t message = status_message(std::move(s), notes_);
  auth::publish(w.lcm, bus_.signer(), "CVO_STATUS", message);
  const std::string summary = text(w.summary) + "; " + text(w.grid, w.mapping.statistics()) + "; " +
                              text("CVO_MAP_CORRECTION", w.corrections) + ", " + text("CVO_MAP", w.maps);
  systemd_.status(store.degraded() ? "degraded: " + describe(store) + "; " + summary : summary);
  w.processed_at_last_status = w.processed;
  w.last_status = now;
}

double Backendd::stop_time_left() const {
  const Clock::time_point deadline{Clock::duration{stop_deadline_.load()}};
  if (deadline == Clock::time_point::max()) return std::numeric_limits<double>::infinity();
  return std::chrono::duration<double>(deadline - Clock::now()).count();
}

// A signal stop out of time for records: what waits is in the store (queued only after it was
// stored), and the next start's replay applies it.
void Backendd::leave_waiting_records() {
  const std::size_t waiting = queue_.size();
  if (waiting == 0) return;
  notes_.note(std::to_string(waiting) + " records not applied within backendd.stop_timeout_s (" +
              fixed(config_.backendd.stop_timeout_s, 1) + " s): " +
              (localization() ? "the map's are read again and live sessions localize again at the next start"
                              : "they are in the store, and the next start applies them"));
}

// The final global optimisation, the map it gives, and the closing note: each a step of its own
// (record_guard.hpp), so that a map that cannot be optimised or described still stops cleanly.
void Backendd::finish() {
  guard_.run("the final optimisation (the last map stands)", [&] { final_optimisation(); });
  guard_.run("the final CVO_GRID", [&] {
    if (stop_time_left() > 0)
      publish_grid(false);  // the final grid, changed or not: what a recording of the run ends with
    else
      notes_.note("final CVO_GRID skipped: no time left of backendd.stop_timeout_s (the last one sent stands)");
  });
  guard_.run("the closing notes", [&] { closing_notes(); });
  guard_.run("the last CVO_STATUS", [&] { publish_status(cvo_lcm::status_t::STATE_STOPPING); });
}

void Backendd::final_optimisation() {
  Work& w = *work_;
  // Nothing to optimise before a local graph; a read-only map was optimised when it became one.
  const bool optimise = w.mapper.backend().local_graphs() > 0 && !w.mapper.localizing_only();
  const double budget = stop_time_left() - kPublishIn * config_.backendd.stop_timeout_s;
  if (optimise && budget <= 0) {
    notes_.note(
        "final optimisation skipped: no time left of backendd.stop_timeout_s (the keyframe graph's poses "
        "stand; the next stop runs it)");
  } else if (optimise) {
    const auto report = w.mapper.finish(budget);
    notes_.note("final optimisation: cost " + std::to_string(report.initial_cost) + " -> " +
                std::to_string(report.final_cost) + " in " + std::to_string(report.iterations) + " iterations" +
                (report.stop_reason == posegraph::kTimeLimit ? ", cut short by backendd.stop_timeout_s" : ""));
  }
  publish_corrections(w.mapper.sessions(), false);
  w.schedule.changed();
  publish_map({}, false);
}

void Backendd::closing_notes() {
  const Work& w = *work_;
  notes_.note(text(w.summary) + "; " + std::to_string(w.local_graphs) + " local graphs; " +
              std::to_string(w.mapper.loops_accepted()) + " loops accepted of " +
              std::to_string(w.mapper.loops_tried()) + " tried");
  notes_.note(text("CVO_MAP_CORRECTION", w.corrections) + "; " + text("CVO_MAP", w.maps));
  if (guard_.refused() + guard_.failed() > 0)
    notes_.note(std::to_string(guard_.refused()) + " records refused by the mapper, " +
                std::to_string(guard_.failed()) + " records or steps skipped after a failure");
  notes_.note(slam::describe(slam::map_robots(w.mapper.map())));
  const auto& g = w.grid;
  notes_.note(text(g, w.mapping.statistics()) + "; " + std::to_string(g.published) + " CVO_GRIDs sent; place " +
              std::to_string(g.places) + " times, " +
              fixed(g.places > 0 ? g.place_ms_total / static_cast<double>(g.places) : 0.0, 1) + " ms on average, " +
              fixed(g.place_ms_max, 1) + " ms at most" +
              (g.not_mapped > 0 ? "; " + std::to_string(g.not_mapped) + " keyframes not mapped" : ""));
  for (const auto& join : w.joins) notes_.note(join);
  if (const auto waited = waited_in_store_.load(); waited > 0)
    notes_.note(std::to_string(waited) +
                " records waited in the store while the back end was behind (backendd.queue_max " +
                std::to_string(queue_.capacity()) + ")");
}

}  // namespace cvo::daemon::backendd
