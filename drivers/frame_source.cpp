#include "drivers/frame_source.hpp"

namespace cvo::drivers {

const char* to_string(ReadStatus status) {
  switch (status) {
    case ReadStatus::kFrame: return "frame";
    case ReadStatus::kTimeout: return "timeout";
    case ReadStatus::kEndOfStream: return "end of stream";
    case ReadStatus::kBadInput: return "bad input";
    case ReadStatus::kDisconnected: return "disconnected";
  }
  return "?";
}

}  // namespace cvo::drivers
