#include "daemon/backendd/receiving.hpp"

#include <algorithm>
#include <functional>
#include <limits>
#include <thread>
#include <utility>

#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/keyframe_chunk_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "daemon/common/realtime.hpp"
#include "libcvo/auth/lcm_publish.hpp"
#include "libcvo/core/units.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/store/merge_record.hpp"
#include "libcvo/store/replay.hpp"

namespace cvo::daemon::backendd {
namespace {

using namespace std::chrono_literals;
// At a stop, messages already in the socket are taken in; a tracker that is still sending must
// not keep the drain going for ever.
constexpr int kMaxDrainMessages = 10000;
// CVO_KEYFRAME_CHUNKs LCM may hold for cvo-receive: 32 keyframes' slices (~12 MB of datagrams).
constexpr int kSliceQueue = 32 * 256;
// Records that may wait in the store for the back end (each queued as a few bytes): hours of a
// tracker's keyframes; beyond it live input is refused and counted (queue_drops).
constexpr std::int64_t kMaxWaitingInStore = 16384;

// The sender a stored record was received from: its auth_t trailer's (verified when it came;
// zero on an open bus), for the bounds per sender across restarts.
std::int64_t stored_sender(const std::vector<std::uint8_t>& payload) {
  return payload.size() >= auth::kTrailerBytes ? auth::read_trailer(payload.data(), payload.size()).sender : 0;
}

std::string channel_of(store::RecordKind kind) {
  return kind == store::RecordKind::kKeyframe ? "CVO_KEYFRAME" : "CVO_LOCAL_GRAPH";
}

KeyframeGaps::Seen seen_as(store::RecordKind kind) {
  return kind == store::RecordKind::kKeyframe ? KeyframeGaps::Seen::kKeyframe : KeyframeGaps::Seen::kLocalGraph;
}

}  // namespace

Receiving::Receiving(Shared& shared)
    : shared_(shared),
      quota_(shared.config.backendd.max_records_per_session, shared.config.backendd.max_records_per_sender),
      gaps_(gap_policy(shared.config)) {
  note_store_change();
}

// The store's records pass the same door as received messages (replayed first, in order), so a
// store written before the door, or a damaged one, cannot feed the mapper a repeat.
void Receiving::let_in(std::vector<store::StoredRecord> recovered) {
  for (auto& record : recovered) {
    std::string why;
    // The back end's own records name no message: they do not pass the door.
    const auto queue_decoded = [&](auto decoded) {
      if (!decoded) return shared_.notes.note_limited("stored skipped", "stored record skipped: " + why);
      ++shared_.counters.replayed_pending;
      shared_.queue.push({std::move(*decoded), std::nullopt, record.where});
    };
    const auto* payload = record.payload.data();
    const auto size = record.payload.size();
    if (record.kind == store::RecordKind::kMerge) {
      auto merge = store::decode_merge(payload, size, &why);
      if (merge) shared_.held.merged(merge->session, merge->id);
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
      shared_.notes.note_limited("stored skipped", why);
      continue;
    }
    const store::MessageKey key = message->key;
    quota_.count(key.session, sender);
    shared_.held.held(key.session, key.id, key.kind == store::RecordKind::kLocalGraph);
    gaps_.seen(
        record.kind == store::RecordKind::kKeyframe ? KeyframeGaps::Seen::kKeyframe : KeyframeGaps::Seen::kLocalGraph,
        key.session, key.id, Clock::now());  // a gap in the store is asked for too
    ++shared_.counters.replayed_pending;
    shared_.queue.push({std::move(*message), std::nullopt, record.where});
  }
}

void Receiving::run() {
  name_this_thread("cvo-receive");
  ::lcm::LCM lcm(shared_.config.backendd.lcm_url);
  auth::Verifier verifier = shared_.bus.verifier(shared_.config.backendd.lcm_url);  // every buffer, before decoding
  struct Verified {  // every channel: its buffers verified first, then handed on with their sender
    Receiving* self;
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
  const bool log = is_log(shared_.config.backendd.lcm_url);
  while (!shared_.stop) {
    shared_.receive_heartbeat.beat();
    retry_store(false);
    ask_for_missing(lcm, false);
    if (shared_.input_ended) {  // a log that ended: nothing more will come; wait for the stop
      std::this_thread::sleep_for(50ms);
      continue;
    }
    if (lcm.handleTimeout(100) >= 0) continue;
    if (log) {
      shared_.notes.note("end of " + shared_.config.backendd.lcm_url +
                         (shared_.config.backendd.exit_on_eof ? ": finishing" : ""));
      shared_.input_ended = true;
      continue;
    }
    shared_.notes.note_limited("receive failed", "LCM receive failed; retrying");
    std::this_thread::sleep_for(100ms);
  }
  // What is in the socket was sent before the stop (a tracker's last keyframe and local graph):
  // it is taken in and used too.
  for (int n = 0; !log && n < kMaxDrainMessages && lcm.handleTimeout(0) > 0; ++n) {
  }
  retry_store(true);
  ask_for_missing(lcm, true);
  shared_.receiver_done = true;
}

std::optional<std::int64_t> Receiving::authentic(auth::Verifier& verifier, const std::string& channel, const void* data,
                                                 std::size_t size) {
  const auto v = verifier.verify(channel, data, size);
  if (v.verdict == auth::Verdict::kOk) return v.sender;
  const auto why = static_cast<std::size_t>(bad_kind(v.verdict));
  ++shared_.counters.bad_messages[why];
  shared_.notes.note_limited("refused " + std::to_string(why),
                             "skipped " + channel + ": " + v.why + " (never decoded)");
  return std::nullopt;
}

void Receiving::refuse(std::size_t why, const std::string& detail) {
  ++shared_.counters.bad_messages[why];
  shared_.notes.note_limited("refused " + std::to_string(why), detail);
}

void Receiving::receive(store::RecordKind kind, const std::uint8_t* data, std::size_t size, std::int64_t sender) {
  try {
    if (auto admitted = admit(kind, data, size, sender))
      store_and_queue(kind, data, size, sender, std::move(*admitted));
  } catch (const std::exception& e) {  // out of memory, most likely: this message is lost, not the daemon
    shared_.notes.note_limited("receive failure", "skipped " + channel_of(kind) + ": " + e.what());
  }
}

// Decoded, through the door, within the bounds, usable, its keyframe known: what may be stored.
std::optional<Receiving::Admitted> Receiving::admit(store::RecordKind kind, const std::uint8_t* data, std::size_t size,
                                                    std::int64_t sender) {
  std::string error;
  std::size_t bad = cvo_lcm::status_t::BAD_BODY;
  const auto message = store::identify(kind, data, size, &error, &bad);
  if (!message) {
    refuse(bad, "skipped " + channel_of(kind) + ": " + error);
    return std::nullopt;
  }
  const store::MessageKey key = message->key;
  const auto crc = store::content_crc(data, size);  // a re-send, signed afresh, is a repeat
  switch (door_.check(key, crc)) {
    case store::Admission::kRepeat:
      shared_.notes.note_limited("repeat", describe(key) + " received again: stored already, not used twice");
      return std::nullopt;
    case store::Admission::kConflict:
      refuse(cvo_lcm::status_t::BAD_CONFLICT, describe(key) + " repeats an existing one with other content" +
                                                  (sender != 0 ? " (sender " + auth::key_name(sender) + ")" : "") +
                                                  ": refused");
      return std::nullopt;
    case store::Admission::kNew: break;
  }
  if (const std::string over = quota_.refusal(key.session, sender); !over.empty()) {
    refuse(cvo_lcm::status_t::BAD_QUOTA, describe(key) + " refused: " + over);
    return std::nullopt;
  }
  auto value = store::usable(*message, &error, &bad);
  if (!value) {
    refuse(bad, "skipped " + channel_of(kind) + ": " + error);
    return std::nullopt;
  }
  // A graph is applied to its keyframe: one that never came is asked for again (a gap), and the
  // tracker sends the keyframe, then the graph.
  if (kind == store::RecordKind::kLocalGraph && !door_.knows({store::RecordKind::kKeyframe, key.session, key.id})) {
    gaps_.seen(KeyframeGaps::Seen::kGraphWithoutKeyframe, key.session, key.id, Clock::now());
    refuse(cvo_lcm::status_t::BAD_UNKNOWN_KEYFRAME, "skipped " + describe(key) + ": its keyframe never came");
    return std::nullopt;
  }
  return Admitted{key, crc, std::move(*value)};
}

// Room first (a log waits for it). Live input that finds the queue full waits in the store (only
// its place is queued), unless the store cannot take it now or too many wait there already. A
// record refused here is neither stored nor let in, so its re-send is new.
void Receiving::store_and_queue(store::RecordKind kind, const std::uint8_t* data, std::size_t size, std::int64_t sender,
                                Admitted admitted) {
  const store::MessageKey& key = admitted.key;
  auto& counters = shared_.counters;
  const bool log = is_log(shared_.config.backendd.lcm_url);
  const bool room = log ? shared_.queue.wait_for_room([&] { return shared_.stop.load(); }) : shared_.queue.has_room();
  const bool to_store = shared_.store && !room && !log && !shared_.store->health().failing &&
                        counters.waiting_in_store < kMaxWaitingInStore;
  if (!room && !to_store) {
    ++counters.queue_drops;
    return shared_.notes.note_limited(
        "queue full",
        describe(key) + " refused: " + std::to_string(shared_.queue.size()) + " records wait for the back end already");
  }
  // Used in any case; what the store cannot write now it holds and writes later, within a bound.
  store::RecordRef where;
  const auto appended = shared_.store
                            ? shared_.store->append(kind, std::vector<std::uint8_t>(data, data + size), &where)
                            : store::Appended::kStored;
  if (shared_.store && appended == store::Appended::kNotDurable)
    shared_.notes.note_limited("not stored", "warning: " + describe(key) + " used but not stored (lost on restart): " +
                                                 describe(shared_.store->health()) + " (backendd.unsaved_records_max)");
  note_store_change();
  door_.admit(key, admitted.crc);
  if (appended == store::Appended::kStored)
    shared_.held.held(key.session, key.id, kind == store::RecordKind::kLocalGraph);
  quota_.count(key.session, sender);
  gaps_.seen(seen_as(kind), key.session, key.id, Clock::now());
  // Had the store failed just now, the record is queued whole, past the bound by this one.
  QueuedRecord queued{std::move(admitted.value), Clock::now()};
  if (appended == store::Appended::kStored && shared_.store) queued.stored = where;
  if (to_store && appended == store::Appended::kStored) {
    queued.content = where;
    ++counters.waiting_in_store;
    ++counters.waited_in_store;
    shared_.notes.note_limited("waiting in the store",
                               describe(key) + " waits in the store: " + std::to_string(shared_.queue.size()) +
                                   " records wait for the back end already");
  }
  shared_.queue.push(std::move(queued));
}

// CVO_KEYFRAME_CHUNK: a slice of a keyframe's or local graph's message (libcvo/lcm/chunks.hpp). A
// slice of a message let in already is a repeat (or, with another CRC, a conflict); the others are
// put together (competing messages of one name apart, by CRC), and a message complete goes through
// the door as if it had come whole, from the sender of its last slice (every slice was verified);
// once one of a name is let in, the others of it are dropped. A slice of a live session says its
// keyframe exists: should the rest not come, it is asked for (keyframe_gaps.hpp); one of a session
// whose tracker is not heard asks for nothing, and is counted refused if it goes unassembled
// (slice_intake.hpp).
void Receiving::receive_slice(const void* data, std::size_t size, std::int64_t sender) {
  const auto chunk = decoded<cvo_lcm::keyframe_chunk_t>(data, size, "CVO_KEYFRAME_CHUNK");
  if (!chunk) return;
  const bool graph = chunk->message == cvo_lcm::keyframe_chunk_t::LOCAL_GRAPH;
  const store::MessageKey key{graph ? store::RecordKind::kLocalGraph : store::RecordKind::kKeyframe, chunk->session,
                              chunk->id};
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
void Receiving::count_strangers_dropped() {
  const std::int64_t dropped = slices_.strangers_dropped();
  if (dropped == 0) return;
  shared_.counters.bad_messages[cvo_lcm::status_t::BAD_UNKNOWN_KEYFRAME] += dropped;
  shared_.notes.note_limited(
      "refused " + std::to_string(cvo_lcm::status_t::BAD_UNKNOWN_KEYFRAME),
      std::to_string(dropped) +
          " CVO_KEYFRAME_CHUNK of sessions whose tracker is not heard dropped unassembled: refused");
}

// A message heard on `channel` (authentic already), decoded; one that does not decode is counted by
// kind and noted.
template <class Message>
std::optional<Message> Receiving::decoded(const void* data, std::size_t size, const char* channel) {
  std::string error;
  auto failure = lcm::DecodeFailure::kBody;
  auto message = lcm::decode<Message>(data, static_cast<int>(size), &error, &failure);
  if (!message) {
    const auto why = static_cast<std::size_t>(failure);
    ++shared_.counters.bad_messages[why];
    shared_.notes.note_limited("refused " + std::to_string(why), std::string("skipped ") + channel + ": " + error);
  }
  return message;
}

// CVO_POSE names the keyframe each frame was tracked against: a keyframe lost in transport is
// noticed while its tracker still runs, even a session's newest one.
void Receiving::saw_pose(const void* data, std::size_t size) {
  const auto pose = decoded<cvo_lcm::pose_t>(data, size, "CVO_POSE");
  if (!pose) return;
  gaps_.seen(KeyframeGaps::Seen::kPose, pose->session, pose->keyframe_id, Clock::now());
  slices_.heard(pose->session, Clock::now(), pose->keyframe_id);
  const bool lost = pose->state == cvo_lcm::pose_t::STATE_LOST;
  if (lost)
    shared_.posed.lost(pose->session);
  else
    shared_.posed.live(pose->session, Clock::now());  // its correction goes again once a status period
  if (lost) shared_.queue.push({LostSession{pose->session}, Clock::now()});
}

// A tracker's CVO_STATUS says its session is alive though it sends no pose (its camera ended or
// paused): the keyframes it lost in transport are still asked for (keyframe_gaps.hpp), and what is
// acknowledged of it is said again.
void Receiving::saw_status(const void* data, std::size_t size) {
  const auto status = decoded<cvo_lcm::status_t>(data, size, "CVO_STATUS");
  if (!status || status->process != "cvo-trackerd") return;
  gaps_.heard(status->session, Clock::now());
  slices_.heard(status->session, Clock::now(), std::nullopt);
  // Live: its correction, with what is acknowledged, goes again once a status period (a tracker that
  // lingers at its exit until its keyframes are acknowledged sends no pose).
  shared_.posed.live(status->session, Clock::now());
}

// The store's state after an append or a retry, noted when it changes (cvo-receive).
void Receiving::note_store_change() {
  if (!shared_.store) return;
  const auto health = shared_.store->health();
  if (health.failing && !store_failing_)
    shared_.notes.note("warning: " + describe(health) + ": accepted records are used and held in memory (at most " +
                       std::to_string(shared_.config.backendd.unsaved_records_max) +
                       "), and stored in order when the store works again");
  else if (!health.failing && store_failing_)
    shared_.notes.note("store " + shared_.store->file().string() + " works again: every held record is stored (" +
                       std::to_string(shared_.store->records()) + " records)");
  store_failing_ = health.failing;
}

// Held records are written as soon as the store works again: tried once a second, and at the
// stop, where what is still unsaved is said.
void Receiving::retry_store(bool final) {
  const auto now = Clock::now();
  if (!shared_.store || (!final && now - store_retried_ < 1s)) return;
  store_retried_ = now;
  shared_.store->retry();
  note_store_change();
  if (const auto health = shared_.store->health(); final && health.degraded())
    shared_.notes.note("warning: stopping with the " + describe(health) + "; what is unsaved is lost on restart");
}

}  // namespace cvo::daemon::backendd
