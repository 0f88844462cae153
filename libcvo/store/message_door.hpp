#pragma once
// What is let into the keyframe store: a keyframe named by (session, id), a local graph by
// (session, its keyframe's id), each name stored once; the same name again is a repeat (same
// content: not used twice) or a conflict (other content: refused, status_t::BAD_CONFLICT). The
// decode on the way in, once (README.md: "The door").
#include <compare>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <variant>

#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/local_graph_t.hpp"
#include "libcvo/lcm/chunks.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/odometry/local_graph.hpp"
#include "libcvo/store/keyframe_store.hpp"

namespace cvo::store {

struct MessageKey {
  RecordKind kind = RecordKind::kKeyframe;
  std::int64_t session = 0;
  std::int64_t id = 0;  // the keyframe's id (a local graph: its keyframe's)
  auto operator<=>(const MessageKey&) const = default;
};

/// "keyframe 12 of session 0x…" / "the local graph of keyframe 12 of session 0x…" (core::session_name).
std::string describe(const MessageKey& key);

// A record is decoded once on its way in (its bytes go to the store): identify() turns the bytes
// into the LCM message, usable() the message into the value the back end applies; each takes what
// the step before gave, so nothing is decoded twice (the images above all).

/// A CVO_KEYFRAME / CVO_LOCAL_GRAPH payload decoded from the wire (no image decoded yet), and its name.
struct Identified {
  MessageKey key;
  std::variant<cvo_lcm::keyframe_t, cvo_lcm::local_graph_t> message;
};

/// A CVO_LOCAL_GRAPH as the back end applies it: the graph of keyframe (session, keyframe_id).
struct LocalGraphRecord {
  std::int64_t session = 0;
  std::int64_t keyframe_id = 0;
  odometry::LocalGraph graph;
};

/// What the back end applies of a record: a keyframe (images decoded) or a local graph.
using RecordValue = std::variant<lcm::Keyframe, LocalGraphRecord>;

/// The payload decoded as the wire allows, with its name. nullopt when it does not decode, with
/// *error and *bad, the status_t::BAD_* index.
std::optional<Identified> identify(RecordKind kind, const std::uint8_t* data, std::size_t size, std::string* error,
                                   std::size_t* bad);

/// The message's content when it is usable (images decode, poses and points are finite, the graph
/// is well formed, its information matrices positive definite): what the back end will apply.
/// nullopt with *error and *bad, the status_t::BAD_* index (BAD_CONTENT, BAD_NOT_FINITE,
/// BAD_INFORMATION, BAD_IMAGE_*).
std::optional<RecordValue> usable(const Identified& message, std::string* error, std::size_t* bad);

/// CRC-32 of a message's bytes before its auth_t trailer: what it says, not who signed it when.
using lcm::content_crc;

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

}  // namespace cvo::store
