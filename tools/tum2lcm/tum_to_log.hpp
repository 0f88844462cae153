#pragma once
// A TUM RGB-D folder -> an LCM log of CVO_RGBD frames, so a dataset becomes a recording exactly
// like one that lcm-logger makes of a camera driver: one event per frame, in recording order, the
// event timestamp being the frame's utime.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "libcvo/auth/key.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"

namespace cvo::tools {

struct TumToLogOptions {
  lcm::RgbdEncoding encoding;
  std::string channel = "CVO_RGBD";
  std::size_t max_frames = 0;  // 0 = all
  // The deployment's keys (--key-file): every event signed as a camera driver on the bus signs
  // (libcvo/auth, sender "tum2lcm"); null: unsigned, for an open bus.
  std::shared_ptr<const auth::KeyRing> keys;
};

struct LogSummary {
  std::size_t frames = 0;
  std::uintmax_t bytes = 0;  // of the log file
};

/// Throws io::InputError (naming the file) on an unreadable dataset or image, or an unwritable log.
LogSummary tum_to_log(const std::filesystem::path& tum_dir, const std::filesystem::path& log,
                      const TumToLogOptions& options);

}  // namespace cvo::tools
