#include "libcvo/io/tum_dataset.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <regex>
#include <stdexcept>

#include <opencv2/core.hpp>

#include "libcvo/image/decode.hpp"
#include "libcvo/image/png.hpp"
#include "libcvo/io/intrinsics_file.hpp"
#include "libcvo/io/text_lines.hpp"
#include "libcvo/io/trajectory_io.hpp"

namespace cvo::io {
namespace {

struct IndexEntry {
  double timestamp = 0;
  std::filesystem::path file;
  std::size_t line = 0;
};

// rgb.txt / depth.txt, sorted by time. Paths are relative to the index file's folder.
std::vector<IndexEntry> read_index(const std::filesystem::path& index) {
  std::ifstream in(index);
  if (!in) throw InputError(index, "cannot open (a TUM folder needs rgb.txt and depth.txt)");
  std::vector<IndexEntry> entries;
  for_each_data_line(in, index, [&](std::size_t line_no, const std::vector<std::string>& fields) {
    if (fields.size() != 2)
      throw InputError(index, line_no, "expected 2 fields 'timestamp path', got " + std::to_string(fields.size()));
    entries.push_back({parse_finite(fields[0], index, line_no), index.parent_path() / fields[1], line_no});
  });
  if (entries.empty()) throw InputError(index, "lists no images");

  // Out-of-order lines are fine; one timestamp naming two different images is ambiguous.
  std::stable_sort(entries.begin(), entries.end(),
                   [](const auto& a, const auto& b) { return a.timestamp < b.timestamp; });
  std::vector<IndexEntry> unique;
  for (auto& e : entries) {
    if (!unique.empty() && unique.back().timestamp == e.timestamp) {
      if (unique.back().file == e.file) continue;  // a repeated line
      throw InputError(index, e.line,
                       "timestamp " + std::to_string(e.timestamp) + " names a second image (first on line " +
                           std::to_string(unique.back().line) + ")");
    }
    unique.push_back(std::move(e));
  }
  return unique;
}

std::vector<double> stamps(const std::vector<IndexEntry>& entries) {
  std::vector<double> t;
  t.reserve(entries.size());
  for (const auto& e : entries) t.push_back(e.timestamp);
  return t;
}

std::vector<std::uint8_t> read_file(std::size_t frame, const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) throw FrameError(frame, file, "image not found");
  std::ifstream in(file, std::ios::binary);
  std::vector<std::uint8_t> bytes(std::filesystem::file_size(file, ec));
  if (ec || !in || !in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(bytes.size())))
    throw FrameError(frame, file, "cannot read image");
  return bytes;
}

// 8-bit BGR whatever the file holds (PNG, JPEG or WebP).
cv::Mat read_colour(std::size_t frame, const std::filesystem::path& file) {
  cv::Mat bgr;
  if (const auto bad = image::decode_colour(read_file(frame, file), bgr); !bad.empty())
    throw FrameError(frame, file, "cannot decode image: " + bad);
  return bgr;
}

// Only a 16-bit single-channel PNG holds depth; its header says so before anything is decoded.
cv::Mat read_depth(std::size_t frame, const std::filesystem::path& file) {
  const auto bytes = read_file(frame, file);
  image::ImageHeader header;
  if (image::read_png_header(bytes, header).empty() && (header.bit_depth != 16 || header.channels != 1))
    throw FrameError(frame, file,
                     "depth must be a 16-bit single-channel image, got " + std::to_string(header.bit_depth) +
                         "-bit with " + std::to_string(header.channels) + " channel(s)");
  cv::Mat depth;
  if (const auto bad = image::decode_png(bytes, image::PngPixels::kGrey16, depth); !bad.empty())
    throw FrameError(frame, file, "cannot decode image: " + bad);
  return depth;
}

std::string size_text(const cv::Size& s) { return std::to_string(s.width) + "x" + std::to_string(s.height); }

