#include "daemon/backendd/backendd.hpp"

#include <chrono>
#include <filesystem>
#include <thread>
#include <utility>

#include <lcm/lcm-cpp.hpp>

#include "daemon/backendd/map_summary.hpp"
#include "daemon/common/signals.hpp"
#include "daemon/common/supervise.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/store/replay.hpp"
#include "libcvo/store/store_records.hpp"

namespace cvo::daemon::backendd {

using namespace std::chrono_literals;

Backendd::Backendd(config::Config config) : shared_(std::make_unique<Shared>(std::move(config))) {
  const auto& b = shared_->config.backendd;
  if (b.exit_on_eof && !is_log(b.lcm_url))
    throw io::InputError("backendd.exit_on_eof", "needs a file:// lcm_url (a log that ends), not '" + b.lcm_url + "'");
  // cvo-receive opens its own provider in its thread: one that cannot open would leave it deaf for
  // good (publish_url's check below sees lcm_url only when the two are one).
  if (!::lcm::LCM(b.lcm_url).good())
    throw io::InputError("backendd.lcm_url", "cannot open LCM provider '" + b.lcm_url + "'");
  map_building_ =
      std::make_unique<MapBuilding>(*shared_, loop_closure::Vocabulary::load(store::resolve_vocabulary(b.vocabulary)));
  if (!map_building_->publishing_good())
    throw io::InputError(b.publish_url == "lcm_url" ? "backendd.lcm_url" : "backendd.publish_url",
                         "cannot open LCM provider '" + publish_url(b) + "'");
  if (shared_->localization())
    read_map_store();
  else
    open_store();
  receiving_ = std::make_unique<Receiving>(*shared_);  // notes the store's state: a new store on a full disk
}

void Backendd::open_store() {
  const auto& b = shared_->config.backendd;
  std::string warning;
  shared_->store = std::make_unique<store::KeyframeStore>(b.store, recovered_, warning, b.unsaved_records_max);
  if (!warning.empty()) shared_->notes.note("warning: " + warning);
  map_building_->keep_merges_in(*shared_->store);
}

// The stored map, read without changing a byte of it; damage costs only the records it touches.
void Backendd::read_map_store() {
  const auto& file = shared_->config.backendd.store;
  if (!std::filesystem::exists(file))
    throw io::InputError("backendd.store", "no keyframe store '" + file + "': localization needs a stored map");
  const store::StoreSnapshot snapshot = store::read_store(file);
  if (!snapshot.scan.clean())
    shared_->notes.note("warning: " +
                        store::describe_damage(file, snapshot.scan, "a write under way", "it is left out"));
  for (const auto& r : snapshot.scan.records) {
    const std::uint8_t* payload = snapshot.payload(r);
    recovered_.push_back({r.kind, {payload, payload + store::StoreSnapshot::payload_bytes(r)}});
  }
}

Backendd::~Backendd() = default;

int Backendd::run() {
  Shared& s = *shared_;
  const auto recovered = recovered_.size();
  receiving_->let_in(std::exchange(recovered_, {}));
  s.notes.note(s.bus.describe());
  s.notes.note((s.localization() ? "localization in the map of " : "store ") + s.config.backendd.store + " (" +
               std::to_string(recovered) + " records " + (s.localization() ? "read" : "recovered") + "), LCM " +
               s.config.backendd.lcm_url);
  std::thread receive([this] { receiving_->run(); });
  std::thread work([this] { map_building_->run(); });
  s.systemd.ready();
  // The worker may be inside a long optimisation: allow it the watchdog's full interval.
  const Heartbeat* const beats[] = {&s.receive_heartbeat, &s.work_heartbeat};
  const auto ended = [&] { return s.input_ended && s.config.backendd.exit_on_eof; };
  if (const auto signal = supervise(s.systemd, {beats, 30s}, ended)) {
    const auto budget =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s.config.backendd.stop_timeout_s));
    s.stop_deadline = (Clock::now() + budget).time_since_epoch().count();
    s.notes.note(std::string("stopping on ") + signal_name(*signal) + " within " +
                 fixed(s.config.backendd.stop_timeout_s, 1) + " s (backendd.stop_timeout_s)");
  }
  s.stop = true;
  receive.join();
  work.join();
  return 0;
}

}  // namespace cvo::daemon::backendd
