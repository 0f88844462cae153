#pragma once
// A TUM RGB-D benchmark recording, read as a stream of frames.
//
// Layout: rgb.txt and depth.txt ("timestamp relative/path" per line, '#' comments), optional
// groundtruth.txt (a TUM trajectory), images next to them. Colour is PNG, JPEG or WebP, told by
// its signature (libcvo/image/decode.hpp; returned as BGR CV_8UC3), depth a 16-bit single-channel
// PNG. Colour and depth are paired as TUM's associate.py does (core::associate).
//
// Only the index (timestamps and paths) is held in memory; each frame's images are read when it
// is asked for, so a sequence of any length costs one frame of memory.
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "libcvo/core/camera.hpp"
#include "libcvo/core/parameters.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/io/input_error.hpp"

namespace cvo::io {

/// One frame's images could not be used (missing, unreadable, corrupt, wrong type or size). The
/// message names the image file; frame_index() is the frame's position in the sequence.
class FrameError : public InputError {
 public:
  FrameError(std::size_t frame_index, const std::filesystem::path& image, const std::string& what)
      : InputError(image, "frame " + std::to_string(frame_index) + ": " + what), frame_index_(frame_index) {}
  [[nodiscard]] std::size_t frame_index() const { return frame_index_; }

 private:
  std::size_t frame_index_;
};

struct TumOptions {
  core::DatasetParameters dataset;  // max_association_dt (libcvo/core/parameters.hpp)
  // nullopt: the folder's own camera.yaml when it has one, else the preset guessed from the
  // folder name (guess_camera_preset). A width and height
  // of 0 (an ETH3D calibration) are taken from the first colour image.
  std::optional<core::Intrinsics> intrinsics;
  std::size_t max_frames = 0;  // 0 = all
};

/// "tum_fr1".."tum_fr3" when the folder's name says which Freiburg sensor recorded it
/// (rgbd_dataset_freiburg2_xyz, fr1_desk, ...), else nullopt.
std::optional<std::string> guess_camera_preset(const std::filesystem::path& dir);

/// One associated frame of the index.
struct TumFrameFiles {
  double timestamp = 0;  // colour
  std::filesystem::path rgb;
  double depth_timestamp = 0;
  std::filesystem::path depth;
};

class TumSequence {
 public:
  /// Reads the index files and the ground truth. Throws InputError on a missing folder or index
  /// file, a malformed line (file:line), two different images with one timestamp, no camera, or
  /// no colour frame with a depth frame within max_association_dt. Images are not opened here,
  /// except the first colour image when the image size must come from it.
  static TumSequence open(const std::filesystem::path& dir, const TumOptions& options = {});

  [[nodiscard]] std::size_t size() const { return frames_.size(); }  // associated frames
  [[nodiscard]] std::size_t position() const { return next_; }       // the frame next() reads
  void seek(std::size_t position) { next_ = position; }

  /// The next frame in time order; nullopt at the end. Throws FrameError when that frame's images
  /// cannot be used; the sequence has then moved past it, so the caller may report and go on.
  std::optional<core::RgbdFrame> next();

  /// Frame i (0 <= i < size(), else std::out_of_range), independent of the stream position; safe
  /// to call from several threads. Throws FrameError as next() does.
  [[nodiscard]] core::RgbdFrame read(std::size_t i) const;

  [[nodiscard]] const std::vector<TumFrameFiles>& files() const { return frames_; }
  [[nodiscard]] const core::Trajectory& groundtruth() const { return groundtruth_; }  // empty without the file
  [[nodiscard]] const core::Intrinsics& intrinsics() const { return intrinsics_; }
  [[nodiscard]] const std::filesystem::path& directory() const { return dir_; }

 private:
  TumSequence() = default;

  std::filesystem::path dir_;
  std::vector<TumFrameFiles> frames_;
  core::Trajectory groundtruth_;
  core::Intrinsics intrinsics_;
  std::size_t next_ = 0;
};

}  // namespace cvo::io
