#include "libcvo/image/png.hpp"

#include <png.h>
#include <zlib.h>

#include <bit>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>

namespace cvo::image {
namespace {

// What libpng's callbacks share with us: the bytes read or written, and its last error message.
struct Stream {
  std::span<const std::uint8_t> in;
  std::size_t at = 0;
  std::vector<std::uint8_t>* out = nullptr;
  char message[160] = "";
  char warning[160] = "";  // the last: libpng says what was wrong with a header as warnings, then fails
};

Stream& stream_of(png_structp png) { return *static_cast<Stream*>(png_get_io_ptr(png)); }

// libpng calls error_fn with its error_ptr, then would print to stderr if it returned: jump back
// to the setjmp of the call in progress ourselves.
[[noreturn]] void on_error(png_structp png, png_const_charp message) {
  auto* s = static_cast<Stream*>(png_get_error_ptr(png));
  std::snprintf(s->message, sizeof s->message, "%s", message);
  png_longjmp(png, 1);
}
// Kept, not printed: alone, a warning is an ancillary chunk's trouble and the pixels are fine.
void on_warning(png_structp png, png_const_charp message) {
  auto* s = static_cast<Stream*>(png_get_error_ptr(png));
  std::snprintf(s->warning, sizeof s->warning, "%s", message);
}

void read_bytes(png_structp png, png_bytep data, std::size_t length) {
  Stream& s = stream_of(png);
  if (length > s.in.size() - s.at) png_error(png, "truncated: the data ends inside the image");
  std::memcpy(data, s.in.data() + s.at, length);
  s.at += length;
}

void write_bytes(png_structp png, png_bytep data, std::size_t length) {
  try {
    stream_of(png).out->insert(stream_of(png).out->end(), data, data + length);
  } catch (const std::bad_alloc&) {  // an exception must not cross libpng's C frames
    png_error(png, "out of memory");
  }
}
void flush(png_structp) {}

// The libpng state of one read or write, destroyed whichever way the call ends.
class Codec {
 public:
  Codec(bool write, Stream& stream) : write_(write) {
    png_ = write ? png_create_write_struct(PNG_LIBPNG_VER_STRING, &stream, on_error, on_warning)
                 : png_create_read_struct(PNG_LIBPNG_VER_STRING, &stream, on_error, on_warning);
    if (png_ != nullptr) info_ = png_create_info_struct(png_);
    if (info_ == nullptr) return;
    if (write)
      png_set_write_fn(png_, &stream, write_bytes, flush);
    else
      png_set_read_fn(png_, &stream, read_bytes);
    png_set_user_limits(png_, kMaxSide, kMaxSide);
  }
  ~Codec() {
    if (write_)
      png_destroy_write_struct(&png_, &info_);
    else
      png_destroy_read_struct(&png_, &info_, nullptr);
  }
  Codec(const Codec&) = delete;
  Codec& operator=(const Codec&) = delete;
  [[nodiscard]] bool ok() const { return info_ != nullptr; }
  [[nodiscard]] png_structp png() const { return png_; }
  [[nodiscard]] png_infop info() const { return info_; }

