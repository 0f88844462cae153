#include "daemon/backendd/map_building.hpp"

#include <chrono>
#include <limits>
#include <stdexcept>
#include <utility>
#include <variant>

#include "cvo_lcm/status_t.hpp"
#include "daemon/common/realtime.hpp"
#include "libcvo/config/mapper_parameters.hpp"
#include "libcvo/slam/map_robots.hpp"
#include "libcvo/store/replay.hpp"

namespace cvo::daemon::backendd {
namespace {

using namespace std::chrono_literals;
// A signal stop's budget (backendd.stop_timeout_s), in shares of it: records are applied while
// more than kApplyUntil of it is left, the final optimisation runs until kPublishIn is left, which
// publishes the final corrections, map and grid.
constexpr double kApplyUntil = 0.5;
constexpr double kPublishIn = 0.25;

}  // namespace

MapBuilding::MapBuilding(Shared& shared, loop_closure::Vocabulary vocabulary)
    : shared_(shared),
      guard_(shared.notes),
      mapper_(std::move(vocabulary), config::mapper_parameters(shared.config)),
      grid_map_(shared.config.mapping),
      publishing_(shared, mapper_, grid_map_, guard_) {}

void MapBuilding::run() {
  name_this_thread("cvo-backend");
  const double stop_timeout_s = shared_.config.backendd.stop_timeout_s;
  while (true) {
    shared_.work_heartbeat.beat();
    const bool receiver_done = shared_.receiver_done;  // read first: it pushes nothing after setting it
    if (shared_.stop_time_left() < kApplyUntil * stop_timeout_s) {
      leave_waiting_records();
      break;
    }
    auto queued = shared_.queue.pop(50ms);
    if (queued)
      process(*queued);
    else if (receiver_done && shared_.queue.size() == 0)
      break;
    try {  // what the map cannot describe now is noted, and described again later: the daemon goes on
      publishing_.due();
      publishing_.grid_due();
    } catch (const std::exception& e) {
      shared_.notes.note_limited("publish failure", std::string("map not published after a failure: ") + e.what());
    }
    publishing_.status_due();
  }
  finish();
}

// One record into the mapper, and what follows it, each a step of its own (record_guard.hpp): a
// record the mapper refuses changed nothing (slam::Mapper's promise), one it fails on costs that
// record, and either way settling and the next record go on.
void MapBuilding::process(QueuedRecord& queued) {
  if (queued.arrived) guard_.run("the start of localization", [&] { localize_when_stored(); });
  guard_.run("record", [&] { process_record(queued); });
  // A service for months: merged keyframes older than their session's newest are forgotten
  // (slam::Mapper::settle), and their records become settled records (libcvo/store/store_merges.hpp).
  if (!mapper_.localizing_only()) guard_.run("settling", [&] { settle(); });
  if (!queued.arrived && --shared_.counters.replayed_pending == 0) guard_.run("the store's map", [&] { replayed(); });
  publishing_.processed();
}

// Localization starts once the stored map is in: its records are queued before any live one.
void MapBuilding::localize_when_stored() {
  if (shared_.localization() && !mapper_.localizing_only() && shared_.counters.replayed_pending == 0)
    start_localizing();
}

// The stored map, optimised as a whole once, becomes read only; sessions from now on are localized.
void MapBuilding::start_localizing() {
  if (mapper_.backend().local_graphs() > 0) mapper_.finish();
  mapper_.localize_only();
  const auto map = mapper_.map();
  shared_.notes.note("localizing new sessions in the stored map: " + std::to_string(map.keyframes.size()) +
                     " keyframes of " + std::to_string(map.sessions.size()) + " sessions, " +
                     std::to_string(map.loops.size()) + " loops" +
                     (map.keyframes.empty() ? " (an empty map: nothing can be localized)" : ""));
  publishing_.optimisations_published();
  publishing_.whole_map();
}

void MapBuilding::settle() {
  if (const auto settlement = mapper_.settle(); merges_ && !settlement.empty())
    merges_->settled(settlement, may_compact());
}

// The store's last record is applied: localization starts, or the store's map goes out at once with
// each session's correction.
void MapBuilding::replayed() {
  if (merges_) merges_->replay_done(may_compact());
  if (shared_.localization())
    localize_when_stored();
  else
    publishing_.replayed();
}

// Throws what the mapper throws: process() guards it.
void MapBuilding::process_record(QueuedRecord& queued) {
  if (const auto* lost = std::get_if<LostSession>(&queued.content)) return mark_lost(lost->session);
  if (const auto* merge = std::get_if<slam::KeyframeMerge>(&queued.content)) return apply_merge(*merge, queued.stored);
  if (const auto* edge = std::get_if<slam::SettledEdge>(&queued.content)) return apply_settled(*edge, queued.stored);
  if (const auto* tally = std::get_if<slam::SessionTally>(&queued.content)) return apply_tally(*tally, queued.stored);
  std::string error;
  const auto value = value_of(queued, &error);
  if (!value) return shared_.notes.note_limited("unreadable", error);
  if (queued.arrived)  // live input: its session is live
    publishing_.seen(std::visit([](const auto& v) { return v.session; }, *value), *queued.arrived);
  if (const auto* keyframe = std::get_if<lcm::Keyframe>(&*value))
    apply_keyframe(*keyframe, queued);
  else
    apply_local_graph(std::get<store::LocalGraphRecord>(*value), queued);
}

void MapBuilding::mark_lost(core::SessionId session) {
  mapper_.mark_lost(session);
  shared_.notes.note("session " + core::session_name(session) + " lost: its tracker's odometry failed");
  publishing_.changes(session, {}, false);
  publishing_.lost(session);
}

// The record's value, decoded here only if it was not at the door: a replayed message's images, a
// record that waited in the store whole.
std::optional<store::RecordValue> MapBuilding::value_of(QueuedRecord& queued, std::string* error) {
  if (auto* value = std::get_if<store::RecordValue>(&queued.content)) return std::move(*value);
  std::optional<store::Identified> message;
  if (auto* replayed = std::get_if<store::Identified>(&queued.content)) {
    message = std::move(*replayed);
  } else {
    --shared_.counters.waiting_in_store;
    const auto record = shared_.store->read(std::get<store::RecordRef>(queued.content), error);
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

void MapBuilding::apply_keyframe(const lcm::Keyframe& k, const QueuedRecord& queued) {
  const auto outcome = store::apply(mapper_, k);
  if (outcome.duplicate) return;
  publishing_.first_keyframe(k.session, queued.arrived);
  if (merges_) merges_->keyframe(k.session, k.id, queued.stored);
  for (const auto& merge : outcome.merges) store_merge(merge, !queued.arrived);
  for (const auto& loop : outcome.loops) {
    const auto to = mapper_.robot(loop.to_session), from = mapper_.robot(loop.from_session);
    shared_.notes.note("loop accepted: " + keyframe_name(loop.to_session, loop.to_id) + " to " +
                       keyframe_name(loop.from_session, loop.from_id) + ", alpha " + fixed(loop.loop.alpha, 3) +
                       (to != from ? ", between robots " + to + " and " + from : ""));
  }
  add_to_grid(k);
  publishing_.changes(k.session, outcome.joined, !outcome.loops.empty() || !outcome.joined.empty());
}

// The keyframe is in the SLAM map whether or not the occupancy grid can use it; a visitor's is in
// no map.
void MapBuilding::add_to_grid(const lcm::Keyframe& k) {
  try {
    if (!mapper_.localizing_only()) grid_map_.add_keyframe({k.session, k.id}, k.frame);
  } catch (const std::invalid_argument& e) {
    ++not_mapped_;
    shared_.notes.note_limited("not mapped", keyframe_name(k.session, k.id) + " left out of the grid: " + e.what());
  }
}

void MapBuilding::store_merge(const slam::KeyframeMerge& merge, bool replayed) {
  if (!merges_) return;
  const auto compactions = merges_->compactions();
  if (merges_->merged(merge, replayed, may_compact()) == store::Appended::kNotDurable)
    shared_.notes.note_limited("not stored", "warning: the merge of " + keyframe_name(merge.session, merge.id) +
                                                 " not stored: its keyframe's record stays (" +
                                                 describe(shared_.store->health()) + ")");
  if (merges_->compactions() != compactions)
    shared_.notes.note("store compacted: merged keyframes' records dropped, " +
                       std::to_string(shared_.store->records()) + " records left");
}

// A stored merge record: the keyframe's own replay merged it already, or (its record compacted
// away) it is registered from the merge alone.
void MapBuilding::apply_merge(const slam::KeyframeMerge& merge, const std::optional<store::RecordRef>& stored) {
  mapper_.apply_merge(merge);
  if (merges_) merges_->record_replayed(merge, stored, may_compact());
  publishing_.changes(merge.session, {}, true);
}

// A stored settled record (libcvo/store/store_merges.hpp): what settled revisits left to its pair of
// keyframes.
void MapBuilding::apply_settled(const slam::SettledEdge& edge, const std::optional<store::RecordRef>& stored) {
  mapper_.apply_settled(edge);
  if (merges_) merges_->settled_replayed(edge, stored, may_compact());
  publishing_.changes(std::nullopt, {}, true);
}

void MapBuilding::apply_tally(const slam::SessionTally& tally, const std::optional<store::RecordRef>& stored) {
  mapper_.apply_tally(tally);
  if (merges_) merges_->tally_replayed(tally, stored, may_compact());
  publishing_.changes(tally.session, {}, false);
}

void MapBuilding::apply_local_graph(const store::LocalGraphRecord& record, const QueuedRecord& queued) {
  const auto joined = store::apply(mapper_, record);
  if (merges_)
    merges_->local_graph(record.session, record.keyframe_id, queued.stored,
                         mapper_.merged(record.session, record.keyframe_id));
  ++local_graphs_;
  publishing_.changes(record.session, joined, !joined.empty());
}

// A signal stop out of time for records: what waits is in the store (queued only after it was
// stored), and the next start's replay applies it.
void MapBuilding::leave_waiting_records() {
  const std::size_t waiting = shared_.queue.size();
  if (waiting == 0) return;
  shared_.notes.note(std::to_string(waiting) + " records not applied within backendd.stop_timeout_s (" +
                     fixed(shared_.config.backendd.stop_timeout_s, 1) + " s): " +
                     (shared_.localization()
                          ? "the map's are read again and live sessions localize again at the next start"
                          : "they are in the store, and the next start applies them"));
}

// The final global optimisation, the map it gives, and the closing note: each a step of its own
// (record_guard.hpp), so that a map that cannot be optimised or described still stops cleanly.
void MapBuilding::finish() {
  guard_.run("the final optimisation (the last map stands)", [&] { final_optimisation(); });
  guard_.run("the final CVO_GRID", [&] {
    if (shared_.stop_time_left() > 0)
      publishing_.grid(false);  // the final grid, changed or not: what a recording of the run ends with
    else
      shared_.notes.note("final CVO_GRID skipped: no time left of backendd.stop_timeout_s (the last one sent stands)");
  });
  guard_.run("the closing notes", [&] { closing_notes(); });
  guard_.run("the last CVO_STATUS", [&] { publishing_.status(cvo_lcm::status_t::STATE_STOPPING); });
}

void MapBuilding::final_optimisation() {
  // Nothing to optimise before a local graph; a read-only map was optimised when it became one.
  const bool optimise = mapper_.backend().local_graphs() > 0 && !mapper_.localizing_only();
  const double budget = shared_.stop_time_left() - kPublishIn * shared_.config.backendd.stop_timeout_s;
  if (optimise && budget <= 0) {
    shared_.notes.note(
        "final optimisation skipped: no time left of backendd.stop_timeout_s (the keyframe graph's poses "
        "stand; the next stop runs it)");
  } else if (optimise) {
    const auto report = mapper_.finish(budget);
    shared_.notes.note("final optimisation: cost " + std::to_string(report.initial_cost) + " -> " +
                       std::to_string(report.final_cost) + " in " + std::to_string(report.iterations) + " iterations" +
                       (report.stop_reason == posegraph::kTimeLimit ? ", cut short by backendd.stop_timeout_s" : ""));
  }
  publishing_.whole_map();
}

void MapBuilding::closing_notes() {
  Notes& notes = shared_.notes;
  notes.note(text(publishing_.summary()) + "; " + std::to_string(local_graphs_) + " local graphs; " +
             std::to_string(mapper_.loops_accepted()) + " loops accepted of " + std::to_string(mapper_.loops_tried()) +
             " tried");
  notes.note(text("CVO_MAP_CORRECTION", publishing_.corrections_sent()) + "; " +
             text("CVO_MAP", publishing_.maps_sent()));
  if (guard_.refused() + guard_.failed() > 0)
    notes.note(std::to_string(guard_.refused()) + " records refused by the mapper, " + std::to_string(guard_.failed()) +
               " records or steps skipped after a failure");
  notes.note(slam::describe(slam::map_robots(mapper_.map())));
  const auto& g = publishing_.grid_summary();
  notes.note(text(g, grid_map_.statistics()) + "; " + std::to_string(g.published) + " CVO_GRIDs sent; place " +
             std::to_string(g.places) + " times, " +
             fixed(g.places > 0 ? g.place_ms_total / static_cast<double>(g.places) : 0.0, 1) + " ms on average, " +
             fixed(g.place_ms_max, 1) + " ms at most" +
             (not_mapped_ > 0 ? "; " + std::to_string(not_mapped_) + " keyframes not mapped" : ""));
  for (const auto& join : publishing_.joins()) notes.note(join);
  if (const auto waited = shared_.counters.waited_in_store.load(); waited > 0)
    notes.note(std::to_string(waited) +
               " records waited in the store while the back end was behind (backendd.queue_max " +
               std::to_string(shared_.queue.capacity()) + ")");
}

}  // namespace cvo::daemon::backendd
