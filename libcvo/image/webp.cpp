#include "libcvo/image/webp.hpp"

#include <webp/decode.h>

namespace cvo::image {
namespace {

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

const char* status_text(VP8StatusCode status) {
  switch (status) {
    case VP8_STATUS_OUT_OF_MEMORY: return "out of memory";
    case VP8_STATUS_INVALID_PARAM: return "invalid parameter";
    case VP8_STATUS_BITSTREAM_ERROR: return "corrupt bitstream";
    case VP8_STATUS_UNSUPPORTED_FEATURE: return "unsupported feature";
    case VP8_STATUS_SUSPENDED: return "suspended";
    case VP8_STATUS_USER_ABORT: return "aborted";
    case VP8_STATUS_NOT_ENOUGH_DATA: return "truncated: not enough data";
    default: return "failed";
  }
}

}  // namespace

std::string decode_webp(std::span<const std::uint8_t> webp, cv::Mat& bgr, cv::Size expected) {
  if (format_of(webp) != Format::kWebp) return "WebP: no RIFF/WEBP signature";
  WebPBitstreamFeatures features;
  if (const auto status = WebPGetFeatures(webp.data(), webp.size(), &features); status != VP8_STATUS_OK)
    return std::string("WebP: ") + status_text(status);
  if (features.has_animation) return "WebP: an animation, not a still image";
  const int w = features.width, h = features.height;
  if (!expected.empty() && (w != expected.width || h != expected.height))
    return "WebP: image is " + size_text(w, h) + ", expected " + size_text(expected.width, expected.height);
  if (w > kMaxSide || h > kMaxSide)
    return "WebP: image of " + size_text(w, h) + " is larger than " + std::to_string(kMaxSide) + " a side";
  bgr.create(h, w, CV_8UC3);
  // The buffer's extent as libwebp counts it: the last row needs only its pixels (a view's rows are padded).
  const std::size_t extent = bgr.step[0] * std::size_t(h - 1) + std::size_t(w) * 3;
  if (WebPDecodeBGRInto(webp.data(), webp.size(), bgr.data, extent, int(bgr.step[0])) == nullptr)
    return "WebP: corrupt or truncated image data";
  return {};
}

}  // namespace cvo::image
