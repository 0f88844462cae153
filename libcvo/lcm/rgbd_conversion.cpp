#include "libcvo/lcm/rgbd_conversion.hpp"

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <vector>

#include <opencv2/core.hpp>

#include "libcvo/image/jpeg.hpp"
#include "libcvo/image/png.hpp"
#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {
namespace {

using Message = cvo_lcm::rgbd_frame_t;
using core::BadKind;

std::nullopt_t fail(std::string* error, const std::string& what) {
  if (error != nullptr) *error = "CVO_RGBD frame: " + what;
  return std::nullopt;
}
std::nullopt_t fail(std::string* error, BadKind* kind, BadKind why, const std::string& what) {
  if (kind != nullptr) *kind = why;
  return fail(error, what);
}
bool refuse(std::string* error, const std::string& what) {
  fail(error, what);
  return false;
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
      if (const auto bad = image::encode_jpeg(bgr, encoding.jpeg_quality, m.colour); !bad.empty())
        return refuse(error, "JPEG encoding of the colour image failed: " + bad);
      return true;
    case ColourEncoding::kPng:
      if (const auto bad = image::encode_png(bgr, image::PngPixels::kBgr8, encoding.png_compression, m.colour);
          !bad.empty())
        return refuse(error, "PNG encoding of the colour image failed: " + bad);
      return true;
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
      if (const auto bad = image::encode_png(depth, image::PngPixels::kGrey16, encoding.png_compression, m.depth);
          !bad.empty())
        return refuse(error, "PNG encoding of the depth image failed: " + bad);
      return true;
  }
  return refuse(error, "unknown depth encoding " + std::to_string(static_cast<int>(encoding.depth)));
}

std::uint32_t be16(const std::uint8_t* p) { return (std::uint32_t{p[0]} << 8) | p[1]; }
std::uint32_t be32(const std::uint8_t* p) { return (be16(p) << 16) | be16(p + 2); }

std::string dims(std::uint32_t w, std::uint32_t h) { return std::to_string(w) + "x" + std::to_string(h); }

// The most bytes an encoded image of this size can sensibly take: twice its raw size (a JPEG of
// noise at quality 100 stays below that; a stored, uncompressed PNG is the raw size plus a little)
// and 64 KiB of headers and metadata.
std::size_t max_encoded_bytes(const ExpectedImage& e) {
  const std::size_t raw = std::size_t(e.width) * std::size_t(e.height) * (e.depth16 ? 2 : 3);
  return 2 * raw + 65536;
}

// PNG: the 8-byte signature, then IHDR first (the PNG specification requires it): width, height,
// bit depth, colour type.
std::string check_png(const std::uint8_t* b, std::size_t size, const ExpectedImage& e, BadKind& kind) {
  static constexpr std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  kind = BadKind::kImageFormat;
  if (size < 33 || !std::equal(std::begin(kSignature), std::end(kSignature), b)) return "not a PNG (no PNG signature)";
  if (be32(b + 8) != 13 || !std::equal(b + 12, b + 16, "IHDR")) return "PNG without an IHDR chunk first";
  kind = BadKind::kImageSize;
  const std::uint32_t w = be32(b + 16), h = be32(b + 20);
  const int bit_depth = b[24], colour_type = b[25];
  if (w != std::uint32_t(e.width) || h != std::uint32_t(e.height))
    return "PNG header says " + dims(w, h) + ", the message " + dims(std::uint32_t(e.width), std::uint32_t(e.height));
  const bool ok =
      e.depth16 ? bit_depth == 16 && colour_type == 0
                : bit_depth == 8 && (colour_type == 0 || colour_type == 2 || colour_type == 3 || colour_type == 6);
  if (!ok)
    return "PNG of bit depth " + std::to_string(bit_depth) + ", colour type " + std::to_string(colour_type) +
           (e.depth16 ? " (depth must be 16-bit grey)" : " (colour must be 8-bit grey, RGB, palette or RGBA)");
  return {};
}

