#pragma once
// The pixel formats of V4L2 RGB-D cameras, converted into core::RgbdFrame's images. Pure
// functions: no device involved, so they are tested with known pixel values.
//
// Each writes into the given Mat (reallocating it only when its size or type differs)
// and returns an empty string, or why the buffer is unusable (too short, does not decode).
#include <cstdint>
#include <span>
#include <string>

#include <opencv2/core/mat.hpp>

namespace cvo::drivers {

/// YUYV 4:2:2 (Y0 U Y1 V for each pair of pixels; ITU-R BT.601 limited range, as UVC cameras
/// send it) to BGR CV_8UC3. bytes_per_line >= 2 * width (V4L2 rows may be padded).
std::string yuyv_to_bgr(std::span<const std::uint8_t> data, int width, int height, int bytes_per_line, cv::Mat& bgr);

/// One Motion-JPEG frame to BGR CV_8UC3 (libcvo/image's TurboJPEG); its header must say width x
/// height. (libjpeg-turbo supplies the standard Huffman tables that MJPEG frames usually leave out.)
std::string mjpeg_to_bgr(std::span<const std::uint8_t> data, int width, int height, cv::Mat& bgr);

/// Z16 (16-bit little-endian depth, 0 = no measurement) to CV_16UC1, each value times `scale`,
/// rounded and saturated at 65535 (scale 1 copies): converts the device's depth unit into the
/// intrinsics' depth_scale. bytes_per_line >= 2 * width.
std::string z16_to_depth(std::span<const std::uint8_t> data, int width, int height, int bytes_per_line, double scale,
                         cv::Mat& depth);

/// A V4L2 fourcc as text, e.g. "YUYV", "MJPG", "Z16 ".
std::string fourcc_text(std::uint32_t fourcc);

}  // namespace cvo::drivers
