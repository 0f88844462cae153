#include "libcvo/lcm/rgbd_conversion.hpp"

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {
namespace {

using Message = cvo_lcm::rgbd_frame_t;

std::nullopt_t fail(std::string* error, const std::string& what) {
  if (error != nullptr) *error = "CVO_RGBD frame: " + what;
  return std::nullopt;
}
bool refuse(std::string* error, const std::string& what) {
  fail(error, what);
  return false;
}

// OpenCV reports some encoder and decoder failures by exception, others by an empty result.
bool encode_image(const char* ext, const cv::Mat& image, const std::vector<int>& params, std::vector<std::uint8_t>& out) {
  try {
    return cv::imencode(ext, image, out, params) && !out.empty();
  } catch (const cv::Exception&) {
    return false;
  }
}

cv::Mat decode_image(const std::vector<std::uint8_t>& bytes, int flags) {
  if (bytes.empty()) return {};
  try {
    return cv::imdecode(cv::Mat(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<std::uint8_t*>(bytes.data())),
                        flags);
  } catch (const cv::Exception&) {
    return {};
  }
}

bool encode_colour(const cv::Mat& bgr, const RgbdEncoding& encoding, Message& m, std::string* error) {
  switch (encoding.colour) {
    case ColourEncoding::kRawBgr8: {
      m.colour.resize(bgr.total() * 3);
      for (int r = 0; r < bgr.rows; ++r)  // row by row: the Mat may be a view with padding
        std::copy_n(bgr.ptr<std::uint8_t>(r), bgr.cols * 3, m.colour.data() + std::size_t(r) * bgr.cols * 3);
      return true;
    }
    case ColourEncoding::kJpeg:
      if (encode_image(".jpg", bgr, {cv::IMWRITE_JPEG_QUALITY, encoding.jpeg_quality}, m.colour)) return true;
      return refuse(error, "JPEG encoding of the colour image failed");
    case ColourEncoding::kPng:
      if (encode_image(".png", bgr, {cv::IMWRITE_PNG_COMPRESSION, encoding.png_compression}, m.colour)) return true;
      return refuse(error, "PNG encoding of the colour image failed");
  }
  return refuse(error, "unknown colour encoding " + std::to_string(static_cast<int>(encoding.colour)));
}

bool encode_depth(const cv::Mat& depth, const RgbdEncoding& encoding, Message& m, std::string* error) {
  switch (encoding.depth) {
    case DepthEncoding::kRawU16Le: {
      m.depth.resize(depth.total() * 2);
      std::size_t k = 0;
      for (int r = 0; r < depth.rows; ++r) {
        const auto* row = depth.ptr<std::uint16_t>(r);
        for (int c = 0; c < depth.cols; ++c) {  // little-endian whatever the host's order
          m.depth[k++] = static_cast<std::uint8_t>(row[c] & 0xff);
          m.depth[k++] = static_cast<std::uint8_t>(row[c] >> 8);
        }
      }
      return true;
    }
    case DepthEncoding::kPng:
      if (encode_image(".png", depth, {cv::IMWRITE_PNG_COMPRESSION, encoding.png_compression}, m.depth)) return true;
      return refuse(error, "PNG encoding of the depth image failed");
  }
  return refuse(error, "unknown depth encoding " + std::to_string(static_cast<int>(encoding.depth)));
}

std::string size_text(const cv::Mat& m) { return std::to_string(m.cols) + "x" + std::to_string(m.rows); }

}  // namespace

std::optional<ColourEncoding> parse_colour_encoding(const std::string& name) {
  if (name == "raw") return ColourEncoding::kRawBgr8;
  if (name == "jpeg") return ColourEncoding::kJpeg;
  if (name == "png") return ColourEncoding::kPng;
  return std::nullopt;
}

std::optional<DepthEncoding> parse_depth_encoding(const std::string& name) {
  if (name == "raw") return DepthEncoding::kRawU16Le;
  if (name == "png") return DepthEncoding::kPng;
  return std::nullopt;
}

const char* to_string(ColourEncoding encoding) {
  switch (encoding) {
    case ColourEncoding::kRawBgr8: return "raw";
    case ColourEncoding::kJpeg: return "jpeg";
    case ColourEncoding::kPng: return "png";
  }
  return "?";
}

const char* to_string(DepthEncoding encoding) {
  switch (encoding) {
    case DepthEncoding::kRawU16Le: return "raw";
    case DepthEncoding::kPng: return "png";
  }
  return "?";
}

std::optional<Message> to_message(const core::RgbdFrame& frame, const RgbdEncoding& encoding, std::string* error) {
  const auto& k = frame.intrinsics;
  if (const std::string bad = k.validate(); !bad.empty()) return fail(error, "intrinsics: " + bad);
  const std::string expected = std::to_string(k.width) + "x" + std::to_string(k.height);
  if (frame.bgr.type() != CV_8UC3 || frame.bgr.cols != k.width || frame.bgr.rows != k.height)
    return fail(error, "colour image must be CV_8UC3 " + expected + ", is type " + std::to_string(frame.bgr.type()) +
                           " " + size_text(frame.bgr));
  if (frame.depth.type() != CV_16UC1 || frame.depth.cols != k.width || frame.depth.rows != k.height)
    return fail(error, "depth image must be CV_16UC1 " + expected + ", is type " +
                           std::to_string(frame.depth.type()) + " " + size_text(frame.depth));

  Message m{};
  m.version = Message::SCHEMA_VERSION;
  m.utime = to_utime(frame.timestamp);
  m.depth_utime = to_utime(frame.depth_timestamp);
  m.frame_index = static_cast<std::int64_t>(frame.index);
  m.fx = k.fx;
  m.fy = k.fy;
  m.cx = k.cx;
  m.cy = k.cy;
  m.width = k.width;
  m.height = k.height;
  m.depth_scale = k.depth_scale;
  std::copy(k.distortion.begin(), k.distortion.end(), m.distortion);
  m.colour_encoding = static_cast<std::int8_t>(encoding.colour);
  m.depth_encoding = static_cast<std::int8_t>(encoding.depth);
  if (!encode_colour(frame.bgr, encoding, m, error) || !encode_depth(frame.depth, encoding, m, error))
    return std::nullopt;
  m.colour_size = static_cast<std::int32_t>(m.colour.size());
  m.depth_size = static_cast<std::int32_t>(m.depth.size());
  return m;
}

std::optional<core::RgbdFrame> from_message(const Message& m, std::string* error) {
  if (m.version != Message::SCHEMA_VERSION)
    return fail(error, "schema version " + std::to_string(m.version) + ", expected " +
                           std::to_string(Message::SCHEMA_VERSION));
  if (m.frame_index < 0) return fail(error, "negative frame_index " + std::to_string(m.frame_index));
  if (m.colour_size != static_cast<std::int64_t>(m.colour.size()) ||
      m.depth_size != static_cast<std::int64_t>(m.depth.size()))
    return fail(error, "colour_size/depth_size do not match the data");

  core::RgbdFrame frame;
  frame.index = static_cast<std::uint64_t>(m.frame_index);
  frame.timestamp = from_utime(m.utime);
  frame.depth_timestamp = from_utime(m.depth_utime);
  frame.intrinsics = {m.fx, m.fy, m.cx, m.cy, m.width, m.height, m.depth_scale, {}};
  std::copy(std::begin(m.distortion), std::end(m.distortion), frame.intrinsics.distortion.begin());
  if (const std::string bad = frame.intrinsics.validate(); !bad.empty())
    return fail(error, "intrinsics: " + bad);
  const int w = m.width, h = m.height;  // at most 16384 each (validate), so w*h*3 fits an int
  const std::string expected = std::to_string(w) + "x" + std::to_string(h);

  switch (m.colour_encoding) {
    case Message::COLOUR_RAW_BGR8:
      if (m.colour.size() != std::size_t(w) * h * 3)
        return fail(error, "raw colour needs " + std::to_string(std::size_t(w) * h * 3) + " bytes for " + expected +
                               ", has " + std::to_string(m.colour.size()));
      frame.bgr = cv::Mat(h, w, CV_8UC3);
      std::copy(m.colour.begin(), m.colour.end(), frame.bgr.data);
      break;
    case Message::COLOUR_JPEG:
    case Message::COLOUR_PNG:
      frame.bgr = decode_image(m.colour, cv::IMREAD_COLOR);
      if (frame.bgr.empty()) return fail(error, "colour image does not decode");
      if (frame.bgr.cols != w || frame.bgr.rows != h)
        return fail(error, "colour image is " + size_text(frame.bgr) + ", intrinsics say " + expected);
      break;
    default:
      return fail(error, "unknown colour encoding " + std::to_string(m.colour_encoding));
  }

  switch (m.depth_encoding) {
    case Message::DEPTH_RAW_U16LE: {
      if (m.depth.size() != std::size_t(w) * h * 2)
        return fail(error, "raw depth needs " + std::to_string(std::size_t(w) * h * 2) + " bytes for " + expected +
                               ", has " + std::to_string(m.depth.size()));
      frame.depth = cv::Mat(h, w, CV_16UC1);
      auto* out = frame.depth.ptr<std::uint16_t>();
      for (std::size_t i = 0; i < std::size_t(w) * h; ++i)
        out[i] = static_cast<std::uint16_t>(m.depth[2 * i] | (m.depth[2 * i + 1] << 8));
      break;
    }
    case Message::DEPTH_PNG:
      frame.depth = decode_image(m.depth, cv::IMREAD_UNCHANGED);
      if (frame.depth.empty()) return fail(error, "depth image does not decode");
      if (frame.depth.type() != CV_16UC1)
        return fail(error, "depth PNG must be 16-bit single-channel, is type " + std::to_string(frame.depth.type()));
      if (frame.depth.cols != w || frame.depth.rows != h)
        return fail(error, "depth image is " + size_text(frame.depth) + ", intrinsics say " + expected);
      break;
    default:
      return fail(error, "unknown depth encoding " + std::to_string(m.depth_encoding));
  }
  return frame;
}

}  // namespace cvo::lcm