 private:
  bool write_;
  png_structp png_ = nullptr;
  png_infop info_ = nullptr;
};

// The functions that call libpng and hold its setjmp: their locals are plain values, so a longjmp
// out of libpng skips no destructor (the rule that makes setjmp/longjmp defined in C++).

bool read_info(png_structp png, png_infop info) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_info(png, info);
  return true;
}

bool read_pixels(png_structp png, png_infop info, PngPixels pixels, cv::Mat& image) {
  if (setjmp(png_jmpbuf(png))) return false;
  if (pixels == PngPixels::kGrey16) {
    if constexpr (std::endian::native == std::endian::little) png_set_swap(png);
  } else {
    png_set_expand(png);  // palette to RGB, grey below 8 bits to 8
    png_set_strip_16(png);
    png_set_strip_alpha(png);
    png_set_gray_to_rgb(png);
    if (pixels == PngPixels::kBgr8) png_set_bgr(png);
  }
  const int passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  // Every row goes straight into the image: libpng must write exactly one row of it.
  if (png_get_rowbytes(png, info) != std::size_t(image.cols) * image.elemSize())
    png_error(png, "rows do not decode to the expected pixel layout");
  for (int pass = 0; pass < passes; ++pass)
    for (int r = 0; r < image.rows; ++r) png_read_row(png, image.ptr<png_byte>(r), nullptr);
  png_read_end(png, nullptr);
  return true;
}

bool write_pixels(png_structp png, png_infop info, const cv::Mat& image, PngPixels pixels, int compression) {
  if (setjmp(png_jmpbuf(png))) return false;
  const bool depth = pixels == PngPixels::kGrey16;
  png_set_IHDR(png, info, png_uint_32(image.cols), png_uint_32(image.rows), depth ? 16 : 8,
               depth ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, compression);
  png_set_compression_strategy(png, compression <= 1 ? Z_RLE : Z_DEFAULT_STRATEGY);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_write_info(png, info);
  if (depth) {
    if constexpr (std::endian::native == std::endian::little) png_set_swap(png);
  } else if (pixels == PngPixels::kBgr8) {
    png_set_bgr(png);
  }
  for (int r = 0; r < image.rows; ++r) png_write_row(png, image.ptr<png_byte>(r));
  png_write_end(png, info);
  return true;
}

std::string failed(const Stream& s) {
  std::string text = std::string("PNG: ") + (s.message[0] != '\0' ? s.message : "libpng failed");
  if (s.warning[0] != '\0') text += std::string(" (libpng warned: ") + s.warning + ")";
  return text;
}

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

std::string header_of(Codec& codec, Stream& stream, ImageHeader& header) {
  if (!codec.ok()) return "PNG: out of memory";
  if (format_of(stream.in) != Format::kPng) return "PNG: no PNG signature";
  if (!read_info(codec.png(), codec.info())) return failed(stream);
  header.width = int(png_get_image_width(codec.png(), codec.info()));
  header.height = int(png_get_image_height(codec.png(), codec.info()));
  header.channels = png_get_channels(codec.png(), codec.info());
  header.bit_depth = png_get_bit_depth(codec.png(), codec.info());
  return {};
}

}  // namespace

std::string read_png_header(std::span<const std::uint8_t> png, ImageHeader& header) {
  Stream stream{png};
  Codec codec(false, stream);
  return header_of(codec, stream, header);
}

std::string decode_png(std::span<const std::uint8_t> png, PngPixels pixels, cv::Mat& image, cv::Size expected) {
  Stream stream{png};
  Codec codec(false, stream);
  ImageHeader header;
  if (auto bad = header_of(codec, stream, header); !bad.empty()) return bad;
  if (!expected.empty() && (header.width != expected.width || header.height != expected.height))
    return "PNG: image is " + size_text(header.width, header.height) + ", expected " +
           size_text(expected.width, expected.height);
  const int colour_type = png_get_color_type(codec.png(), codec.info());
  if (pixels == PngPixels::kGrey16 && (header.bit_depth != 16 || colour_type != PNG_COLOR_TYPE_GRAY))
    return "PNG: bit depth " + std::to_string(header.bit_depth) + " with " + std::to_string(header.channels) +
           " channel(s), not 16-bit grey";
  image.create(header.height, header.width, pixels == PngPixels::kGrey16 ? CV_16UC1 : CV_8UC3);
  if (!read_pixels(codec.png(), codec.info(), pixels, image)) return failed(stream);
  return {};
}

std::string encode_png(const cv::Mat& image, PngPixels pixels, int compression, std::vector<std::uint8_t>& png) {
  const int type = pixels == PngPixels::kGrey16 ? CV_16UC1 : CV_8UC3;
  if (image.type() != type || image.dims != 2)
    return std::string("PNG: can encode only a 2-D ") + (type == CV_16UC1 ? "CV_16UC1" : "CV_8UC3") +
           " image here, not type " + std::to_string(image.type());
  if (image.empty() || image.cols > kMaxSide || image.rows > kMaxSide)
    return "PNG: cannot encode an image of " + size_text(image.cols, image.rows);
  if (compression < 0 || compression > 9) return "PNG: compression " + std::to_string(compression) + " is not 0..9";
  png.clear();
  Stream stream{{}, 0, &png};
  Codec codec(true, stream);
  if (!codec.ok()) return "PNG: out of memory";
  if (!write_pixels(codec.png(), codec.info(), image, pixels, compression)) return failed(stream);
  return {};
}

}  // namespace cvo::image
