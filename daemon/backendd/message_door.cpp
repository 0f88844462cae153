#include "daemon/backendd/message_door.hpp"

#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/local_graph_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/lcm/local_graph_conversion.hpp"
#include "libcvo/slam/mapper.hpp"

namespace cvo::daemon::backendd {

std::string describe(const MessageKey& key) {
  const std::string keyframe = "keyframe " + std::to_string(key.id) + " of session " + core::session_name(key.session);
  return key.kind == RecordKind::kKeyframe ? keyframe : "the local graph of " + keyframe;
}

std::optional<MessageKey> identify(RecordKind kind, const std::uint8_t* data, std::size_t size, std::string* error,
                                   std::size_t* bad) {
  lcm::DecodeFailure failure{};
  const auto length = static_cast<int>(size);
  std::optional<MessageKey> key;
  if (kind == RecordKind::kKeyframe) {
    if (const auto m = lcm::decode<cvo_lcm::keyframe_t>(data, length, error, &failure))
      key = MessageKey{kind, m->session, m->id};
  } else if (const auto m = lcm::decode<cvo_lcm::local_graph_t>(data, length, error, &failure)) {
    key = MessageKey{kind, m->session, m->keyframe_id};
  }
  if (!key && bad != nullptr) *bad = static_cast<std::size_t>(failure);
  return key;
}

bool usable(RecordKind kind, const std::uint8_t* data, std::size_t size, std::string* error, std::size_t* bad) {
  const auto length = static_cast<int>(size);
  auto failure = lcm::ContentFailure::kContent;
  bool ok = false;
  if (kind == RecordKind::kKeyframe) {
    const auto m = lcm::decode<cvo_lcm::keyframe_t>(data, length, error);
    ok = m && lcm::from_message(*m, error, &failure).has_value();
  } else {
    const auto m = lcm::decode<cvo_lcm::local_graph_t>(data, length, error);
    ok = m && lcm::from_message(*m, error, &failure).has_value();
  }
  if (!ok && bad != nullptr) *bad = static_cast<std::size_t>(failure);
  return ok;
}

Admission MessageDoor::check(const MessageKey& key, std::uint32_t crc) const {
  const auto it = crc_.find(key);
  if (it == crc_.end()) return Admission::kNew;
  return it->second == crc ? Admission::kRepeat : Admission::kConflict;
}

}  // namespace cvo::daemon::backendd
