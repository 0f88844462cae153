#pragma once
// Why a received message (or one of its images, or a frame from a driver) was refused: the one
// list of refusal kinds, shared by the decoders (decode.hpp, the from_message conversions), the
// frame sources (drivers/frame_source.hpp) and CVO_STATUS, whose bad_messages array it indexes.
// In core, free of the generated headers, so that the drivers' interface and every daemon can use
// it without the wire library; libcvo/lcm/tracker_messages.cpp checks each value against
// cvo_lcm::status_t's BAD_* constant by static_assert.
#include <cstdint>

namespace cvo::core {

enum class BadKind : std::int32_t {
  kTooShort = 0,         // shorter than the 8-byte fingerprint
  kFingerprint = 1,      // another message type, or another schema of this one
  kBody = 2,             // counts that do not fit, a truncated or corrupt body, trailing bytes
  kVersion = 3,          // our type, another `version`
  kContent = 4,          // decodes, but malformed: sizes that do not match, images that do not decode, ...
  kConflict = 5,         // contradicts what was accepted before
  kUnknownKeyframe = 6,  // names a keyframe the receiver does not have
  kNotFinite = 7,        // a NaN or infinite pose, point or number
  kInformation = 8,      // an information matrix that is not symmetric positive definite
  kImageFormat = 9,      // an image that is not the format its encoding field declares
  kImageSize = 10,       // an image header with another size or depth than the message, or too large
  kStale = 11,           // a CVO_MAP not newer than the last one applied
  kForeign = 12,         // a CVO_MAP without an entry for this tracker's session
  kImplausible = 13,     // a CVO_MAP correction that jumps further than allowed
  kAuth = 14,            // no valid authenticator under a key the receiver holds (libcvo/auth)
  kReplay = 15,          // authentic, but its counter was seen already or is too old (libcvo/auth)
  kQuota = 16,           // past the bound of what its session or sender may store (cvo-backendd)
};
inline constexpr int kNumBadKinds = 17;

/// "too short", "fingerprint", ..., as cvo-log and the daemons' notes name them.
const char* to_string(BadKind kind);

}  // namespace cvo::core
