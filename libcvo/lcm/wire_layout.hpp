#pragma once
// Where the element counts of each cvo_lcm type sit in its encoding, so that decode() can check
// them against the buffer before the lcm-gen code allocates.
//
// Why: lcm-gen's decoders resize each variable-length array to the count read from the wire before
// checking that the bytes are there, so one corrupt count (with a valid fingerprint) can ask for
// gigabytes. Every cvo_lcm type with arrays puts all its counts in a fixed-size header ahead of
// all variable-length data (proto/*.lcm), which makes this check a simple table lookup.
//
// Offsets are in bytes from the start of the body, i.e. after the 8-byte fingerprint. The tests
// check this table against lcm-gen's own encodings.
//
// Every type sent on a channel ends with auth_t (proto/auth_t.lcm), fixed size, after all
// variable-length data: its kAuthTrailerBytes are the last bytes of every encoded message
// (libcvo/auth signs and verifies them there, on the raw buffer).
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace cvo::lcm {

struct CountField {
  std::string_view name;
  int offset;             // of the big-endian int32 count in the body
  int bytes_per_element;  // wire bytes each counted element adds (all arrays sized by this count)
};

struct WireLayout {
  int header_bytes = 0;                // body bytes before the first variable-length array
  std::span<const CountField> counts;  // empty: the type has no variable-length arrays
  // Strings, consecutive, from this body offset to the end (-1: none; kStringsAfterArrays: right
  // after the arrays the counts size). lcm-gen's decoder reads a zero or negative string length as
  // a huge size (undefined behaviour for INT32_MIN), so each length is checked to be in
  // 1..remaining bytes first, and the text to end at its only NUL.
  int strings_at = -1;
  int num_strings = 0;
  // -1, or the index in `counts` of the count that gives as many more strings after those (map_t's
  // robots, one per session).
  int strings_counted_by = -1;
};
inline constexpr int kStringsAfterArrays = -2;

/// auth_t on the wire: sender, counter, key id (int64 each), authenticator (32 bytes).
inline constexpr int kAuthTrailerBytes = 3 * 8 + 32;

/// The layout of the type named by lcm-gen's getTypeName() ("rgbd_frame_t", ...); an empty layout
/// for types with neither arrays nor strings.
WireLayout wire_layout(std::string_view type_name);

/// Empty when the counts and string lengths in body[0, size) fit the body, else why not. A body
/// shorter than the header is not judged here (the lcm-gen decoder reports it as truncated).
std::string check_counts(const WireLayout& layout, const std::uint8_t* body, int size);

}  // namespace cvo::lcm
