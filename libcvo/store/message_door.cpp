#include "libcvo/store/message_door.hpp"

#include <utility>

#include "cvo_lcm/status_t.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/lcm/local_graph_conversion.hpp"
#include "libcvo/slam/mapper.hpp"

namespace cvo::store {

std::string describe(const MessageKey& key) {
  const std::string keyframe = "keyframe " + std::to_string(key.id) + " of session " + core::session_name(key.session);
  return key.kind == RecordKind::kKeyframe ? keyframe : "the local graph of " + keyframe;
}

std::optional<Identified> identify(RecordKind kind, const std::uint8_t* data, std::size_t size, std::string* error,
                                   std::size_t* bad) {
  lcm::DecodeFailure failure{};
  const auto length = static_cast<int>(size);
  std::optional<Identified> out;
  if (kind == RecordKind::kKeyframe) {
    if (auto m = lcm::decode<cvo_lcm::keyframe_t>(data, length, error, &failure)) {
      const MessageKey key{kind, m->session, m->id};
      out = Identified{key, std::move(*m)};
    }
  } else if (auto m = lcm::decode<cvo_lcm::local_graph_t>(data, length, error, &failure)) {
    const MessageKey key{kind, m->session, m->keyframe_id};
    out = Identified{key, std::move(*m)};
  }
  if (!out && bad != nullptr) *bad = static_cast<std::size_t>(failure);
  return out;
}

std::optional<RecordValue> usable(const Identified& message, std::string* error, std::size_t* bad) {
  auto failure = lcm::ContentFailure::kContent;
  std::optional<RecordValue> value;
  if (const auto* k = std::get_if<cvo_lcm::keyframe_t>(&message.message)) {
    if (auto keyframe = lcm::from_message(*k, error, &failure)) value = std::move(*keyframe);
  } else {
    const auto& g = std::get<cvo_lcm::local_graph_t>(message.message);
    if (auto graph = lcm::from_message(g, error, &failure))
      value = LocalGraphRecord{g.session, g.keyframe_id, std::move(*graph)};
  }
  if (!value && bad != nullptr) *bad = static_cast<std::size_t>(failure);
  return value;
}

Admission MessageDoor::check(const MessageKey& key, std::uint32_t crc) const {
  const auto it = crc_.find(key);
  if (it == crc_.end()) return Admission::kNew;
  return it->second == crc ? Admission::kRepeat : Admission::kConflict;
}

}  // namespace cvo::store
