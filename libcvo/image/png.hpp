#pragma once
// PNG through libpng (format.hpp says why, and the rules every function here keeps).
//
// PNG stores 16-bit samples big-endian; depth comes out, and goes in, in the host's order.
// libpng reports errors by longjmp: each call into it runs in a function that holds nothing a
// destructor must release, and the libpng state is freed by RAII one frame up.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "libcvo/image/format.hpp"

namespace cvo::image {

/// What an image is in memory.
enum class PngPixels {
  kBgr8,    // CV_8UC3, OpenCV's channel order
  kRgb8,    // CV_8UC3, the file's channel order
  kGrey16,  // CV_16UC1: depth
};

/// Reads the signature and IHDR only.
std::string read_png_header(std::span<const std::uint8_t> png, ImageHeader& header);

/// Decodes into `image` (created CV_8UC3 or CV_16UC1 of the file's size). For kBgr8 / kRgb8 any
/// PNG decodes, as cv::imread's IMREAD_COLOR would read it: grey is replicated, a palette looked
/// up, alpha dropped (not composited) and 16-bit samples cut to their high byte. kGrey16 takes only
/// a 16-bit grey PNG, bit-exact. With `expected` non-empty, another size is refused from the
/// header. The whole file is checked, up to IEND and every CRC of the critical chunks.
std::string decode_png(std::span<const std::uint8_t> png, PngPixels pixels, cv::Mat& image, cv::Size expected = {});

/// Encodes `image` (CV_8UC3 for kBgr8 / kRgb8, CV_16UC1 for kGrey16; a view with row padding is
/// fine) into `png` (replaced). compression is zlib's level, 0 (stored) to 9; every row is
/// filtered with Sub. Up to level 1 it is deflated with Z_RLE, which is what makes encoding fast
/// (libcvo/image/README.md has the measurements); above, with deflate's full search, which finds
/// the repeats of a row (a depth image 7 % smaller at level 4, for twice the time).
std::string encode_png(const cv::Mat& image, PngPixels pixels, int compression, std::vector<std::uint8_t>& png);

}  // namespace cvo::image
