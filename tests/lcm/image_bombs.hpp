#pragma once
// Images whose headers claim far more than the message they travel in: what an attacker sends to
// make a receiver allocate and decode gigabytes (decompression bombs), and files of a format other
// than the one declared. Shared by the conversion's unit test and cvo-trackerd's end-to-end test.
#include <zlib.h>

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace cvo::test {

inline void put_be32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}

inline void put_png_chunk(std::vector<std::uint8_t>& out, const char* type, const std::vector<std::uint8_t>& data) {
  put_be32(out, static_cast<std::uint32_t>(data.size()));
  std::vector<std::uint8_t> typed(type, type + 4);
  typed.insert(typed.end(), data.begin(), data.end());
  out.insert(out.end(), typed.begin(), typed.end());
  put_be32(out, static_cast<std::uint32_t>(crc32(0, typed.data(), static_cast<uInt>(typed.size()))));
}

// A zlib stream of `bytes` zeros, about a thousandth of their size, made without deflating them
// all: one block of 64 KiB of zeros deflated with a full flush (byte-aligned, no reference to what
// came before) repeated, the rest likewise, then an empty final block and the Adler-32 of n zeros
// (a = 1, b = n mod 65521).
inline std::vector<std::uint8_t> zlib_zeros(std::uint64_t bytes) {
  const auto deflate_zeros = [](std::size_t n) {
    z_stream z{};
    deflateInit2(&z, 9, Z_DEFLATED, -15, 9, Z_DEFAULT_STRATEGY);  // raw deflate: the framing is ours
    std::vector<std::uint8_t> in(n, 0), out(n / 64 + 1024);
    z.next_in = in.data();
    z.avail_in = static_cast<uInt>(n);
    z.next_out = out.data();
    z.avail_out = static_cast<uInt>(out.size());
    deflate(&z, Z_FULL_FLUSH);
    out.resize(out.size() - z.avail_out);
    deflateEnd(&z);
    return out;
  };
  constexpr std::size_t kBlock = 65536;
  std::vector<std::uint8_t> stream = {0x78, 0xda};
  const auto block = deflate_zeros(kBlock);
  for (std::uint64_t i = 0; i < bytes / kBlock; ++i) stream.insert(stream.end(), block.begin(), block.end());
  if (bytes % kBlock != 0) {
    const auto rest = deflate_zeros(static_cast<std::size_t>(bytes % kBlock));
    stream.insert(stream.end(), rest.begin(), rest.end());
  }
  stream.push_back(0x03);  // final fixed-Huffman block holding only its end
  stream.push_back(0x00);
  put_be32(stream, static_cast<std::uint32_t>((bytes % 65521) << 16 | 1));
  return stream;
}

/// A PNG whose IHDR says width x height (8-bit RGB, or 16-bit grey as depth is sent) and whose
/// image data really is that many rows of zeros: a decoder that trusts it writes every byte.
inline std::vector<std::uint8_t> png_bomb(std::uint32_t width, std::uint32_t height, bool depth16) {
  std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<std::uint8_t> ihdr;
  put_be32(ihdr, width);
  put_be32(ihdr, height);
  ihdr.insert(ihdr.end(),
              {static_cast<std::uint8_t>(depth16 ? 16 : 8), static_cast<std::uint8_t>(depth16 ? 0 : 2), 0, 0, 0});
  put_png_chunk(png, "IHDR", ihdr);
  const std::uint64_t row = 1 + std::uint64_t{width} * (depth16 ? 2 : 3);  // filter byte, then the pixels
  put_png_chunk(png, "IDAT", zlib_zeros(row * height));
  put_png_chunk(png, "IEND", {});
  return png;
}

/// A JPEG of a few hundred bytes whose frame header says width x height: a small real JPEG with
/// its SOF0 dimensions changed. A decoder that trusts it allocates the whole image and, the data
/// ending early, fills it in.
inline std::vector<std::uint8_t> jpeg_bomb(std::uint16_t width, std::uint16_t height) {
  std::vector<std::uint8_t> jpeg;
  cv::imencode(".jpg", cv::Mat(16, 16, CV_8UC3, cv::Scalar(40, 80, 120)), jpeg);
  for (std::size_t i = 2; i + 9 < jpeg.size(); ++i)
    if (jpeg[i] == 0xff && jpeg[i + 1] == 0xc0) {
      jpeg[i + 5] = static_cast<std::uint8_t>(height >> 8);
      jpeg[i + 6] = static_cast<std::uint8_t>(height & 0xff);
      jpeg[i + 7] = static_cast<std::uint8_t>(width >> 8);
      jpeg[i + 8] = static_cast<std::uint8_t>(width & 0xff);
      break;
    }
  return jpeg;
}

/// A Radiance HDR file (OpenCV's decoder for it writes temporary files) of width x height.
inline std::vector<std::uint8_t> hdr_file(int width, int height) {
  std::vector<std::uint8_t> hdr;
  cv::imencode(".hdr", cv::Mat(height, width, CV_32FC3, cv::Scalar(0.25f, 0.5f, 0.75f)), hdr);
  return hdr;
}

}  // namespace cvo::test
