#pragma once
// What the emulated camera sees: the frames of a TUM folder (read with io::TumSequence), encoded
// as the nodes stream them. Colour: YUYV (BT.601 limited range, as UVC cameras send it) or MJPEG
// (OpenCV's JPEG encoder with the Huffman tables left out, as UVC cameras send it). Depth: Z16,
// 16-bit little-endian in the configured unit. A node whose size differs from the recording's is
// given the recording's images resized to it (depth by nearest neighbour, so no invented depths).
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "libcvo/io/tum_dataset.hpp"
#include "tests/support/v4l2_emulator/config.hpp"

namespace cvo::drivers::v4l2_emulator {

/// BGR CV_8UC3 to YUYV 4:2:2, rows of exactly 2 * width bytes.
void bgr_to_yuyv(const cv::Mat& bgr, std::vector<std::uint8_t>& out);

/// A JPEG without its DHT segments: a decoder uses the standard tables (what UVC MJPEG is).
std::vector<std::uint8_t> encode_mjpeg(const cv::Mat& bgr);

/// Depth CV_16UC1 in `from_units` per metre to Z16 in `to_units` per metre (rounded, saturated).
void depth_to_z16(const cv::Mat& depth, double from_units, double to_units, std::vector<std::uint8_t>& out);

class Scene {
 public:
  /// Throws io::InputError when the folder does not open.
  Scene(const std::filesystem::path& tum, double depth_units_per_metre);

  [[nodiscard]] std::size_t size() const { return sequence_.size(); }

  /// Entry `entry` (< size()) as `fourcc` at `size`: the bytes of one buffer. Any thread; the
  /// last entry read is kept, since both nodes ask for it in turn.
  std::vector<std::uint8_t> encode(std::size_t entry, std::uint32_t fourcc, FrameSize size);

 private:
  const core::RgbdFrame& read(std::size_t entry);

  io::TumSequence sequence_;
  double depth_units_per_metre_;
  std::mutex mutex_;
  std::optional<std::size_t> cached_entry_;
  core::RgbdFrame cached_;
};

}  // namespace cvo::drivers::v4l2_emulator
