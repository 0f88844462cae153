#include "libcvo/image/decode.hpp"

#include "libcvo/image/format.hpp"
#include "libcvo/image/jpeg.hpp"
#include "libcvo/image/png.hpp"
#include "libcvo/image/webp.hpp"

namespace cvo::image {

std::string decode_colour(std::span<const std::uint8_t> bytes, cv::Mat& bgr, cv::Size expected) {
  const auto format = format_of(bytes);
  if (!format) return "neither PNG, JPEG nor WebP (no signature of one)";
  switch (*format) {
    case Format::kPng: return decode_png(bytes, PngPixels::kBgr8, bgr, expected);
    case Format::kJpeg: return decode_jpeg(bytes, bgr, expected);
    case Format::kWebp: return decode_webp(bytes, bgr, expected);
  }
  return "unknown format";
}

}  // namespace cvo::image
