#pragma once
// A record message (an encoded CVO_KEYFRAME or CVO_LOCAL_GRAPH) in slices that each travel in one
// datagram (CVO_KEYFRAME_CHUNK, proto/keyframe_chunk_t.lcm), and the slices put back together.
//
// Why: LCM sends a message larger than one UDP datagram in fragments of ~64 kB, and IP splits each
// into ~45 packets of a 1500-byte link; one lost packet loses the message. A keyframe is ~200
// packets, so a link losing a fraction p of its packets loses 1 - (1 - p)^200 of the keyframes
// (87 % at p = 1 %), and a re-send of all of it is lost as likely. In slices of D = MAX_DATA bytes a
// lost packet loses one slice, and only the missing slices are asked for again: a message of n
// slices needs about n / (1 - p) slices sent, whatever n.
//
// Slice k of a message of n bytes holds bytes [k·D, min(n, (k+1)·D)); a message of n bytes has
// ceil(n / D) slices. The message travels with its auth_t trailer zero (each slice is signed), and
// its content CRC (content_crc: the CRC-32 of its bytes before the trailer) in every slice, so that
// slices of two different messages of one name are never put together (each is assembled apart),
// and the message put together is checked whole.
#include <compare>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "cvo_lcm/keyframe_chunk_t.hpp"
#include "libcvo/core/bad_kind.hpp"

namespace cvo::lcm {

/// CRC-32 of an encoded message's bytes before its auth_t trailer (kAuthTrailerBytes): what it
/// says, not who signed it when (a re-send is signed afresh).
std::uint32_t content_crc(const std::uint8_t* data, std::size_t size);

/// A sliced message: keyframe `id` of `session`, or that keyframe's local graph
/// (`message`: keyframe_chunk_t::KEYFRAME or LOCAL_GRAPH).
struct SlicedName {
  std::int64_t session = 0;
  std::int64_t id = 0;
  std::int8_t message = cvo_lcm::keyframe_chunk_t::KEYFRAME;
  auto operator<=>(const SlicedName&) const = default;
};

/// Slices first .. first + count - 1.
struct SliceRange {
  std::int32_t first = 0;
  std::int32_t count = 0;
  bool operator==(const SliceRange&) const = default;
};

/// How many slices a message of `bytes` has.
std::int32_t slice_count(std::size_t bytes);

/// Slice `index` of `message` (its trailer zero), as its CVO_KEYFRAME_CHUNK (unsigned);
/// crc: content_crc of the message. index must be below slice_count(message.size()).
cvo_lcm::keyframe_chunk_t slice(std::span<const std::uint8_t> message, const SlicedName& name, std::uint32_t crc,
                                std::int32_t index);

/// The slices of `wanted` that a message of `bytes` has (a range reaching past its last slice ends
/// there; an empty range when it starts past it).
SliceRange clamp(SliceRange wanted, std::size_t bytes);

/// Slices put back together into their messages, within bounds: a receiver's memory of the messages
/// it holds in part. Single-threaded.
///
/// Competing messages of one name (a forger's first slice before the tracker's, or a re-send with
/// other content) are held apart by their CRC and size, at most max_per_name of them: a slice never
/// locks a name, and the first of them to complete with its CRC is handed out (its receiver decodes
/// it, and forget()s the name once one is let in).
///
/// Memory: each slice is held as it came (never a claimed size allocated ahead), charged its data
/// plus kSliceOverhead bytes; bytes() <= max_bytes, so in all at most
/// max_bytes + max_messages * (sizeof(Partial) + a map node) whatever comes (a flood included).
/// To make room, the message holding the fewest slices is dropped (the least recently added to of
/// those): a flood of first slices evicts its own, not a message well under way.
class ChunkAssembly {
 public:
  struct Limits {
    std::size_t max_messages = 64;                   // held in part at once
    std::size_t max_bytes = std::size_t{256} << 20;  // their room, in all (also the largest message)
    std::size_t max_per_name = 4;                    // competing messages of one name (other CRC or size)
  };
  static constexpr std::size_t kSliceOverhead = 96;  // a held slice's map node and vector, charged to bytes()
  explicit ChunkAssembly(Limits limits);
  ChunkAssembly() : ChunkAssembly(Limits{}) {}

  struct Added {
    enum class Outcome {
      kPartial,   // kept; the message is not complete yet
      kComplete,  // the last slice: `message` holds the message, checked against its CRC
      kRepeat,    // a slice held already
      kRefused,   // see `refusal` and `why`
    };
    Outcome outcome = Outcome::kPartial;
    std::vector<std::uint8_t> message;  // kComplete
    core::BadKind refusal = core::BadKind::kContent;
    std::string why;
  };
  /// Takes one decoded slice. Refused (BAD_CONTENT): an unknown message kind, a size outside
  /// [trailer + 8, max_bytes], an index past the last slice, a data size other than its slice's, a
  /// message whose slices put together do not give its CRC (all of it dropped). A slice of another
  /// CRC or size than the messages of its name held in part starts one of its own (past
  /// max_per_name, the one of that name holding the fewest slices goes).
  Added add(const cvo_lcm::keyframe_chunk_t& chunk);

  /// The slices missing of a message held in part (of competing ones, the one holding the most), as
  /// at most `max_ranges` ranges (>= 1): the closest holes are asked for as one range, with the few
  /// slices held between them. nullopt when nothing of it is held.
  [[nodiscard]] std::optional<std::vector<SliceRange>> missing(const SlicedName& name, std::size_t max_ranges) const;
  /// Drops every message of `name` held in part (one of that name was let in: the rest compete in vain).
  void forget(const SlicedName& name);

  [[nodiscard]] bool holds(const SlicedName& name) const { return of_name_count(name) > 0; }
  [[nodiscard]] std::size_t held() const { return partial_.size(); }
  [[nodiscard]] std::size_t bytes() const { return bytes_; }
  [[nodiscard]] std::int64_t dropped() const { return dropped_; }                // messages dropped for room
  [[nodiscard]] std::int64_t dropped_slices() const { return dropped_slices_; }  // the slices they held

 private:
  struct Key {  // one message: its name, CRC and size
    SlicedName name;
    std::uint32_t crc = 0;
    std::int32_t size = 0;
    auto operator<=>(const Key&) const = default;
  };
  struct Partial {
    std::map<std::int32_t, std::vector<std::uint8_t>> slices;  // by index, as they came
    std::int32_t count = 0;                                    // slices of the whole message
    std::uint64_t touched = 0;                                 // add() count when last added to
  };
  using Partials = std::map<Key, Partial>;
  [[nodiscard]] std::string check(const cvo_lcm::keyframe_chunk_t& chunk) const;  // empty: well formed
  [[nodiscard]] std::pair<Partials::const_iterator, Partials::const_iterator> of_name(const SlicedName& name) const;
  [[nodiscard]] std::size_t of_name_count(const SlicedName& name) const;
  static bool weaker(const Partials::value_type& a, const Partials::value_type& b);  // fewer slices, older
  static Partials::const_iterator weakest(Partials::const_iterator first, Partials::const_iterator last);
  void drop(Partials::const_iterator it);   // uncounted
  void evict(Partials::const_iterator it);  // counted: dropped(), dropped_slices()
  void make_room(const SlicedName& name);
  bool room_for(Partials::const_iterator keep, std::size_t bytes);
  Added complete(Partials::iterator it);

  Limits limits_;
  Partials partial_;
  std::size_t bytes_ = 0;
  std::uint64_t adds_ = 0;
  std::int64_t dropped_ = 0, dropped_slices_ = 0;
};

}  // namespace cvo::lcm