core::Intrinsics camera_for(const std::filesystem::path& dir, const TumOptions& options) {
  if (options.intrinsics) {
    if (const auto error = validate_allowing_unknown_size(*options.intrinsics); !error.empty())
      throw std::invalid_argument("TumOptions::intrinsics: " + error);
    return *options.intrinsics;
  }
  // A folder that carries its calibration (the renderer writes camera.yaml) says it best.
  if (const auto own = dir / "camera.yaml"; std::filesystem::exists(own)) return read_intrinsics_file(own);
  const auto preset = guess_camera_preset(dir);
  if (!preset)
    throw InputError(dir,
                     "cannot tell the camera: no camera.yaml and no fr1/fr2/fr3 in the folder name; give a "
                     "preset or an intrinsics file");
  return *core::camera_preset(*preset);
}

}  // namespace

std::optional<std::string> guess_camera_preset(const std::filesystem::path& dir) {
  auto path = dir.lexically_normal();
  if (path.filename().empty()) path = path.parent_path();  // "dir/" names "dir"
  std::string name = path.filename().string();
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
  // "freiburg2" or "fr2" as a word of the name, not "frames" or "fr10".
  static const std::regex kSensor("(^|[^a-z0-9])(freiburg|fr)([123])($|[^0-9])");
  std::smatch m;
  if (!std::regex_search(name, m, kSensor)) return std::nullopt;
  return "tum_fr" + m[3].str();
}

TumSequence TumSequence::open(const std::filesystem::path& dir, const TumOptions& options) {
  if (!(std::isfinite(options.dataset.max_association_dt) && options.dataset.max_association_dt > 0))
    throw std::invalid_argument("TumOptions::dataset.max_association_dt must be a positive number of seconds");
  std::error_code ec;
  if (!std::filesystem::exists(dir, ec)) throw InputError(dir, "no such dataset folder");
  if (!std::filesystem::is_directory(dir, ec)) throw InputError(dir, "not a folder");

  TumSequence seq;
  seq.dir_ = dir;
  seq.intrinsics_ = camera_for(dir, options);

  const auto rgb = read_index(dir / "rgb.txt");
  const auto depth = read_index(dir / "depth.txt");
  for (const auto& [i, j] : core::associate(stamps(rgb), stamps(depth), options.dataset.max_association_dt)) {
    if (options.max_frames != 0 && seq.frames_.size() == options.max_frames) break;
    seq.frames_.push_back({rgb[i].timestamp, rgb[i].file, depth[j].timestamp, depth[j].file});
  }
  if (seq.frames_.empty())
    throw InputError(dir, "no colour image of rgb.txt has a depth image of depth.txt within " +
                              std::to_string(options.dataset.max_association_dt) + " s");

  if (const auto gt = dir / "groundtruth.txt"; std::filesystem::exists(gt, ec))
    seq.groundtruth_ = read_tum_trajectory(gt);

  if (seq.intrinsics_.width == 0 && seq.intrinsics_.height == 0) {
    const auto size = read_colour(0, seq.frames_.front().rgb).size();
    seq.intrinsics_.width = size.width;
    seq.intrinsics_.height = size.height;
  }
  return seq;
}

std::optional<core::RgbdFrame> TumSequence::next() {
  if (next_ >= frames_.size()) return std::nullopt;
  return read(next_++);  // advanced first, so a FrameError leaves the stream past the bad frame
}

core::RgbdFrame TumSequence::read(std::size_t i) const {
  if (i >= frames_.size())
    throw std::out_of_range("TumSequence::read(" + std::to_string(i) + "): only " + std::to_string(frames_.size()) +
                            " frames");
  const auto& files = frames_[i];
  core::RgbdFrame frame;
  frame.index = i;
  frame.timestamp = files.timestamp;
  frame.depth_timestamp = files.depth_timestamp;
  frame.intrinsics = intrinsics_;
  frame.bgr = read_colour(i, files.rgb);
  frame.depth = read_depth(i, files.depth);
  if (frame.depth.size() != frame.bgr.size())
    throw FrameError(
        i, files.depth,
        "depth image is " + size_text(frame.depth.size()) + " but its colour image " + size_text(frame.bgr.size()));
  if (const cv::Size camera(intrinsics_.width, intrinsics_.height); frame.bgr.size() != camera)
    throw FrameError(i, files.rgb,
                     "image is " + size_text(frame.bgr.size()) + " but the camera's " + size_text(camera));
  return frame;
}

}  // namespace cvo::io
