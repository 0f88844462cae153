#include "drivers/v4l2_formats.hpp"

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "libcvo/image/jpeg.hpp"

namespace cvo::drivers {
namespace {

std::string check_layout(std::size_t size, int width, int height, int bytes_per_line, int bytes_per_pixel) {
  if (width <= 0 || height <= 0) return "image size " + std::to_string(width) + "x" + std::to_string(height);
  if (bytes_per_line < width * bytes_per_pixel)
    return "rows of " + std::to_string(bytes_per_line) + " bytes cannot hold " + std::to_string(width) + " pixels";
  // The last row needs only its pixels, not its padding.
  const std::size_t needed =
      std::size_t(bytes_per_line) * std::size_t(height - 1) + std::size_t(width) * std::size_t(bytes_per_pixel);
  if (size < needed)
    return "a buffer of " + std::to_string(size) + " bytes is too short for " + std::to_string(width) + "x" +
           std::to_string(height) + " (" + std::to_string(needed) + " bytes)";
  return {};
}

}  // namespace

std::string yuyv_to_bgr(std::span<const std::uint8_t> data, int width, int height, int bytes_per_line, cv::Mat& bgr) {
  if (auto bad = check_layout(data.size(), width, height, bytes_per_line, 2); !bad.empty()) return "YUYV: " + bad;
  if (width % 2 != 0) return "YUYV: odd width " + std::to_string(width);
  const cv::Mat yuyv(height, width, CV_8UC2, const_cast<std::uint8_t*>(data.data()), std::size_t(bytes_per_line));
  cv::cvtColor(yuyv, bgr, cv::COLOR_YUV2BGR_YUYV);
  return {};
}

std::string mjpeg_to_bgr(std::span<const std::uint8_t> data, int width, int height, cv::Mat& bgr) {
  if (data.empty()) return "MJPEG: empty frame";
  // Straight into `bgr` (kept at the stream's size: no allocation). On failure its pixels are
  // partly written, and the caller drops it. Warnings are accepted as OpenCV accepted them
  // (jpeg.hpp): the driver flags the frames it knows are incomplete.
  if (auto bad = image::decode_jpeg(data, bgr, {width, height}, image::JpegWarnings::kAccept); !bad.empty())
    return "MJPEG: frame does not decode (" + bad + ")";
  return {};
}

std::string z16_to_depth(std::span<const std::uint8_t> data, int width, int height, int bytes_per_line, double scale,
                         cv::Mat& depth) {
  if (auto bad = check_layout(data.size(), width, height, bytes_per_line, 2); !bad.empty()) return "Z16: " + bad;
  if (!(std::isfinite(scale) && scale > 0)) return "Z16: scale must be a positive number";
  depth.create(height, width, CV_16UC1);
  for (int r = 0; r < height; ++r) {
    const std::uint8_t* in = data.data() + std::size_t(r) * std::size_t(bytes_per_line);
    auto* out = depth.ptr<std::uint16_t>(r);
    for (int c = 0; c < width; ++c) {
      const auto raw = static_cast<std::uint16_t>(in[2 * c] | (in[2 * c + 1] << 8));  // little-endian on any host
      out[c] = scale == 1.0 ? raw : cv::saturate_cast<std::uint16_t>(raw * scale);
    }
  }
  return {};
}

std::string fourcc_text(std::uint32_t fourcc) {
  std::string text(4, ' ');
  for (int i = 0; i < 4; ++i) {
    const auto c = static_cast<char>((fourcc >> (8 * i)) & 0xff);
    text[static_cast<std::size_t>(i)] = c >= 32 && c < 127 ? c : '?';
  }
  return text;
}

}  // namespace cvo::drivers
