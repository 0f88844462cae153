#include "tools/cvo-map/store_map.hpp"

#include <exception>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

#include "libcvo/config/mapper_parameters.hpp"
#include "libcvo/store/replay.hpp"
#include "libcvo/store/store_records.hpp"

namespace cvo::tools {
namespace {

namespace fs = std::filesystem;
using namespace store;

// The keyframe is in the SLAM map whether or not the mapping can use it (as in cvo-backendd).
void map_keyframe(const lcm::Keyframe& k, StoreMap& out) {
  try {
    out.mapping.add_keyframe({k.session, k.id}, k.frame);
  } catch (const std::invalid_argument& e) {
    out.not_mapped.push_back(describe(MessageKey{RecordKind::kKeyframe, k.session, k.id}) +
                             " left out of the grid: " + e.what());
  }
}

// One intact record through the door and into the mapper and the mapping, as cvo-backendd replays
// it; "" when it was used, else why not.
std::string use_record(const StoreSnapshot& snapshot, const IntactRecord& record, MessageDoor& door,
                       slam::Mapper& mapper, StoreMap& out) {
  const auto replayed =
      replay(door, mapper, record.kind, snapshot.payload(record), StoreSnapshot::payload_bytes(record));
  if (!replayed.value) return replayed.why;
  if (const auto* k = std::get_if<lcm::Keyframe>(&*replayed.value)) {
    ++out.keyframes;
    map_keyframe(*k, out);
  } else {
    ++out.local_graphs;
  }
  return {};
}

void note_damage(const fs::path& store, const StoreSnapshot& snapshot, StoreMap& out, std::ostream& problems) {
  const auto& scan = snapshot.scan;
  for (const auto& d : scan.damaged) {
    problems << store.string() << ": byte " << d.at << ": " << d.bytes << " damaged bytes skipped (" << d.why << ")\n";
    ++out.damaged_stretches;
    out.damaged_bytes += d.bytes;
  }
  if (scan.torn) out.torn_bytes = scan.torn->bytes;
  if (!scan.clean())
    problems << "warning: "
             << describe_damage(store, scan, "as a record being written or a crash leaves it", "is left out") << "\n";
}

void place(const slam::Mapper& mapper, StoreMap& out) {
  const slam::Map map = mapper.map();
  out.sessions = map.sessions.size();
  for (const auto& s : map.sessions) out.sessions_placed += s.placed ? 1 : 0;
  for (const auto* k : mapping::placed_keyframes(map)) out.trajectory.push_back(k->pose.translation());
  out.mapping.place(map);
}

}  // namespace

StoreMap map_store(const fs::path& store, const config::Config& config, loop_closure::Vocabulary vocabulary,
                   std::ostream& problems) {
  const StoreSnapshot snapshot = read_store(store);
  StoreMap out{.mapping = mapping::Mapping(config.mapping)};
  note_damage(store, snapshot, out, problems);
  slam::Mapper mapper(std::move(vocabulary), config::mapper_parameters(config));
  MessageDoor door;
  for (const auto& record : snapshot.scan.records) {
    ++out.records;
    const auto not_mapped = out.not_mapped.size();
    if (const auto why = use_record(snapshot, record, door, mapper, out); !why.empty()) {
      problems << store.string() << ": record at byte " << record.at << ": " << why << "\n";
      ++out.skipped;
    }
    if (out.not_mapped.size() > not_mapped)
      problems << store.string() << ": record at byte " << record.at << ": " << out.not_mapped.back() << "\n";
  }
  // The final global optimisation, as cvo-backendd's at its stop (nothing to optimise before a
  // local graph).
  if (mapper.backend().local_graphs() > 0) mapper.finish();
  place(mapper, out);
  return out;
}

}  // namespace cvo::tools
