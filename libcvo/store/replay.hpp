#pragma once
// A stored record replayed into slam::Mapper, the one way cvo-backendd does it at start-up and
// cvo-map and cvo-run --mode localize do it for a whole store: through the door (message_door.hpp),
// its content checked, then applied (README.md: "Replay").
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "libcvo/core/session.hpp"
#include "libcvo/slam/mapper.hpp"
#include "libcvo/store/message_door.hpp"
#include "libcvo/store/store_records.hpp"

namespace cvo::store {

/// The vocabulary file a config names (backendd.vocabulary): "default" is
/// loop_closure::default_vocabulary_file(); anything else a path.
std::filesystem::path resolve_vocabulary(const std::string& setting);

/// A stored record's payload through `door`: its message, decoded (no image decoded yet), once
/// let in. nullopt, with *why ("stored record skipped: ..."), when it does not decode (another
/// schema) or its name was let in before (the store holds it twice).
std::optional<Identified> let_in_stored(MessageDoor& door, RecordKind kind, const std::uint8_t* data, std::size_t size,
                                        std::string* why);

/// A stored record replayed whole: let in, checked, applied. `why` is "" when it was used (a
/// keyframe the mapper holds already: used, `value` empty), else why not ("stored record skipped:
/// ...", "stored ... unreadable: ...", "not applied: ..."); `value` is what was applied.
struct Replayed {
  std::string why;
  std::optional<RecordValue> value;
};
Replayed replay(MessageDoor& door, slam::Mapper& mapper, RecordKind kind, const std::uint8_t* data, std::size_t size);

/// A merge record (merge_record.hpp) applied to the mapper (Mapper::apply_merge), not through the
/// door: it names no message. A merge its keyframe's replay made already is used, changing nothing.
Replayed replay_merge(slam::Mapper& mapper, const std::uint8_t* data, std::size_t size);
/// A settled record (merge_record.hpp) applied likewise (Mapper::apply_settled).
Replayed replay_settled(slam::Mapper& mapper, const std::uint8_t* data, std::size_t size);

/// A keyframe into the mapper; throws slam::MapperError when it cannot be applied (nothing changed).
slam::KeyframeOutcome apply(slam::Mapper& mapper, const lcm::Keyframe& keyframe);
/// A local graph into the mapper: the sessions it placed in the map; throws as above.
std::vector<core::SessionId> apply(slam::Mapper& mapper, const LocalGraphRecord& record);

}  // namespace cvo::store
