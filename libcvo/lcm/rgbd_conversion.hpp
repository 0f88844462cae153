#pragma once
// core::RgbdFrame <-> cvo_lcm::rgbd_frame_t (channel CVO_RGBD), with the image encodings of the
// message: colour raw BGR8, JPEG or PNG; depth raw 16-bit little-endian or PNG. Raw and PNG are
// lossless (a frame comes back bit-exact); JPEG is lossy.
//
// Both directions validate and return nullopt with a message instead of throwing: a message is
// untrusted input, and a frame from a driver may be malformed.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "cvo_lcm/rgbd_frame_t.hpp"
#include "libcvo/core/bad_kind.hpp"
#include "libcvo/core/rgbd_frame.hpp"

namespace cvo::lcm {

enum class ColourEncoding : std::int8_t {
  kRawBgr8 = cvo_lcm::rgbd_frame_t::COLOUR_RAW_BGR8,
  kJpeg = cvo_lcm::rgbd_frame_t::COLOUR_JPEG,
  kPng = cvo_lcm::rgbd_frame_t::COLOUR_PNG,
};
enum class DepthEncoding : std::int8_t {
  kRawU16Le = cvo_lcm::rgbd_frame_t::DEPTH_RAW_U16LE,
  kPng = cvo_lcm::rgbd_frame_t::DEPTH_PNG,
};

struct RgbdEncoding {
  ColourEncoding colour = ColourEncoding::kPng;
  DepthEncoding depth = DepthEncoding::kPng;
  int jpeg_quality = 90;    // 0..100, for ColourEncoding::kJpeg
  int png_compression = 1;  // 0..9; 1: most of the size gain at a fraction of the time of 9
};

/// "raw", "jpeg", "png" (and back); nullopt for other names.
std::optional<ColourEncoding> parse_colour_encoding(const std::string& name);
std::optional<DepthEncoding> parse_depth_encoding(const std::string& name);
const char* to_string(ColourEncoding encoding);
const char* to_string(DepthEncoding encoding);

/// Fails when the intrinsics are invalid, the images are not CV_8UC3 / CV_16UC1 of the
/// intrinsics' size, or an encoder fails.
std::optional<cvo_lcm::rgbd_frame_t> to_message(const core::RgbdFrame& frame, const RgbdEncoding& encoding,
                                                std::string* error);

/// Fails on another schema version, a negative frame index, invalid intrinsics, an unknown
/// encoding, raw data of the wrong size, or an image that does not decode to the right type and size.
/// JPEG and PNG images are checked before any decoder runs (check_image_header): an image that is
/// not its declared format is refused as kImageFormat, one whose header gives another size, depth
/// or channel count than the message, or more bytes than such an image can take, as kImageSize;
/// then only the declared format's decoder runs. *kind (when given) says which refusal; kContent
/// for the others.
std::optional<core::RgbdFrame> from_message(const cvo_lcm::rgbd_frame_t& message, std::string* error,
                                            core::BadKind* kind = nullptr);

/// What an image of a CVO_RGBD or CVO_KEYFRAME message must be: its format, and what its header
/// must say (the message's width and height; 8-bit colour or 16-bit single-channel depth).
enum class ImageFormat { kJpeg, kPng };
struct ExpectedImage {
  ImageFormat format = ImageFormat::kPng;
  int width = 0, height = 0;
  bool depth16 = false;  // a 16-bit single-channel PNG (depth); otherwise 8-bit colour
};

/// Reads only the magic bytes and the header (PNG IHDR; JPEG markers up to the first SOFn, a
/// bounded scan): "" when `bytes` may go to the declared decoder, otherwise why not, with *kind set
/// to kImageFormat or kImageSize. Allocates nothing on success.
std::string check_image_header(const std::uint8_t* bytes, std::size_t size, const ExpectedImage& expected,
                               core::BadKind* kind);

}  // namespace cvo::lcm
