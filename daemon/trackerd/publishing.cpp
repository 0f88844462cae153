#include "daemon/trackerd/publishing.hpp"

#include <poll.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <set>
#include <span>
#include <thread>
#include <utility>
#include <vector>

#include "cvo_lcm/keyframe_chunk_t.hpp"
#include "cvo_lcm/keyframe_request_t.hpp"
#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/local_graph_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "daemon/common/realtime.hpp"
#include "daemon/common/status.hpp"
#include "daemon/trackerd/killed_graph.hpp"
#include "libcvo/auth/lcm_publish.hpp"
#include "libcvo/config/config.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/core/units.hpp"
#include "libcvo/lcm/chunks.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/lcm/local_graph_conversion.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "libcvo/lcm/tracker_messages.hpp"

namespace cvo::daemon::trackerd {
namespace {

using namespace std::chrono_literals;

// Room for the largest CVO_KEYFRAME a camera's keyframe can be: every point, the images raw plus
// an eighth for the encoders' own overhead (a compressed image larger than that is pathological,
// and not kept); and for a full local graph (a node and two edges per frame).
std::size_t max_keyframe_bytes(std::uint64_t camera_size, const odometry::KeyframeOdometryParameters& parameters) {
  const auto pixels = (camera_size >> 32) * (camera_size & 0xffffffffU);
  const std::size_t images = pixels * (3 + 2);  // BGR8 and 16-bit depth
  return static_cast<std::size_t>(cvo_lcm::keyframe_t{}.getEncodedSize()) +
         parameters.odometry.max_points * (3 + 5) * sizeof(float) + images + images / 8;
}

std::size_t max_local_graph_bytes(const odometry::KeyframeOdometryParameters& parameters) {
  cvo_lcm::local_graph_t graph{};
  const auto empty = static_cast<std::size_t>(graph.getEncodedSize());
  graph.num_nodes = 1;
  graph.nodes.resize(1);
  const auto node = static_cast<std::size_t>(graph.getEncodedSize()) - empty;
  graph.num_edges = 1;
  graph.edges.resize(1);
  const auto edge = static_cast<std::size_t>(graph.getEncodedSize()) - empty - node;
  return empty + parameters.tracking.local_graph_capacity * (node + 2 * edge);
}

// Keyframes whose odometry poses the loop check of a placement can use: a loop of the back end is
// to one of the session's recent keyframes (it joins the map as soon as it can).
constexpr std::size_t kOwnKeyframes = 64;

std::string id_list(const std::vector<std::int64_t>& ids) {
  std::string out;
  for (const auto id : ids) out += (out.empty() ? "" : ", ") + std::to_string(id);
  return out;
}

}  // namespace

Publishing::Publishing(Shared& shared)
    : shared_(shared),
      lcm_(shared.config.trackerd.lcm_url),
      verifier_(shared.bus.verifier(shared.config.trackerd.lcm_url)),
      receives_(!shared.config.trackerd.lcm_url.starts_with("file://")),
      encoding_(lcm::keyframe_encoding(*lcm::parse_colour_encoding(shared.config.trackerd.keyframe_colour_encoding))),
      chunks_(config::keyframes_in_chunks(shared.config.trackerd)),
      robot_(config::robot_name(shared.config.trackerd.robot)),
      resend_budget_(shared.config.trackerd.resend_bytes_per_s),
      delivery_(shared.config.trackerd.spool, shared.config.trackerd.spool_bytes, shared.config.trackerd.linger_s,
                &delivery_warning_),
      session_(shared.session.load()) {}

KeyframeHistory& Publishing::history() {
  if (!history_)
    history_ = std::make_unique<KeyframeHistory>(shared_.config.trackerd.keyframe_history,
                                                 max_keyframe_bytes(shared_.out.camera_size, shared_.parameters),
                                                 max_local_graph_bytes(shared_.parameters));
  return *history_;
}

void Publishing::run() {
  name_this_thread("cvo-publish");
  struct Handler {
    Publishing* self;
    void map(const ::lcm::ReceiveBuffer* b, const std::string& channel) {
      if (const auto sender = self->authentic(channel, b->data, b->data_size))
        self->apply_map(channel, b->data, static_cast<int>(b->data_size), *sender);
    }
    void request(const ::lcm::ReceiveBuffer* b, const std::string& channel) {
      if (const auto requester = self->authentic(channel, b->data, b->data_size))
        self->answer_request(b->data, static_cast<int>(b->data_size), *requester);
    }
  } handler{this};
  if (receives_) {
    lcm_.subscribe("CVO_MAP_CORRECTION", &Handler::map, &handler);
    lcm_.subscribe("CVO_MAP", &Handler::map, &handler);  // a back end of before CVO_MAP_CORRECTION, lcm-spy users
    lcm_.subscribe("CVO_KEYFRAME_REQUEST", &Handler::request, &handler);
  }
  const auto period = std::chrono::duration<double>(shared_.config.trackerd.status_period_s);
  if (!delivery_warning_.empty()) shared_.notes.note("warning: " + delivery_warning_);
  hand_over();
  Event event;
  while (!finished()) {
    shared_.publish_heartbeat.beat();
    const auto wait = pacer_.idle() ? std::chrono::milliseconds(10) : std::chrono::milliseconds(1);
    if (!shared_.out.ready)
      std::this_thread::sleep_for(wait);
    else if (shared_.out.outbox->pop(event, wait))
      publish(event);
    send_slices();
    receive();
    send_unacknowledged();
    if (Clock::now() - last_status_ >= period) publish_status(-1);
  }
  if (const auto note = delivery_.unacknowledged_note(); !note.empty()) shared_.notes.note("exit: " + note);
  // A source that could not be opened is the daemon's failure, and says so in its last status.
  publish_status(shared_.source_failed ? cvo_lcm::status_t::STATE_FAILED : cvo_lcm::status_t::STATE_STOPPING);
  shared_.publisher_done = true;
}

// CVO_MAP_CORRECTION, CVO_MAP and CVO_KEYFRAME_REQUEST, without blocking the poses.
void Publishing::receive() {
  if (!receives_) return;
  pollfd pfd{lcm_.getFileno(), POLLIN, 0};
  while (poll(&pfd, 1, 0) > 0 && (pfd.revents & POLLIN) != 0) lcm_.handle();
}

// Done once the tracker is done, every event published and every slice sent, and the back end
// acknowledged what was published (or trackerd.linger_s has passed: delivery.hpp).
bool Publishing::finished() {
  const bool idle = shared_.tracker_done && (!shared_.out.ready || shared_.out.outbox->finished()) && pacer_.idle();
  if (!idle) return false;
  const auto now = Delivery::Clock::now();
  if (!done_at_) done_at_ = now;
  return delivery_.may_exit(*done_at_, now);
}

// What earlier runs left in the spool (a tracker killed, or out of power, before the back end
// acknowledged it) goes out first, and waits for acknowledgement as this run's keyframes do.
void Publishing::hand_over() {
  const auto left = with_killed_graphs(delivery_.left_over(shared_.session.load()));
  if (left.empty()) return;
  std::size_t keyframes = 0;
  for (const auto& e : left) {
    const auto bytes = delivery_.spooled(e.session, e.id, e.graph);
    if (!bytes) continue;
    const std::int8_t message = e.graph ? cvo_lcm::keyframe_chunk_t::LOCAL_GRAPH : cvo_lcm::keyframe_chunk_t::KEYFRAME;
    send_record({e.session, e.id, message}, *bytes, lcm::content_crc(bytes->data(), bytes->size()), std::nullopt);
    keyframes += e.graph ? 0 : 1;
  }
  delivery_.handed_over(left, Delivery::Clock::now());
  shared_.notes.note("handing over " + std::to_string(keyframes) + " keyframes (" + std::to_string(left.size()) +
                     " messages) that an earlier run left in the spool unacknowledged");
}

// A killed session's newest keyframe is in the spool without its local graph (which would have
// gone out with the next keyframe): it gets one of itself alone (killed_graph.hpp), spooled before
// it is sent, so that the back end holds it with a graph and acknowledges it, and it leaves the
// spool only then. One whose graph cannot be made or kept is handed over alone, as before.
std::vector<Spool::Entry> Publishing::with_killed_graphs(const std::vector<Spool::Entry>& left) {
  std::set<std::pair<std::int64_t, std::int64_t>> graphs;
  for (const auto& e : left)
    if (e.graph) graphs.emplace(e.session, e.id);
  std::vector<Spool::Entry> out;
  std::size_t made = 0;
  for (const auto& e : left) {
    out.push_back(e);
    if (e.graph || graphs.contains({e.session, e.id})) continue;
    const auto keyframe = delivery_.spooled(e.session, e.id, false);
    const auto graph = keyframe ? graph_of_killed_keyframe(*keyframe, core::wall_utime()) : std::nullopt;
    const Spool::Entry entry{e.session, e.id, true, graph ? graph->size() : 0};
    if (!graph || !delivery_.spool(entry, *graph)) continue;
    out.push_back(entry);
    ++made;
  }
  if (made > 0)
    shared_.notes.note(std::to_string(made) +
                       " killed sessions' newest keyframes given a local graph of the keyframe " +
                       "alone (the frames tracked against them died with their tracker)");
  return out;
}

// Keyframes the back end has not acknowledged long after they went out are sent again unasked,
// keyframe then local graph (from the history, or the spool for a session handed over), within the
// re-send budget.
void Publishing::send_unacknowledged() {
  const auto now = Delivery::Clock::now();
  const double now_s = std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
  for (const auto& [session, id] : delivery_.due(now)) {
    for (const bool graph : {false, true}) {
      const std::int8_t kind = graph ? cvo_lcm::keyframe_chunk_t::LOCAL_GRAPH : cvo_lcm::keyframe_chunk_t::KEYFRAME;
      std::vector<std::uint8_t> spooled;
      KeyframeHistory::Message m;  // from the history (its CRC kept), else from the spool
      if (const auto held = shared_.out.ready ? history().find(session, id) : std::nullopt)
        m = graph ? held->graph : held->keyframe;
      if (m.bytes.empty())
        if (auto s = delivery_.spooled(session, id, graph)) {
          spooled = std::move(*s);
          m = {spooled, lcm::content_crc(spooled.data(), spooled.size())};
        }
      if (m.bytes.empty() || !resend_budget_.take(-1, session, m.bytes.size(), now_s)) continue;
      send_record({session, id, kind}, m.bytes, m.crc, std::nullopt);
    }
  }
  if (const auto note = delivery_.spool_note(); !note.empty()) shared_.notes.note_limited("spool", note);
}

std::optional<std::int64_t> Publishing::authentic(const std::string& channel, const void* data, std::size_t size) {
  const auto v = verifier_.verify(channel, data, size);
  if (v.verdict == auth::Verdict::kOk) return v.sender;
  shared_.count_bad(bad_kind(v.verdict), "skipped " + channel, std::string(v.why) + " (never decoded)");
  return std::nullopt;
}

void Publishing::publish(const Event& event) {
  Outbox& outbox = *shared_.out.outbox;
  if (event.session != session_) {  // noted here: the tracking thread does not allocate
    session_ = event.session;
    shared_.notes.note("camera re-initialised: new session " + core::session_name(event.session));
    // A camera change may have made keyframes larger.
    history().reserve_keyframe_bytes(max_keyframe_bytes(shared_.out.camera_size, shared_.parameters));
    own_keyframes_.clear();
    own_next_ = 0;
  }
  if (event.has_pose && event.pose.keyframe_odom_pose)
    remember_keyframe(event.pose.keyframe_id, *event.pose.keyframe_odom_pose);
  if (event.has_pose && event.pose.keyframe_id >= 0) history().made(event.session, event.pose.keyframe_id);
  if (event.graph_slot >= 0) {  // encoded here, so that the history keeps the very bytes sent
    const auto& g = outbox.graph(event.graph_slot);
    auto bytes = lcm::encode(lcm::to_message(g.graph, event.session, g.keyframe_id, core::wall_utime(), robot_));
    const auto crc = lcm::content_crc(bytes.data(), bytes.size());
    send_record({event.session, g.keyframe_id, cvo_lcm::keyframe_chunk_t::LOCAL_GRAPH}, bytes, crc, std::nullopt);
    history().keep_graph(event.session, g.keyframe_id, bytes, crc);
    delivery_.published(event.session, g.keyframe_id, true, bytes, Delivery::Clock::now());
  }
  if (event.keyframe_slot >= 0)
    publish_keyframe(event);
  else if (event.has_pose && event.pose.is_keyframe)  // no outbox slot: counted by the outbox
    history().never_sent(event.session, event.pose.keyframe_id);
  if (event.has_pose) {
    const double latency_ms = core::ms_since(event.pose.received);
    const cvo_lcm::pose_t m = lcm::pose_message(event.session, robot_, event.pose, latency_ms);
    auth::publish(lcm_, shared_.bus.signer(), "CVO_POSE", m);
    latency_.add(m.latency_ms);
    if (m.latency_ms > shared_.config.trackerd.deadline_ms) ++deadline_misses_;
    if (published_++ == 0) shared_.notes.note("first pose published");
    if (event.pose.state == core::LocalizationState::kLost)
      shared_.notes.note("session " + core::session_name(event.session) + " lost at frame " +
                         std::to_string(event.pose.frame_index) + ": the odometry failed (" +
                         odometry::to_string(event.pose.status) + "); tracking again in a new session");
    last_frame_ = Clock::now();
  }
  outbox.release(event);
}

void Publishing::remember_keyframe(std::int64_t id, const core::SE3& odometry_pose) {
  if (own_keyframes_.size() < kOwnKeyframes)
    own_keyframes_.push_back({id, odometry_pose});
  else
    own_keyframes_[own_next_] = {id, odometry_pose};
  own_next_ = (own_next_ + 1) % kOwnKeyframes;
}

void Publishing::publish_keyframe(const Event& event) {
  const auto& k = shared_.out.outbox->keyframe(event.keyframe_slot);
  std::string error;
  const lcm::Keyframe keyframe{event.session, k.id, k.frame, k.pose, k.cloud, robot_};
  const auto message = lcm::to_message(keyframe, encoding_, &error);
  if (!message) {
    ++unsent_;
    history().never_sent(event.session, k.id);
    shared_.notes.note("keyframe " + std::to_string(k.id) + " not published (lost): " + error);
    return;
  }
  auto bytes = lcm::encode(*message);
  const auto crc = lcm::content_crc(bytes.data(), bytes.size());
  send_record({event.session, k.id, cvo_lcm::keyframe_chunk_t::KEYFRAME}, bytes, crc, std::nullopt);
  delivery_.published(event.session, k.id, false, bytes, Delivery::Clock::now());
  if (!history().keep_keyframe(event.session, k.id, bytes, crc) && history().capacity() > 0)
    shared_.notes.note("keyframe " + std::to_string(k.id) + " (" + std::to_string(bytes.size()) +
                       " bytes) is larger than a history slot: it cannot be sent again");
}

// A keyframe's or local graph's message out, first or again: whole on its channel, signed (afresh,
// for a re-send), or in slices on CVO_KEYFRAME_CHUNK (trackerd.keyframe_transport), each signed,
// the message's trailer left zero, paced (slice_pacer.hpp); `slices`: only those (a re-send of
// what the back end lacks).
void Publishing::send_record(const lcm::SlicedName& name, std::span<const std::uint8_t> bytes, std::uint32_t crc,
                             std::optional<lcm::SliceRange> slices) {
  if (!chunks_) {
    resend_.assign(bytes.begin(), bytes.end());
    const bool graph = name.message == cvo_lcm::keyframe_chunk_t::LOCAL_GRAPH;
    auth::publish_bytes(lcm_, shared_.bus.signer(), graph ? "CVO_LOCAL_GRAPH" : "CVO_KEYFRAME", resend_);
    return;
  }
  pacer_.add(name, std::make_shared<const std::vector<std::uint8_t>>(bytes.begin(), bytes.end()), crc,
             slices.value_or(lcm::SliceRange{0, lcm::slice_count(bytes.size())}));
  send_slices();  // the first burst at once
}

// The slices due (slice_pacer.hpp), each signed.
void Publishing::send_slices() {
  pacer_.send_due(SlicePacer::Clock::now(), [this](const cvo_lcm::keyframe_chunk_t& slice) {
    resend_.resize(static_cast<std::size_t>(slice.getEncodedSize()));
    slice.encode(resend_.data(), 0, static_cast<int>(resend_.size()));
    auth::publish_bytes(lcm_, shared_.bus.signer(), "CVO_KEYFRAME_CHUNK", resend_);
  });
}

// CVO_KEYFRAME_REQUEST: the back end missed keyframes of a session; those of this tracker's sessions
// that the history still holds go out again as first sent (keyframe, then its local graph).
// Requests for other sessions are other trackers'.
void Publishing::answer_request(const void* data, int size, std::int64_t requester) {
  std::string error;
  auto failure = lcm::DecodeFailure::kBody;
  const auto request = lcm::decode<cvo_lcm::keyframe_request_t>(data, size, &error, &failure);
  if (!request) return shared_.count_bad(static_cast<int>(failure), "skipped CVO_KEYFRAME_REQUEST", error);
  const std::string what = "CVO_KEYFRAME_REQUEST for session " + core::session_name(request->session);
  if (request->num_ids > cvo_lcm::keyframe_request_t::MAX_IDS ||
      request->num_ranges > cvo_lcm::keyframe_request_t::MAX_RANGES)
    return shared_.count_bad(cvo_lcm::status_t::BAD_CONTENT, "skipped " + what,
                             std::to_string(request->num_ids) + " ids and " + std::to_string(request->num_ranges) +
                                 " ranges, more than " + std::to_string(cvo_lcm::keyframe_request_t::MAX_IDS) +
                                 " and " + std::to_string(cvo_lcm::keyframe_request_t::MAX_RANGES));
  if (!shared_.out.ready) {  // nothing made yet: only a request for the running session concerns us
    if (request->session == shared_.session.load())
      shared_.count_bad(cvo_lcm::status_t::BAD_CONTENT, "skipped " + what, "no keyframe made yet");
    return;
  }
  const auto send = [&](const KeyframeHistory::Resend& r) {
    const std::int8_t message = r.graph ? cvo_lcm::keyframe_chunk_t::LOCAL_GRAPH : cvo_lcm::keyframe_chunk_t::KEYFRAME;
    send_record({request->session, r.id, message}, r.message.bytes, r.message.crc, r.slices);
  };
  std::vector<KeyframeHistory::Wanted> ranges;
  for (std::int32_t i = 0; i < request->num_ranges; ++i)
    ranges.push_back({request->range_ids[i],
                      request->range_messages[i] == cvo_lcm::keyframe_chunk_t::LOCAL_GRAPH,
                      {request->range_first[i], request->range_count[i]}});
  const double now_s = std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
  const auto afford = [&](std::size_t bytes) { return resend_budget_.take(requester, request->session, bytes, now_s); };
  const auto answer = history().answer(request->session, request->ids, ranges, send, afford);
  if (!answer.ours) return answer_from_spool(*request, ranges, afford);
  if (!answer.over.empty())
    shared_.notes.note_limited("re-send budget", "keyframes " + id_list(answer.over) + " of session " +
                                                     core::session_name(request->session) +
                                                     " not sent again: over trackerd.resend_bytes_per_s (" +
                                                     std::to_string(resend_budget_.refused()) + " refused so far)");
  if (!answer.never.empty())
    shared_.count_bad(cvo_lcm::status_t::BAD_CONTENT, "skipped part of " + what,
                      "keyframes " + id_list(answer.never) + " were never made");
  if (answer.sent.empty() && answer.lost.empty()) return;
  const auto n = ++requests_answered_;
  std::string done = answer.sent.empty() ? "" : "sent " + id_list(answer.sent);
  if (!answer.lost.empty())
    done += (done.empty() ? "" : "; ") + std::string("lost (not in the history of ") +
            std::to_string(history().capacity()) + "): " + id_list(answer.lost);
  const std::string by = requester != 0 ? " (sender " + auth::key_name(requester) + ")" : "";
  shared_.notes.note_limited("keyframe request", "the back end" + by + " asked again for keyframes of session " +
                                                     core::session_name(request->session) + " (#" + std::to_string(n) +
                                                     "): " + done);
}

// A request for a session an earlier run left in the spool (handed over): answered from there.
void Publishing::answer_from_spool(const cvo_lcm::keyframe_request_t& request,
                                   const std::vector<KeyframeHistory::Wanted>& ranges,
                                   const KeyframeHistory::Afford& afford) {
  const auto send = [&](std::int64_t id, bool graph, std::optional<lcm::SliceRange> slices) {
    const auto bytes = delivery_.spooled(request.session, id, graph);
    if (!bytes || !afford(bytes->size())) return;
    const std::int8_t kind = graph ? cvo_lcm::keyframe_chunk_t::LOCAL_GRAPH : cvo_lcm::keyframe_chunk_t::KEYFRAME;
    send_record({request.session, id, kind}, *bytes, lcm::content_crc(bytes->data(), bytes->size()), slices);
  };
  for (const auto id : request.ids) {
    send(id, false, std::nullopt);
    send(id, true, std::nullopt);
  }
  for (const auto& w : ranges) send(w.id, w.graph, w.slices);
}

void Publishing::publish_status(std::int8_t state_override) {
  const auto now = Clock::now();
  const double elapsed = std::chrono::duration<double>(now - last_status_).count();
  const auto& c = shared_.counters;
  lcm::ProcessStatus s;
  s.process = "cvo-trackerd";
  s.robot = robot_;
  s.session = session_;
  s.rate_hz = elapsed > 0 ? static_cast<double>(published_ - published_at_last_status_) / elapsed : 0;
  const auto l = latency_.summary();
  s.latency_median_ms = l.median_ms;
  s.latency_p99_ms = l.p99_ms;
  s.deadline_misses = deadline_misses_;
  s.dropped_frames = shared_.ring.dropped() + c.source_lost_frames;
  s.failed_frames = c.failed_frames;
  s.source_gaps = c.source_gaps;
  s.allocations_after_warmup = c.allocations_after_warmup;
  s.queue_depth = static_cast<std::int32_t>(shared_.ring.waiting());
  for (std::size_t k = 0; k < s.bad_messages.size(); ++k) s.bad_messages[k] = c.bad_messages[k];
  const std::int64_t outbox_lost = shared_.out.ready ? shared_.out.outbox->lost() : 0;
  if (outbox_lost > outbox_lost_noted_) {  // noted here: the tracking thread does not allocate
    shared_.notes.note(std::to_string(outbox_lost) +
                       " keyframes or local graphs lost before publication (the publisher fell behind)");
    outbox_lost_noted_ = outbox_lost;
  }
  s.keyframes_requested = shared_.out.ready ? history().resent() : 0;
  s.bus = shared_.bus.status_bus();
  s.sender = shared_.bus.sender();
  s.keyframes_lost = outbox_lost + unsent_ + (shared_.out.ready ? history().lost() : 0);
  s.state = state_override >= 0 ? state_override
                                : lcm::tracker_state({published_, c.source_connected.load(), now - last_frame_ > 1s,
                                                      c.failed_frames > failed_at_last_status_});
  const cvo_lcm::status_t message = daemon::status_message(std::move(s), shared_.notes);
  auth::publish(lcm_, shared_.bus.signer(), "CVO_STATUS", message);
  shared_.systemd.status(std::to_string(published_) + " frames, " + std::to_string(std::lround(s.rate_hz)) +
                         " Hz, latency p99 " + std::to_string(std::lround(s.latency_p99_ms)) + " ms, " +
                         std::to_string(s.dropped_frames) + " dropped");
  published_at_last_status_ = published_;
  failed_at_last_status_ = c.failed_frames;
  last_status_ = now;
}

// CVO_MAP_CORRECTION or CVO_MAP: what the one decision trusts (lcm::decide_session_correction,
// lcm::decide_map_correction) moves the running session's map poses (placed: its correction; not
// placed: map pose = odometry pose); what it ignores (another session's correction, the applied one
// again) is no fault; anything else is counted by kind.
void Publishing::apply_map(const std::string& channel, const void* data, int size, std::int64_t sender) {
  const std::int64_t session = shared_.session.load();
  const auto& t = shared_.config.trackerd;
  const lcm::CorrectionLimits limits{t.max_map_jump_m, t.max_map_jump_deg, t.map_epoch_slack_s, t.map_revisions_per_s};
  const lcm::MapContext context{core::wall_utime(), sender, own_keyframes_};
  const auto decide = channel == "CVO_MAP" ? lcm::decide_map_correction : lcm::decide_session_correction;
  const lcm::CorrectionDecision d = decide(data, size, session, applied_, limits, context);
  take_acknowledgement(d);
  if (d.ignored) return;
  if (!d.apply) return shared_.count_bad(static_cast<int>(d.refusal), "skipped " + channel, d.why);
  const bool was_placed = applied_.session == session && applied_.placed;
  if (d.correction.placed != was_placed)
    shared_.notes.note("session " + core::session_name(session) +
                       (d.correction.placed ? " placed in the map" : " no longer placed in the map") +
                       " (map revision " + std::to_string(d.correction.revision) + ", " + channel + ")");
  applied_ = d.correction;
  const auto& c = d.correction;
  shared_.correction.set(session, {c.T_map_odom, c.placed, c.epoch, c.revision, c.last_match_time,
                                   c.keyframe_covariance, c.covariance_keyframe});
}

// What a CVO_MAP_CORRECTION the decision trusts acknowledges (map_decision.hpp), taken no further
// than what was published (Delivery::acknowledged). A word that claims more, and another session's
// whose epoch or sender the rules refuse, are counted when the session is ours: a forger on an open
// bus, or a faulty back end, for an operator to see.
void Publishing::take_acknowledgement(const lcm::CorrectionDecision& d) {
  const std::string what = "skipped the acknowledgement of a CVO_MAP_CORRECTION";
  if (d.acknowledgement_refused && delivery_.newest_published(*d.acknowledgement_refused))
    return shared_.count_bad(static_cast<int>(d.refusal), what, d.why);
  if (!d.acknowledged) return;
  const auto [session, prefix] = *d.acknowledged;
  const auto taken = delivery_.acknowledged(session, prefix, Delivery::Clock::now());
  if (!taken || *taken == prefix) return;
  shared_.count_bad(static_cast<int>(core::BadKind::kImplausible), what,
                    "it acknowledges keyframes below " + std::to_string(prefix) + " of session " +
                        core::session_name(session) + ", beyond the newest published (" + std::to_string(*taken - 1) +
                        "): taken below " + std::to_string(*taken));
}

}  // namespace cvo::daemon::trackerd
