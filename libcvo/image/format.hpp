#pragma once
// cvo::image: PNG and JPEG coded by the libraries made for them, libpng (png.hpp) and
// libjpeg-turbo's TurboJPEG (jpeg.hpp), and WebP decoded by libwebp (webp.hpp), with cv::Mat
// values in and out (opencv_core only).
//
// Why not cv::imencode / cv::imdecode: OpenCV's imgcodecs calls these same libraries for these
// formats, but it links every format it knows and, on Debian, GDAL with it (poppler,
// HDF5, NetCDF, a PostgreSQL client, curl): about a hundred shared libraries that a daemon would
// load, and lock in memory with mlockall, to read three formats.
//
// Every function returns "" on success, otherwise why not, starting with the format's name. The
// input is untrusted: a corrupt, truncated or foreign buffer is a message, never an exception
// escaping or a crash (libpng's longjmp and TurboJPEG's error codes end inside this module).
// Decoders write into the caller's Mat (create(): no allocation when it already has the image's
// size and type; on failure its pixels are unspecified), so a reader of frames of one size
// allocates nothing per frame beyond the libraries' own state.
#include <cstdint>
#include <optional>
#include <span>

namespace cvo::image {

enum class Format { kPng, kJpeg, kWebp };

/// By the signature: PNG's 8 bytes, JPEG's start-of-image marker (FF D8 FF), WebP's RIFF header
/// naming WEBP; nullopt for others.
std::optional<Format> format_of(std::span<const std::uint8_t> bytes);

/// What a file's header says, before any pixel is decoded.
struct ImageHeader {
  int width = 0, height = 0;
  int channels = 0;   // in the file: 1 grey or palette, 2 grey+alpha, 3 colour, 4 colour+alpha
  int bit_depth = 0;  // bits per channel in the file
};

/// Images wider or taller are refused from their header, before any allocation: a few hundred
/// bytes of PNG can claim 10^6 x 10^6 pixels. The same bound as core::Intrinsics' sizes.
inline constexpr int kMaxSide = 16384;

}  // namespace cvo::image
