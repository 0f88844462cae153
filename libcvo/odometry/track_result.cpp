#include "libcvo/odometry/track_result.hpp"

namespace cvo::odometry {

const char* to_string(TrackStatus status) {
  switch (status) {
    case TrackStatus::kOk: return "ok";
    case TrackStatus::kFirstFrame: return "first_frame";
    case TrackStatus::kSelectionFailed: return "selection_failed";
    case TrackStatus::kRegistrationFailed: return "registration_failed";
  }
  return "unknown";
}

}  // namespace cvo::odometry