// JPEG: SOI, then marker segments up to the first frame header (SOFn: precision, height, width,
// components); a bounded walk that stops at the scan (SOS), the end or the buffer's end.
std::string check_jpeg(const std::uint8_t* b, std::size_t size, const ExpectedImage& e, BadKind& kind) {
  kind = BadKind::kImageFormat;
  if (size < 4 || b[0] != 0xff || b[1] != 0xd8 || b[2] != 0xff) return "not a JPEG (no start-of-image marker)";
  std::size_t at = 2;
  for (int segments = 0; segments < 256 && at + 4 <= size; ++segments) {
    if (b[at] != 0xff) return "JPEG with a corrupt marker at byte " + std::to_string(at);
    const std::uint8_t marker = b[at + 1];
    if (marker == 0xff) {  // fill byte
      ++at;
      continue;
    }
    if (marker == 0xda || marker == 0xd9) break;  // scan or end without a frame header
    const std::size_t length = be16(b + at + 2);
    const bool sof = marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc;
    if (sof) {
      if (length < 8 || at + 2 + 8 > size) return "JPEG with a truncated frame header";
      kind = BadKind::kImageSize;
      const std::uint32_t h = be16(b + at + 5), w = be16(b + at + 7);
      const int precision = b[at + 4], components = b[at + 9];
      if (w != std::uint32_t(e.width) || h != std::uint32_t(e.height))
        return "JPEG header says " + dims(w, h) + ", the message " +
               dims(std::uint32_t(e.width), std::uint32_t(e.height));
      if (e.depth16 || precision != 8 || (components != 1 && components != 3))
        return "JPEG of precision " + std::to_string(precision) + " with " + std::to_string(components) +
               " components (colour must be 8-bit grey or 3-component)";
      return {};
    }
    if (length < 2) return "JPEG with a corrupt segment length at byte " + std::to_string(at);
    at += 2 + length;
  }
  return "JPEG without a frame header (SOFn) before its scan";
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
    return fail(error, "depth image must be CV_16UC1 " + expected + ", is type " + std::to_string(frame.depth.type()) +
                           " " + size_text(frame.depth));

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
  m.readout_s = k.readout_s;
  m.colour_encoding = static_cast<std::int8_t>(encoding.colour);
  m.depth_encoding = static_cast<std::int8_t>(encoding.depth);
  if (!encode_colour(frame.bgr, encoding, m, error) || !encode_depth(frame.depth, encoding, m, error))
    return std::nullopt;
  m.colour_size = static_cast<std::int32_t>(m.colour.size());
  m.depth_size = static_cast<std::int32_t>(m.depth.size());
  return m;
}

