// core::BadKind's values are CVO_STATUS's bad_messages indices (cvo_lcm::status_t's BAD_*): checked
// here, in the wire library, because core does not see the generated headers.
#include "cvo_lcm/status_t.hpp"
#include "libcvo/core/bad_kind.hpp"

namespace cvo::lcm {
namespace {

using core::BadKind;
using S = cvo_lcm::status_t;
constexpr bool same(BadKind kind, std::int32_t index) { return static_cast<std::int32_t>(kind) == index; }

// CVO_STATUS counts refusals at these indices: a kind added to one side only fails the build.
static_assert(same(BadKind::kTooShort, S::BAD_TOO_SHORT) && same(BadKind::kFingerprint, S::BAD_FINGERPRINT) &&
              same(BadKind::kBody, S::BAD_BODY) && same(BadKind::kVersion, S::BAD_VERSION) &&
              same(BadKind::kContent, S::BAD_CONTENT) && same(BadKind::kConflict, S::BAD_CONFLICT) &&
              same(BadKind::kUnknownKeyframe, S::BAD_UNKNOWN_KEYFRAME) &&
              same(BadKind::kNotFinite, S::BAD_NOT_FINITE) && same(BadKind::kInformation, S::BAD_INFORMATION) &&
              same(BadKind::kImageFormat, S::BAD_IMAGE_FORMAT) && same(BadKind::kImageSize, S::BAD_IMAGE_SIZE) &&
              same(BadKind::kStale, S::BAD_STALE) && same(BadKind::kForeign, S::BAD_FOREIGN) &&
              same(BadKind::kImplausible, S::BAD_IMPLAUSIBLE) && same(BadKind::kAuth, S::BAD_AUTH) &&
              same(BadKind::kReplay, S::BAD_REPLAY) && same(BadKind::kQuota, S::BAD_QUOTA));
static_assert(core::kNumBadKinds == S::NUM_BAD_KINDS &&
              sizeof(S{}.bad_messages) / sizeof(std::int64_t) == core::kNumBadKinds);

}  // namespace
}  // namespace cvo::lcm
