#pragma once
// What cvo-receive lets into the keyframe store. A keyframe is named by (session, id), a local
// graph by (session, its keyframe's id); each name is stored once. The same name again with the
// same bytes (the CRC-32 of the LCM payload) is a repeat, a re-send: not stored or used again.
// With other bytes it contradicts what was accepted and is refused (status_t::BAD_CONFLICT):
// stored, it would be replayed into the back end on every restart.
#include <compare>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "daemon/backendd/keyframe_store.hpp"

namespace cvo::daemon::backendd {

struct MessageKey {
  RecordKind kind = RecordKind::kKeyframe;
  std::int64_t session = 0;
  std::int64_t id = 0;  // the keyframe's id (a local graph: its keyframe's)
  auto operator<=>(const MessageKey&) const = default;
};

/// "keyframe 12 of session 0x…" / "the local graph of keyframe 12 of session 0x…" (core::session_name).
std::string describe(const MessageKey& key);

/// The name of a CVO_KEYFRAME / CVO_LOCAL_GRAPH payload, decoded as the wire allows (no image is
/// decoded). nullopt when it does not decode, with *error and *bad, the status_t::BAD_* index.
std::optional<MessageKey> identify(RecordKind kind, const std::uint8_t* data, std::size_t size, std::string* error,
                                   std::size_t* bad);

/// Whether the payload's content is usable (images decode, poses and points are finite, the graph
/// is well formed, its information matrices positive definite): what the back end will need of
/// it. false with *error and *bad, the status_t::BAD_* index (BAD_CONTENT, BAD_NOT_FINITE,
/// BAD_INFORMATION).
bool usable(RecordKind kind, const std::uint8_t* data, std::size_t size, std::string* error, std::size_t* bad);

enum class Admission { kNew, kRepeat, kConflict };

class MessageDoor {
 public:
  [[nodiscard]] Admission check(const MessageKey& key, std::uint32_t crc) const;
  /// Whether a message of this name was let in.
  [[nodiscard]] bool knows(const MessageKey& key) const { return crc_.contains(key); }
  /// Remembers a message that was let in (stored); a name already known keeps its first CRC.
  void admit(const MessageKey& key, std::uint32_t crc) { crc_.try_emplace(key, crc); }
  [[nodiscard]] std::size_t size() const { return crc_.size(); }

 private:
  std::map<MessageKey, std::uint32_t> crc_;
};

}  // namespace cvo::daemon::backendd
