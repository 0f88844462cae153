#include "tests/support/v4l2_emulator/scene.hpp"

#include <linux/videodev2.h>

#include <algorithm>
#include <cmath>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace cvo::drivers::v4l2_emulator {
namespace {

std::uint8_t clamp_byte(double v) { return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L)); }

cv::Mat at_size(const cv::Mat& image, FrameSize size, int interpolation) {
  if (image.cols == static_cast<int>(size.width) && image.rows == static_cast<int>(size.height)) return image;
  cv::Mat resized;
  cv::resize(image, resized, cv::Size(static_cast<int>(size.width), static_cast<int>(size.height)), 0, 0,
             interpolation);
  return resized;
}

}  // namespace

void bgr_to_yuyv(const cv::Mat& bgr, std::vector<std::uint8_t>& out) {
  out.resize(std::size_t(bgr.cols) * std::size_t(bgr.rows) * 2);
  std::uint8_t* o = out.data();
  for (int r = 0; r < bgr.rows; ++r) {
    const auto* px = bgr.ptr<cv::Vec3b>(r);
    for (int c = 0; c + 1 < bgr.cols; c += 2, o += 4) {
      // BT.601, limited range: the inverse of what yuyv_to_bgr (OpenCV's YUV2BGR_YUYV) applies.
      double u = 0, v = 0;
      for (int k = 0; k < 2; ++k) {
        const double b = px[c + k][0], g = px[c + k][1], rr = px[c + k][2];
        o[2 * k] = clamp_byte(16 + (65.481 * rr + 128.553 * g + 24.966 * b) / 255);
        u += (-37.797 * rr - 74.203 * g + 112.0 * b) / 255 / 2;
        v += (112.0 * rr - 93.786 * g - 18.214 * b) / 255 / 2;
      }
      o[1] = clamp_byte(128 + u);
      o[3] = clamp_byte(128 + v);
    }
  }
}

std::vector<std::uint8_t> encode_mjpeg(const cv::Mat& bgr) {
  std::vector<std::uint8_t> jpeg;
  cv::imencode(".jpg", bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90});
  // Segments up to the scan: SOI, then 0xFF marker, 2-byte big-endian length (itself included).
  std::vector<std::uint8_t> out(jpeg.begin(), jpeg.begin() + 2);
  std::size_t i = 2;
  while (i + 4 <= jpeg.size() && jpeg[i] == 0xFF && jpeg[i + 1] != 0xDA) {
    const std::size_t length = std::size_t(jpeg[i + 2]) << 8 | jpeg[i + 3];
    if (jpeg[i + 1] != 0xC4) out.insert(out.end(), jpeg.begin() + long(i), jpeg.begin() + long(i + 2 + length));
    i += 2 + length;
  }
  out.insert(out.end(), jpeg.begin() + long(i), jpeg.end());  // the scan and EOI
  return out;
}

void depth_to_z16(const cv::Mat& depth, double from_units, double to_units, std::vector<std::uint8_t>& out) {
  out.resize(std::size_t(depth.cols) * std::size_t(depth.rows) * 2);
  const double scale = to_units / from_units;
  std::uint8_t* o = out.data();
  for (int r = 0; r < depth.rows; ++r) {
    const auto* d = depth.ptr<std::uint16_t>(r);
    for (int c = 0; c < depth.cols; ++c, o += 2) {
      const auto z = scale == 1.0 ? d[c] : cv::saturate_cast<std::uint16_t>(d[c] * scale);
      o[0] = static_cast<std::uint8_t>(z & 0xff);  // little-endian on any host
      o[1] = static_cast<std::uint8_t>(z >> 8);
    }
  }
}

Scene::Scene(const std::filesystem::path& tum, double depth_units_per_metre)
    : sequence_(io::TumSequence::open(tum)), depth_units_per_metre_(depth_units_per_metre) {}

const core::RgbdFrame& Scene::read(std::size_t entry) {
  if (cached_entry_ != entry) {
    cached_entry_.reset();  // a read that throws leaves nothing half cached
    cached_ = sequence_.read(entry);
    cached_entry_ = entry;
  }
  return cached_;
}

std::vector<std::uint8_t> Scene::encode(std::size_t entry, std::uint32_t fourcc, FrameSize size) {
  const std::lock_guard lock(mutex_);
  const auto& frame = read(entry);
  std::vector<std::uint8_t> out;
  if (fourcc == V4L2_PIX_FMT_Z16)
    depth_to_z16(at_size(frame.depth, size, cv::INTER_NEAREST), frame.intrinsics.depth_scale, depth_units_per_metre_,
                 out);
  else if (fourcc == V4L2_PIX_FMT_MJPEG)
    out = encode_mjpeg(at_size(frame.bgr, size, cv::INTER_AREA));
  else
    bgr_to_yuyv(at_size(frame.bgr, size, cv::INTER_AREA), out);
  return out;
}

}  // namespace cvo::drivers::v4l2_emulator