namespace {

// A JPEG or PNG image of the message, decoded only once its header says it is the declared format
// with the message's size: a decompression bomb or a file of another format (HDR, ...) never
// reaches a decoder. Then only that format's decoder runs (libcvo/image: libpng or TurboJPEG), into
// what the image must become.
cv::Mat decode_checked(const std::vector<std::uint8_t>& bytes, const ExpectedImage& expected, const char* what,
                       std::string* error, BadKind* kind) {
  BadKind why = BadKind::kContent;
  if (const std::string bad = check_image_header(bytes.data(), bytes.size(), expected, &why); !bad.empty()) {
    fail(error, kind, why, std::string(what) + " image: " + bad);
    return {};
  }
  cv::Mat decoded;
  const cv::Size size(expected.width, expected.height);
  const std::string bad =
      expected.format == ImageFormat::kJpeg
          ? image::decode_jpeg(bytes, decoded, size)
          : image::decode_png(bytes, expected.depth16 ? image::PngPixels::kGrey16 : image::PngPixels::kBgr8, decoded,
                              size);
  if (!bad.empty()) {
    fail(error, kind, BadKind::kContent,
         std::string(what) + " image does not decode to " +
             (expected.depth16 ? "16-bit depth of " : "8-bit colour of ") + std::to_string(expected.width) + "x" +
             std::to_string(expected.height) + ": " + bad);
    return {};
  }
  return decoded;
}

std::string raw_size_error(const char* what, std::size_t needed, int w, int h, std::size_t has) {
  return std::string("raw ") + what + " needs " + std::to_string(needed) + " bytes for " + std::to_string(w) + "x" +
         std::to_string(h) + ", has " + std::to_string(has);
}

bool decode_colour(const Message& m, core::RgbdFrame& frame, std::string* error, BadKind* kind) {
  const int w = m.width, h = m.height;  // at most 16384 each (validate), so w*h*3 fits an int
  switch (m.colour_encoding) {
    case Message::COLOUR_RAW_BGR8:
      if (m.colour.size() != std::size_t(w) * h * 3) {
        fail(error, kind, BadKind::kContent, raw_size_error("colour", std::size_t(w) * h * 3, w, h, m.colour.size()));
        return false;
      }
      frame.bgr = cv::Mat(h, w, CV_8UC3);
      std::copy(m.colour.begin(), m.colour.end(), frame.bgr.data);
      return true;
    case Message::COLOUR_JPEG:
    case Message::COLOUR_PNG: {
      const auto format = m.colour_encoding == Message::COLOUR_JPEG ? ImageFormat::kJpeg : ImageFormat::kPng;
      frame.bgr = decode_checked(m.colour, {format, w, h, false}, "colour", error, kind);
      return !frame.bgr.empty();
    }
    default:
      fail(error, kind, BadKind::kContent, "unknown colour encoding " + std::to_string(m.colour_encoding));
      return false;
  }
}

bool decode_depth(const Message& m, core::RgbdFrame& frame, std::string* error, BadKind* kind) {
  const int w = m.width, h = m.height;
  switch (m.depth_encoding) {
    case Message::DEPTH_RAW_U16LE: {
      if (m.depth.size() != std::size_t(w) * h * 2) {
        fail(error, kind, BadKind::kContent, raw_size_error("depth", std::size_t(w) * h * 2, w, h, m.depth.size()));
        return false;
      }
      frame.depth = cv::Mat(h, w, CV_16UC1);
      auto* out = frame.depth.ptr<std::uint16_t>();
      for (std::size_t i = 0; i < std::size_t(w) * h; ++i)
        out[i] = static_cast<std::uint16_t>(m.depth[2 * i] | (m.depth[2 * i + 1] << 8));
      return true;
    }
    case Message::DEPTH_PNG:
      frame.depth = decode_checked(m.depth, {ImageFormat::kPng, w, h, true}, "depth", error, kind);
      return !frame.depth.empty();
    default:
      fail(error, kind, BadKind::kContent, "unknown depth encoding " + std::to_string(m.depth_encoding));
      return false;
  }
}

}  // namespace

std::string check_image_header(const std::uint8_t* bytes, std::size_t size, const ExpectedImage& expected,
                               BadKind* kind) {
  BadKind why = BadKind::kContent;
  std::string bad;
  if (bytes == nullptr || size == 0) {
    bad = "empty";
  } else if (size > max_encoded_bytes(expected)) {
    why = BadKind::kImageSize;
    bad = std::to_string(size) + " bytes, more than an image of " + std::to_string(expected.width) + "x" +
          std::to_string(expected.height) + " can take";
  } else {
    bad = expected.format == ImageFormat::kPng ? check_png(bytes, size, expected, why)
                                               : check_jpeg(bytes, size, expected, why);
  }
  if (!bad.empty() && kind != nullptr) *kind = why;
  return bad;
}

std::optional<core::RgbdFrame> from_message(const Message& m, std::string* error, BadKind* kind) {
  if (kind != nullptr) *kind = BadKind::kContent;
  if (m.version != Message::SCHEMA_VERSION)
    return fail(
        error, "schema version " + std::to_string(m.version) + ", expected " + std::to_string(Message::SCHEMA_VERSION));
  if (m.frame_index < 0) return fail(error, "negative frame_index " + std::to_string(m.frame_index));
  if (m.colour_size != static_cast<std::int64_t>(m.colour.size()) ||
      m.depth_size != static_cast<std::int64_t>(m.depth.size()))
    return fail(error, "colour_size/depth_size do not match the data");

  core::RgbdFrame frame;
  frame.index = static_cast<std::uint64_t>(m.frame_index);
  frame.timestamp = from_utime(m.utime);
  frame.depth_timestamp = from_utime(m.depth_utime);
  frame.intrinsics = {m.fx, m.fy, m.cx, m.cy, m.width, m.height, m.depth_scale, {}, m.readout_s};
  std::copy(std::begin(m.distortion), std::end(m.distortion), frame.intrinsics.distortion.begin());
  if (const std::string bad = frame.intrinsics.validate(); !bad.empty()) return fail(error, "intrinsics: " + bad);
  if (!decode_colour(m, frame, error, kind) || !decode_depth(m, frame, error, kind)) return std::nullopt;
  return frame;
}

}  // namespace cvo::lcm
