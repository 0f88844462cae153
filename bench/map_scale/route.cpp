#include "route.hpp"

#include <opencv2/core.hpp>

#include "libcvo/config/module_parameters.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"

namespace cvo::bench {
namespace {

core::RgbdFrame owned(const core::RgbdFrame& frame) {
  core::RgbdFrame copy = frame;
  copy.bgr = frame.bgr.clone();
  copy.depth = frame.depth.clone();
  return copy;
}

void keep(const odometry::TrackStep& step, Route& route) {
  RouteStep out;
  if (const auto& g = step.closed_graph) out.graph = RouteGraph{g->keyframe_id, *g->graph};
  if (const auto& k = step.new_keyframe) {
    out.keyframe = RouteKeyframe{k->id, owned(k->frame), k->pose};
    ++route.keyframes;
  }
  if (out.graph || out.keyframe) route.steps.push_back(std::move(out));
}

}  // namespace

Route track_route(const std::string& name, const std::filesystem::path& tum_folder, const config::Config& config) {
  const auto sequence = io::TumSequence::open(tum_folder, config::tum_options(config));
  const auto& camera = sequence.intrinsics();
  odometry::KeyframeOdometry tracker(camera.width, camera.height, config::keyframe_odometry_parameters(config));
  Route route{name, {}, 0};
  // A keyframe may be the previous frame: its images stay alive until the next track() returned.
  core::RgbdFrame previous, current;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    current = sequence.read(i);
    keep(tracker.track(current), route);
    previous = current;
  }
  if (const auto open = tracker.finish()) route.steps.push_back({RouteGraph{open->keyframe_id, *open->graph}, {}});
  return route;
}

core::RgbdFrame perturbed(const core::RgbdFrame& frame, std::uint64_t seed) {
  core::RgbdFrame out = owned(frame);
  cv::RNG rng(seed * 0x9E3779B97F4A7C15ULL + 1);
  cv::Mat noise(out.bgr.size(), CV_16SC3);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 2.0);
  cv::Mat colour;
  out.bgr.convertTo(colour, CV_16SC3);
  cv::add(colour, noise, colour);
  colour.convertTo(out.bgr, CV_8UC3);  // saturates to [0, 255]
  cv::Mat step(out.depth.size(), CV_16SC1);
  rng.fill(step, cv::RNG::UNIFORM, -1, 2);  // -1, 0 or +1
  for (int v = 0; v < out.depth.rows; ++v) {
    auto* d = out.depth.ptr<std::uint16_t>(v);
    const auto* s = step.ptr<std::int16_t>(v);
    for (int u = 0; u < out.depth.cols; ++u)
      if (d[u] > 1 && d[u] < 0xFFFF) d[u] = static_cast<std::uint16_t>(d[u] + s[u]);
  }
  return out;
}

}  // namespace cvo::bench
