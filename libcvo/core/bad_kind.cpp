#include "libcvo/core/bad_kind.hpp"

namespace cvo::core {

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
    case BadKind::kAuth: return "auth";
    case BadKind::kReplay: return "replay";
    case BadKind::kQuota: return "quota";
  }
  return "?";
}

}  // namespace cvo::core
