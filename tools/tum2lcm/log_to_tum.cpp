#include "log_to_tum.hpp"

#include <cstdint>
#include <fstream>
#include <optional>

#include <lcm/lcm-cpp.hpp>
#include <opencv2/imgcodecs.hpp>

#include "libcvo/core/camera.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/io/intrinsics_file.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"

namespace cvo::tools {
namespace {

namespace fs = std::filesystem;

// "1305031229.528748": TUM's 6 decimals, straight from the integer microseconds (no rounding).
std::string tum_timestamp(std::int64_t utime) {
  const std::int64_t seconds = utime / 1000000, micros = utime % 1000000;
  std::string frac = std::to_string(micros < 0 ? -micros : micros);
  return std::to_string(seconds) + "." + std::string(6 - frac.size(), '0') + frac;
}

void write_image(const fs::path& file, const cv::Mat& image) {
  bool ok = false;
  try {
    ok = cv::imwrite(file.string(), image);
  } catch (const cv::Exception&) {
  }
  if (!ok) throw io::InputError(file, "cannot write the image");
}

}  // namespace

LogToTumSummary log_to_tum(const fs::path& log, const fs::path& out_dir, const std::string& channel) {
  if (!fs::is_regular_file(log)) throw io::InputError(log, "no such log file");
  ::lcm::LogFile in(log.string(), "r");
  if (!in.good()) throw io::InputError(log, "cannot open the log file");

  std::error_code ec;
  fs::create_directories(out_dir / "rgb", ec);
  fs::create_directories(out_dir / "depth", ec);
  if (ec) throw io::InputError(out_dir, "cannot create the folder: " + ec.message());
  std::ofstream rgb_txt(out_dir / "rgb.txt"), depth_txt(out_dir / "depth.txt");
  if (!rgb_txt || !depth_txt) throw io::InputError(out_dir, "cannot write rgb.txt / depth.txt");
  rgb_txt << "# color images\n# file: '" << log.filename().string() << "'\n# timestamp filename\n";
  depth_txt << "# depth maps\n# file: '" << log.filename().string() << "'\n# timestamp filename\n";

  LogToTumSummary summary;
  std::optional<core::Intrinsics> intrinsics;
  std::size_t event_number = 0;
  while (const ::lcm::LogEvent* event = in.readNextEvent()) {
    ++event_number;
    if (event->channel != channel) {
      ++summary.other_events;
      continue;
    }
    const std::string where = "event " + std::to_string(event_number) + " (" + channel + ")";
    std::string error;
    const auto message = lcm::decode<cvo_lcm::rgbd_frame_t>(event->data, event->datalen, &error);
    if (!message) throw io::InputError(log, where + ": " + error);
    const auto frame = lcm::from_message(*message, &error);
    if (!frame) throw io::InputError(log, where + ": " + error);
    if (!intrinsics) intrinsics = frame->intrinsics;
    if (*intrinsics != frame->intrinsics)
      throw io::InputError(log, where + ": the intrinsics change; a TUM folder has one camera");

    const std::string rgb_name = "rgb/" + tum_timestamp(message->utime) + ".png";
    const std::string depth_name = "depth/" + tum_timestamp(message->depth_utime) + ".png";
    write_image(out_dir / rgb_name, frame->bgr);
    write_image(out_dir / depth_name, frame->depth);
    rgb_txt << tum_timestamp(message->utime) << ' ' << rgb_name << '\n';
    depth_txt << tum_timestamp(message->depth_utime) << ' ' << depth_name << '\n';
    ++summary.frames;
  }
  if (summary.frames == 0) throw io::InputError(log, "no " + channel + " frames in the log");

  std::ofstream camera(out_dir / "camera.yaml");
  camera << io::format_intrinsics_yaml(*intrinsics, "written by tum2lcm --to-tum from " + log.filename().string());
  rgb_txt.flush();
  depth_txt.flush();
  if (!camera || !rgb_txt || !depth_txt) throw io::InputError(out_dir, "writing the index files failed");
  return summary;
}

}  // namespace cvo::tools
