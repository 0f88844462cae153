#pragma once
// A colour image of any format this module reads, told by its signature (format_of): what a
// folder of image files holds (a TUM recording: PNG, or the embedded sample's WebP; JPEG).
#include <cstdint>
#include <span>
#include <string>

#include <opencv2/core/mat.hpp>

namespace cvo::image {

/// PNG, JPEG or WebP into `bgr` (CV_8UC3), as png.hpp / jpeg.hpp / webp.hpp decode them; another
/// signature is refused. JPEG warnings (corrupt data) are refused.
std::string decode_colour(std::span<const std::uint8_t> bytes, cv::Mat& bgr, cv::Size expected = {});

}  // namespace cvo::image
