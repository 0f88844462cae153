#include "libcvo/sim/sequence.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "libcvo/io/input_error.hpp"
#include "libcvo/io/intrinsics_file.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/sim/random.hpp"

namespace cvo::sim {
namespace {

void make_directory(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw io::InputError(dir, "cannot create directory" + (ec ? ": " + ec.message() : std::string()));
}

void write_image(const std::filesystem::path& file, const cv::Mat& image) {
  bool ok = false;
  try {
    ok = cv::imwrite(file.string(), image);
  } catch (const cv::Exception& e) {
    throw io::InputError(file, std::string("cannot write image: ") + e.what());
  }
  if (!ok) throw io::InputError(file, "cannot write image");
}

void write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  if (!out) throw io::InputError(file, "cannot open for writing");
  out << text;
  out.flush();
  if (!out) throw io::InputError(file, "write failed");
}

// The cvo-render arguments that give these options (the defaults left out), for the lists' headers.
std::string command_line(const SequenceOptions& options) {
  std::string line = "cvo-render --scene " + std::string(scene_name(options.scene)) + " --path " +
                     std::string(path_name(options.path)) + " --seed " + std::to_string(options.seed);
  if (options.noise.enabled) line += " --noise";
  if (options.intrinsics.rolling_shutter())
    line += " --rolling-shutter " + std::to_string(options.intrinsics.readout_s);
  if (options.sensor.kinect_depth.enabled) line += " --sensor kinect";
  if (options.sensor.exposure.exposure_s > 0)
    line += " --exposure " + std::to_string(options.sensor.exposure.exposure_s);
  if (options.sensor.auto_exposure.enabled) line += " --auto-exposure";
  return line;
}

}  // namespace

std::string stamp_string(double seconds) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.6f", seconds);
  return buffer;
}

SequenceSummary write_sequence(const std::filesystem::path& dir, const SequenceOptions& options) {
  if (const std::string problem = options.intrinsics.validate(); !problem.empty())
    throw std::invalid_argument("write_sequence: " + problem);
  if (options.intrinsics.has_distortion())  // the renderer casts pinhole rays (render.hpp)
    throw std::invalid_argument("write_sequence: the renderer has no lens distortion; give zero coefficients");
  make_directory(dir / "rgb");
  make_directory(dir / "depth");

  const Scene scene = make_scene(options.scene, options.seed);
  const core::Trajectory truth = sample_path(options.path, options.frames, options.start_time, options.rate_hz);
  const std::string source = "# file: '" + command_line(options) + "'\n";
  std::string rgb_list = "# color images\n" + source + "# timestamp filename\n";
  std::string depth_list = "# depth maps\n" + source + "# timestamp filename\n";

  SequenceSummary summary;
  std::size_t valid = 0;
  AutoExposure auto_exposure(options.sensor.auto_exposure, options.rate_hz);
  for (std::size_t i = 0; i < truth.size(); ++i) {
    // The ground truth is the middle row's pose; a rolling shutter sees row v at its own time.
    const double seconds = truth[i].timestamp - options.start_time;
    const core::Intrinsics& k = options.intrinsics;
    const auto pose = [&](int v, double offset_s) {
      return path_pose(options.path, seconds + offset_s + k.readout_s * (v / std::max(k.height - 1.0, 1.0) - 0.5));
    };
    const Radiance radiance = expose(scene, k, pose, options.sensor.exposure, options.render);
    const double gain = options.sensor.auto_exposure.enabled ? auto_exposure.expose(mean_luminance(radiance.bgr)) : 1.0;
    const core::RgbdFrame frame = develop(radiance, k, gain, options.noise, options.sensor, hash(options.seed, i));
    const std::string stamp = stamp_string(truth[i].timestamp);
    write_image(dir / "rgb" / (stamp + ".png"), frame.bgr);
    write_image(dir / "depth" / (stamp + ".png"), frame.depth);
    rgb_list += stamp + " rgb/" + stamp + ".png\n";
    depth_list += stamp + " depth/" + stamp + ".png\n";
    valid += static_cast<std::size_t>(cv::countNonZero(frame.depth));
    if (i > 0) summary.path_length_m += (truth[i].pose.translation() - truth[i - 1].pose.translation()).norm();
  }
  write_text(dir / "rgb.txt", rgb_list);
  write_text(dir / "depth.txt", depth_list);
  write_text(dir / "camera.yaml",
             io::format_intrinsics_yaml(options.intrinsics,
                                        "Camera of a cvo-render sequence; depth is registered to colour."));
  io::write_tum_trajectory(dir / "groundtruth.txt", truth);

  summary.frames = truth.size();
  if (!truth.empty()) summary.duration_s = truth.back().timestamp - truth.front().timestamp;
  const double pixels = static_cast<double>(truth.size()) * options.intrinsics.width * options.intrinsics.height;
  if (pixels > 0) summary.valid_depth_fraction = static_cast<double>(valid) / pixels;
  return summary;
}

}  // namespace cvo::sim
