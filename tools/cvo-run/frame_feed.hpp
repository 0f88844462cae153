#pragma once
// One SEQUENCE of cvo-run: a TUM folder, or any source cvo-trackerd reads (`openni2:FILE.oni`,
// `lcm:file://LOG`, `tum:DIR`, a device), so that a recording is measured offline with one
// command, every frame tracked in order (a source is read unpaced: as fast as it is tracked).
// A source is opened, and its first frame read, before the run: what cannot be read fails at once.
#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "drivers/frame_source.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/io/tum_dataset.hpp"

namespace cvo::tools {

/// Whether SEQUENCE names a source (it starts with a scheme: tum:, lcm:, openni2:, v4l2:).
bool is_source_spec(const std::string& sequence);

class FrameFeed {
 public:
  /// A frame, a frame that could not be read (index, timestamp, why) or the end.
  struct Item {
    enum class Kind { kFrame, kBad, kEnd } kind = Kind::kEnd;
    std::optional<core::RgbdFrame> frame;
    std::size_t index = 0;
    double timestamp = 0;
    std::string error;
  };

  /// A folder (io::TumSequence with `options`), or a source; options.intrinsics (an explicit
  /// camera) overrides a source's own as a folder's, options.max_frames stops either. Throws io::InputError (a
  /// SourceError for a source) when it cannot be opened or, a source, gives no frame.
  static FrameFeed open(const std::string& sequence, const io::TumOptions& options);

  [[nodiscard]] const core::Intrinsics& intrinsics() const;
  [[nodiscard]] const core::Trajectory& groundtruth() const;  // empty for a source
  /// Frames to expect (the progress bar's total); a source's count is unknown: 0.
  [[nodiscard]] std::size_t expected_frames() const;
  [[nodiscard]] std::string describe() const;

  Item next();

 private:
  FrameFeed() = default;
  Item next_from_source();

  std::optional<io::TumSequence> folder_;
  std::unique_ptr<drivers::FrameSource> source_;
  std::optional<core::RgbdFrame> ahead_;  // a source's frame read before it was asked for
  core::Intrinsics intrinsics_;
  core::Trajectory no_groundtruth_;
  std::size_t max_frames_ = 0, read_ = 0;
};

}  // namespace cvo::tools
