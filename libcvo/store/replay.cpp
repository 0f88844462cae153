#include "libcvo/store/replay.hpp"

#include <exception>
#include <utility>
#include <variant>

#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/store/merge_record.hpp"

namespace cvo::store {

std::filesystem::path resolve_vocabulary(const std::string& setting) {
  return setting == "default" ? loop_closure::default_vocabulary_file() : std::filesystem::path(setting);
}

std::optional<Identified> let_in_stored(MessageDoor& door, RecordKind kind, const std::uint8_t* data, std::size_t size,
                                        std::string* why) {
  std::string error;
  auto message = identify(kind, data, size, &error, nullptr);
  if (!message) {
    *why = "stored record skipped: " + error;
    return std::nullopt;
  }
  const auto crc = content_crc(data, size);
  if (door.check(message->key, crc) != Admission::kNew) {
    *why = "stored record skipped: " + describe(message->key) + " is in the store twice";
    return std::nullopt;
  }
  door.admit(message->key, crc);
  return message;
}

Replayed replay(MessageDoor& door, slam::Mapper& mapper, RecordKind kind, const std::uint8_t* data, std::size_t size) {
  Replayed out;
  if (kind == RecordKind::kMerge) return replay_merge(mapper, data, size);
  if (kind == RecordKind::kSettled) return replay_settled(mapper, data, size);
  if (kind == RecordKind::kTally) {
    const auto tally = decode_tally(data, size, &out.why);
    if (!tally) return {"stored record skipped: " + out.why, std::nullopt};
    try {
      mapper.apply_tally(*tally);
    } catch (const std::exception& e) {
      return {"not applied: " + std::string(e.what()), std::nullopt};
    }
    return {};
  }
  const auto message = let_in_stored(door, kind, data, size, &out.why);
  if (!message) return out;
  auto value = usable(*message, &out.why, nullptr);
  if (!value) return {"stored " + describe(message->key) + " unreadable: " + out.why, std::nullopt};
  try {
    if (const auto* k = std::get_if<lcm::Keyframe>(&*value)) {
      if (apply(mapper, *k).duplicate) return {};
    } else {
      apply(mapper, std::get<LocalGraphRecord>(*value));
    }
  } catch (const std::exception& e) {  // slam::MapperError: nothing changed
    return {"not applied: " + std::string(e.what()), std::nullopt};
  }
  out.value = std::move(value);
  return out;
}

Replayed replay_merge(slam::Mapper& mapper, const std::uint8_t* data, std::size_t size) {
  std::string error;
  const auto merge = decode_merge(data, size, &error);
  if (!merge) return {"stored record skipped: " + error, std::nullopt};
  try {
    mapper.apply_merge(*merge);        // false: merged so by its keyframe's own replay already
  } catch (const std::exception& e) {  // slam::MapperError: nothing changed
    return {"not applied: " + std::string(e.what()), std::nullopt};
  }
  return {};
}

Replayed replay_settled(slam::Mapper& mapper, const std::uint8_t* data, std::size_t size) {
  std::string error;
  const auto edge = decode_settled(data, size, &error);
  if (!edge) return {"stored record skipped: " + error, std::nullopt};
  try {
    mapper.apply_settled(*edge);
  } catch (const std::exception& e) {  // slam::MapperError: nothing changed
    return {"not applied: " + std::string(e.what()), std::nullopt};
  }
  return {};
}

slam::KeyframeOutcome apply(slam::Mapper& mapper, const lcm::Keyframe& k) {
  return mapper.add_keyframe({k.session, k.id, k.frame, k.pose, k.cloud, k.robot});
}

std::vector<core::SessionId> apply(slam::Mapper& mapper, const LocalGraphRecord& record) {
  return mapper.add_local_graph(record.session, record.keyframe_id, record.graph);
}

}  // namespace cvo::store
