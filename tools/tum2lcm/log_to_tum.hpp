#pragma once
// An LCM log's CVO_RGBD frames -> a TUM RGB-D folder: rgb/ and depth/ PNGs named by timestamp,
// rgb.txt, depth.txt and camera.yaml (io::read_intrinsics_file's format), which TumSequence reads
// back. Colour is written as PNG whatever the message's encoding, so raw and PNG recordings come
// back bit-exact (a JPEG recording as its decoded pixels).
#include <cstddef>
#include <filesystem>
#include <string>

namespace cvo::tools {

struct LogToTumSummary {
  std::size_t frames = 0;
  std::size_t other_events = 0;  // events on other channels, skipped
};

/// Throws io::InputError naming the log (and the event) on an unreadable log, a message that does
/// not decode, intrinsics that change during the log or a log without frames; naming the output
/// file when it cannot be written.
LogToTumSummary log_to_tum(const std::filesystem::path& log, const std::filesystem::path& out_dir,
                           const std::string& channel);

}  // namespace cvo::tools
