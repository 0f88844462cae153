#pragma once
// WebP through libwebp, decoding only (format.hpp says why, and the rules every function here
// keeps): the embedded sample's colour frames are lossless WebP (tests/data/fr1_rpy_50/README.md),
// and a TUM folder may hold them. Nothing in the project writes WebP.
#include <cstdint>
#include <span>
#include <string>

#include <opencv2/core/mat.hpp>

#include "libcvo/image/format.hpp"

namespace cvo::image {

/// Decodes a still WebP, lossless or lossy, into `bgr` (created CV_8UC3 of the file's size; alpha
/// is dropped). With `expected` non-empty, another size is refused from the header. An animation
/// is refused.
std::string decode_webp(std::span<const std::uint8_t> webp, cv::Mat& bgr, cv::Size expected = {});

}  // namespace cvo::image
