#pragma once
// JPEG through libjpeg-turbo's TurboJPEG API (format.hpp says why, and the rules every function
// here keeps). Debian 12 ships libjpeg-turbo 2.1, the tjInitCompress / tjCompress2 /
// tjDecompress2 API (the tj3 functions came with 3.0).
//
// Decoding is what cv::imdecode does with the same library: accurate IDCT, smooth ("fancy")
// chroma upsampling; standard Huffman tables when a frame has none (UVC cameras leave them out of
// MJPEG). Encoding is what cv::imencode writes: baseline, 4:2:0 chroma, accurate DCT.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "libcvo/image/format.hpp"

namespace cvo::image {

/// What a libjpeg warning does: corrupt data the decoder worked around (a truncated scan, whose
/// missing rows it fills with grey; extraneous bytes before a marker). Refused by default; a
/// V4L2 camera's MJPEG frames are accepted as OpenCV accepted them, since the driver itself flags
/// the frames it knows are incomplete and many cameras pad the rest.
enum class JpegWarnings { kRefuse, kAccept };

/// Reads the markers up to the frame header; channels is the file's component count.
std::string read_jpeg_header(std::span<const std::uint8_t> jpeg, ImageHeader& header);

/// Decodes into `bgr` (created CV_8UC3 of the file's size); grey and colour JPEGs alike. With
/// `expected` non-empty, another size is refused from the header.
std::string decode_jpeg(std::span<const std::uint8_t> jpeg, cv::Mat& bgr, cv::Size expected = {},
                        JpegWarnings warnings = JpegWarnings::kRefuse);

/// Encodes a CV_8UC3 BGR image (a view with row padding is fine) at quality 0..100 (libjpeg's
/// scale, as IMWRITE_JPEG_QUALITY) into `jpeg` (replaced).
std::string encode_jpeg(const cv::Mat& bgr, int quality, std::vector<std::uint8_t>& jpeg);

}  // namespace cvo::image
