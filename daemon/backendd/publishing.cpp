#include "daemon/backendd/publishing.hpp"

#include <algorithm>
#include <utility>

#include "cvo_lcm/grid_t.hpp"
#include "cvo_lcm/map_correction_t.hpp"
#include "cvo_lcm/map_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "daemon/common/status.hpp"
#include "libcvo/auth/lcm_publish.hpp"
#include "libcvo/core/units.hpp"
#include "libcvo/lcm/grid_conversion.hpp"
#include "libcvo/lcm/map_conversion.hpp"
#include "libcvo/lcm/map_correction_conversion.hpp"
#include "libcvo/lcm/tracker_messages.hpp"

namespace cvo::daemon::backendd {
namespace {

using namespace std::chrono_literals;
constexpr const char* kProcess = "cvo-backendd";
// CVO_GRID at most this often while the grid changes (a loop closure's goes out at once): a grid
// is tens of kilobytes, and a planner replans on each.
constexpr auto kGridPeriod = 1s;
// A session whose tracker said nothing (no record, no CVO_POSE) for this long is no longer live: its
// correction is not sent again.
constexpr auto kLiveFor = 10s;

}  // namespace

Publishing::Publishing(Shared& shared, const slam::Mapper& mapper, mapping::Mapping& grid, const RecordGuard& guard)
    : shared_(shared),
      mapper_(mapper),
      grid_map_(grid),
      guard_(guard),
      lcm_(publish_url(shared.config.backendd)),
      schedule_({std::chrono::duration<double>(shared.config.backendd.map_period_s),
                 std::chrono::duration<double>(shared.config.backendd.status_period_s), kLiveFor, kGridPeriod}),
      epoch_(core::wall_utime()) {}

// A change that optimised the keyframe graph may have moved every session; any other, only its own.
void Publishing::changes(std::optional<core::SessionId> touched, const std::vector<std::int64_t>& joined,
                         bool after_loop) {
  schedule_.changed(after_loop);
  if (shared_.counters.replayed_pending > 0) {  // a record of the store: what they make goes out once all are in
    replay_joined_.insert(replay_joined_.end(), joined.begin(), joined.end());
    return;
  }
  // After the store's replay every session's correction (their trackers may be live, not heard yet);
  // after an optimisation the live ones' (map_schedule.hpp); else the touched session's.
  const bool optimised = mapper_.optimisations() != optimisations_;
  optimisations_ = mapper_.optimisations();
  std::vector<core::SessionId> offered;
  if (!touched)
    offered = mapper_.sessions();
  else if (optimised)
    offered = schedule_.live(mapper_.sessions(), Clock::now());
  if (touched && std::find(offered.begin(), offered.end(), *touched) == offered.end()) offered.push_back(*touched);
  corrections(offered, false);
  if (schedule_.map_due(Clock::now(), !joined.empty())) map(joined, schedule_.loop_waiting());
}

void Publishing::replayed() { changes(std::nullopt, std::exchange(replay_joined_, {}), true); }

void Publishing::whole_map() {
  corrections(mapper_.sessions(), false);
  schedule_.changed();
  map({}, false);
}

void Publishing::corrections(const std::vector<core::SessionId>& sessions, bool again) {
  for (const core::SessionId session : sessions) {
    const auto message = lcm::to_message(mapper_.correction(session, cvo_lcm::map_correction_t::MAX_LOOPS),
                                         core::wall_utime(), epoch_, shared_.held.acknowledged(session));
    auto entry = lcm::encode(message.session);
    if (!again && !schedule_.differs(session, entry)) continue;
    auth::publish(lcm_, shared_.bus.signer(), "CVO_MAP_CORRECTION", message);
    corrections_.add(static_cast<std::size_t>(message.getEncodedSize()));
    schedule_.sent(session, std::move(entry), Clock::now(), message.acknowledged);
  }
}

// The full map once its period has passed while a change waited, the corrections of live sessions
// (a CVO_POSE or a record of theirs came lately) again, and those of sessions the store holds more
// of than they were told: between two records, so a tracker lingering for its acknowledgement waits
// for one record of the mapper's, not for its backlog.
void Publishing::due() {
  const auto now = Clock::now();
  for (const auto& [session, at] : shared_.posed.take()) schedule_.seen(session, at);
  if (shared_.counters.replayed_pending > 0) return;  // the store's map goes once it is in
  if (schedule_.map_due(now, false)) map({}, schedule_.loop_waiting());
  if (const auto resend = schedule_.resends_due(now); !resend.empty()) corrections(resend, true);
  // A session the mapper has not reached gets its default entry (unplaced, at the map's revision):
  // the first correction its tracker applies, or a handed-over session's word (map_decision.hpp).
  if (const auto grown = schedule_.acknowledgements_due(shared_.held.take_grown()); !grown.empty())
    corrections(grown, true);
}

void Publishing::grid_due() {
  if (grid_changed_ && (!grid_.last || Clock::now() - *grid_.last >= kGridPeriod)) grid(false);
}

void Publishing::status_due() {
  if (Clock::now() - last_status_ < std::chrono::duration<double>(shared_.config.backendd.status_period_s)) return;
  status(summary_.keyframes == 0 ? cvo_lcm::status_t::STATE_WAITING_FOR_INPUT : cvo_lcm::status_t::STATE_RUNNING);
}

void Publishing::map(const std::vector<std::int64_t>& joined, bool after_loop) {
  const slam::Map map = mapper_.map();
  const auto message = lcm::to_message(map, core::wall_utime(), epoch_);
  auth::publish(lcm_, shared_.bus.signer(), "CVO_MAP", message);
  maps_.add(static_cast<std::size_t>(message.getEncodedSize()));
  schedule_.map_sent(Clock::now());
  summary_ = summarise(map);
  for (const auto session : joined) {
    const auto arrived = first_arrival_.find(session);
    joins_.push_back(join_text(map, session, arrived != first_arrival_.end() ? arrived->second : std::nullopt));
    shared_.notes.note(joins_.back());
  }
  place_in_grid(map, after_loop);
}

// The map's keyframes into the grid at their new poses. A changed grid goes out at once when it is
// the first, or a loop closure moved keyframes so that they were re-placed (some cell of theirs
// moved by a quarter cell: a robot must not plan on the grid of before the loop); else when a
// second has passed since the last (grid_due).
void Publishing::place_in_grid(const slam::Map& map, bool after_loop) {
  if (!grid_map_.place(map)) return;
  const auto s = grid_map_.statistics();
  ++grid_.places;
  grid_.place_ms_total += s.place_ms_last;
  grid_.place_ms_max = std::max(grid_.place_ms_max, s.place_ms_last);
  grid_changed_ = true;
  const bool moved = after_loop && s.moved_last > 0;
  if (!grid_.last || moved || Clock::now() - *grid_.last >= kGridPeriod) grid(moved);
}

void Publishing::grid(bool after_loop) {
  const auto grid = grid_map_.grid();
  if (!grid) return;
  const auto message = lcm::to_message(*grid, core::wall_utime(), epoch_);
  auth::publish(lcm_, shared_.bus.signer(), "CVO_GRID", message);
  const bool first = grid_.published == 0;
  grid_.last = Clock::now();
  grid_.revision = message.revision;
  grid_.bytes = static_cast<std::size_t>(message.getEncodedSize());
  ++grid_.published;
  grid_changed_ = false;
  note_grid(*grid, first, after_loop);
}

void Publishing::note_grid(const mapping::MapGrid& grid, bool first, bool after_loop) {
  const auto s = grid_map_.statistics();
  if (first)
    shared_.notes.note("first CVO_GRID: " + std::to_string(grid.grid.width) + " x " + std::to_string(grid.grid.height) +
                       " cells of " + fixed(grid.grid.resolution, 3) + " m, up from the " +
                       std::string(mapping::up_source_name(grid.frame.up)));
  else if (after_loop)
    shared_.notes.note_limited("grid after loop", "CVO_GRID revision " + std::to_string(grid.revision) +
                                                      " after a loop: " + std::to_string(s.replaced_last) +
                                                      " keyframes re-placed in " + fixed(s.place_ms_last, 1) + " ms" +
                                                      (s.rebuilt_last ? " (rebuilt)" : ""));
}

void Publishing::status(std::int8_t state) {
  const auto now = Clock::now();
  const auto& counters = shared_.counters;
  lcm::ProcessStatus s;
  s.process = kProcess;
  s.robot = config::robot_name(config::kHostName);  // its host
  s.session = 0;                                    // the back end is no tracker session
  // A store that does not keep every record is the daemon's degraded state (the stop says itself).
  const auto store = shared_.store ? shared_.store->health() : store::StoreHealth{};
  s.state = store.degraded() && state != cvo_lcm::status_t::STATE_STOPPING ? cvo_lcm::status_t::STATE_DEGRADED : state;
  s.unsaved_records = static_cast<std::int64_t>(store.unsaved);
  const double elapsed = std::chrono::duration<double>(now - last_status_).count();
  s.rate_hz = elapsed > 0 ? static_cast<double>(processed_ - processed_at_last_status_) / elapsed : 0;
  s.queue_depth = static_cast<std::int32_t>(shared_.queue.size());
  for (std::size_t k = 0; k < s.bad_messages.size(); ++k) s.bad_messages[k] = counters.bad_messages[k];
  s.bad_messages[cvo_lcm::status_t::BAD_CONTENT] += guard_.refused();  // records the mapper refused
  s.failed_frames = guard_.failed();                                   // records and steps it failed on
  s.queue_drops = counters.queue_drops;
  s.keyframes_requested = counters.keyframes_requested;
  s.keyframes_recovered = counters.keyframes_recovered;
  s.keyframes_lost = counters.keyframes_lost;
  s.bus = shared_.bus.status_bus();
  s.sender = shared_.bus.sender();
  const cvo_lcm::status_t message = status_message(std::move(s), shared_.notes);
  auth::publish(lcm_, shared_.bus.signer(), "CVO_STATUS", message);
  const std::string summary = text(summary_) + "; " + text(grid_, grid_map_.statistics()) + "; " +
                              text("CVO_MAP_CORRECTION", corrections_) + ", " + text("CVO_MAP", maps_);
  shared_.systemd.status(store.degraded() ? "degraded: " + describe(store) + "; " + summary : summary);
  processed_at_last_status_ = processed_;
  last_status_ = now;
}

}  // namespace cvo::daemon::backendd
