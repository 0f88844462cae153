#include "libcvo/image/jpeg.hpp"

#include <turbojpeg.h>

#include <memory>

namespace cvo::image {
namespace {

using Handle = std::unique_ptr<void, int (*)(tjhandle)>;

std::string failed(tjhandle tj) { return std::string("JPEG: ") + tjGetErrorStr2(tj); }

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

// tjDecompressHeader3's colour space as a component count.
int channels_of(int colourspace) {
  switch (colourspace) {
    case TJCS_GRAY: return 1;
    case TJCS_CMYK:
    case TJCS_YCCK: return 4;
    default: return 3;
  }
}

std::string header_of(tjhandle tj, std::span<const std::uint8_t> jpeg, ImageHeader& header) {
  if (format_of(jpeg) != Format::kJpeg) return "JPEG: no start-of-image marker";
  int w = 0, h = 0, subsampling = 0, colourspace = 0;
  if (tjDecompressHeader3(tj, jpeg.data(), jpeg.size(), &w, &h, &subsampling, &colourspace) != 0) return failed(tj);
  header = {w, h, channels_of(colourspace), 8};  // TurboJPEG 2.1 reads only 8-bit JPEG
  return {};
}

}  // namespace

std::string read_jpeg_header(std::span<const std::uint8_t> jpeg, ImageHeader& header) {
  const Handle tj(tjInitDecompress(), tjDestroy);
  if (!tj) return failed(nullptr);
  return header_of(tj.get(), jpeg, header);
}

std::string decode_jpeg(std::span<const std::uint8_t> jpeg, cv::Mat& bgr, cv::Size expected, JpegWarnings warnings) {
  const Handle tj(tjInitDecompress(), tjDestroy);
  if (!tj) return failed(nullptr);
  ImageHeader header;
  if (auto bad = header_of(tj.get(), jpeg, header); !bad.empty()) return bad;
  if (!expected.empty() && (header.width != expected.width || header.height != expected.height))
    return "JPEG: image is " + size_text(header.width, header.height) + ", expected " +
           size_text(expected.width, expected.height);
  if (header.width > kMaxSide || header.height > kMaxSide)
    return "JPEG: image of " + size_text(header.width, header.height) + " is larger than " + std::to_string(kMaxSide) +
           " a side";
  bgr.create(header.height, header.width, CV_8UC3);
  const int flags = warnings == JpegWarnings::kRefuse ? TJFLAG_STOPONWARNING : 0;
  if (tjDecompress2(tj.get(), jpeg.data(), jpeg.size(), bgr.data, bgr.cols, int(bgr.step[0]), bgr.rows, TJPF_BGR,
                    flags | TJFLAG_ACCURATEDCT) != 0 &&
      !(warnings == JpegWarnings::kAccept && tjGetErrorCode(tj.get()) == TJERR_WARNING))
    return failed(tj.get());
  return {};
}

std::string encode_jpeg(const cv::Mat& bgr, int quality, std::vector<std::uint8_t>& jpeg) {
  if (bgr.type() != CV_8UC3 || bgr.dims != 2)
    return "JPEG: can encode only a 2-D CV_8UC3 image, not type " + std::to_string(bgr.type());
  if (bgr.empty() || bgr.cols > kMaxSide || bgr.rows > kMaxSide)
    return "JPEG: cannot encode an image of " + size_text(bgr.cols, bgr.rows);
  if (quality < 0 || quality > 100) return "JPEG: quality " + std::to_string(quality) + " is not 0..100";
  const Handle tj(tjInitCompress(), tjDestroy);
  if (!tj) return failed(nullptr);
  unsigned char* buffer = nullptr;  // TurboJPEG's own, grown as it writes
  unsigned long size = 0;
  const int status = tjCompress2(tj.get(), bgr.data, bgr.cols, int(bgr.step[0]), bgr.rows, TJPF_BGR, &buffer, &size,
                                 TJSAMP_420, quality, TJFLAG_ACCURATEDCT);
  const std::unique_ptr<unsigned char, void (*)(unsigned char*)> owned(buffer, tjFree);
  if (status != 0) return failed(tj.get());
  jpeg.assign(buffer, buffer + size);
  return {};
}

}  // namespace cvo::image
