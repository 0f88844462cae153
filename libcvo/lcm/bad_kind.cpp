#include "libcvo/lcm/bad_kind.hpp"

#include "cvo_lcm/status_t.hpp"

namespace cvo::lcm {
namespace {

using S = cvo_lcm::status_t;
constexpr bool same(BadKind kind, std::int32_t index) { return static_cast<std::int32_t>(kind) == index; }

// CVO_STATUS counts refusals at these indices: a kind added to one side only fails the build.
static_assert(same(BadKind::kTooShort, S::BAD_TOO_SHORT) && same(BadKind::kFingerprint, S::BAD_FINGERPRINT) &&
              same(BadKind::kBody, S::BAD_BODY) && same(BadKind::kVersion, S::BAD_VERSION) &&
              same(BadKind::kContent, S::BAD_CONTENT) && same(BadKind::kConflict, S::BAD_CONFLICT) &&
              same(BadKind::kUnknownKeyframe, S::BAD_UNKNOWN_KEYFRAME) && same(BadKind::kNotFinite, S::BAD_NOT_FINITE) &&
              same(BadKind::kInformation, S::BAD_INFORMATION) && same(BadKind::kImageFormat, S::BAD_IMAGE_FORMAT) &&
              same(BadKind::kImageSize, S::BAD_IMAGE_SIZE) && same(BadKind::kStale, S::BAD_STALE) &&
              same(BadKind::kForeign, S::BAD_FOREIGN) && same(BadKind::kImplausible, S::BAD_IMPLAUSIBLE));
static_assert(kNumBadKinds == S::NUM_BAD_KINDS && sizeof(S{}.bad_messages) / sizeof(std::int64_t) == kNumBadKinds);

}  // namespace

const char* to_string(BadKind kind) {
  switch (kind) {
    case BadKind::kTooShort: return "too short";
    case BadKind::kFingerprint: return "fingerprint";
    case BadKind::kBody: return "body";
    case BadKind::kVersion: return "version";
    case BadKind::kContent: return "content";
    case BadKind::kConflict: return "conflict";
    case BadKind::kUnknownKeyframe: return "unknown keyframe";
    case BadKind::kNotFinite: return "not finite";
    case BadKind::kInformation: return "information";
    case BadKind::kImageFormat: return "image format";
    case BadKind::kImageSize: return "image size";
    case BadKind::kStale: return "stale";
    case BadKind::kForeign: return "foreign";
    case BadKind::kImplausible: return "implausible";
  }
  return "?";
}

}  // namespace cvo::lcm
