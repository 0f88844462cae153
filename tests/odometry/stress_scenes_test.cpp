// KF-CVO on the rendered stress sequences of issue 47 (libcvo/sim/sensor.hpp): a texture-less
// white room seen by a Kinect-like camera, and turns at 1.5 times fr1/rpy's peak rate under a
// rolling shutter. Short (12 frames, 3 sub-exposures) to keep CI fast; the bounds are the errors
// measured on the code of this commit with a margin, stated beside each.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/odometry/keyframe_odometry.hpp"
#include "libcvo/sim/sensor.hpp"
#include "tests/odometry/odometry_fixtures.hpp"

namespace cvo::odometry {
namespace {

// The full 640x480 camera: the selector's noise-driven points and the Kinect constants are those of
// a full-size frame.
core::Intrinsics camera(double readout_s) {
  core::Intrinsics k = *core::camera_preset("synthetic");
  k.readout_s = readout_s;
  return k;
}

// n frames along `path` through `scene` with the sensor effects, as write_sequence renders them;
// frame i's sensor noise drawn from seed noise_seed * 1000 + i.
testing::RenderedSequence render_stress(sim::SceneKind scene_kind, sim::PathKind path, const core::Intrinsics& k,
                                        const sim::SensorOptions& sensor, std::size_t n, std::uint64_t noise_seed = 0) {
  const sim::Scene scene = sim::make_scene(scene_kind, 42);
  testing::RenderedSequence s;
  s.truth = sim::sample_path(path, n);
  sim::AutoExposure auto_exposure(sensor.auto_exposure, 30.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = s.truth[i].timestamp - 1000.0;
    const auto pose = [&](int v, double offset) {
      return sim::path_pose(path, t + offset + k.readout_s * (v / (k.height - 1.0) - 0.5));
    };
    const sim::Radiance radiance = sim::expose(scene, k, pose, sensor.exposure, testing::fast_render());
    const double gain = auto_exposure.expose(sim::mean_luminance(radiance.bgr));
    core::RgbdFrame frame = sim::develop(radiance, k, gain, {}, sensor, noise_seed * 1000 + i);
    frame.index = i;
    frame.timestamp = frame.depth_timestamp = s.truth[i].timestamp;
    s.frames.push_back(std::move(frame));
  }
  return s;
}

struct Drift {
  double worst_translation_mm = 0, worst_rotation_deg = 0;
  int failed = 0;
};

// Each frame's pose relative to the first against the truth's: the worst error over the sequence.
Drift track(const testing::RenderedSequence& s) {
  KeyframeOdometryParameters p;
  p.selection.depth_time_offset_s = 0.0;  // rendered depth shares the colour's time
  KeyframeOdometry odometry(640, 480, p);
  Drift drift;
  core::SE3 first;
  for (std::size_t i = 0; i < s.frames.size(); ++i) {
    const auto r = odometry.track(s.frames[i]);
    drift.failed += !r.tracked();
    if (i == 0) first = r.pose;
    const auto e = testing::motion_error(s.truth[0].pose.inverse() * s.truth[i].pose, first.inverse() * r.pose);
    drift.worst_translation_mm = std::max(drift.worst_translation_mm, e.translation_mm);
    drift.worst_rotation_deg = std::max(drift.worst_rotation_deg, e.rotation_deg);
  }
  std::printf("worst error %.1f mm, %.2f deg; %d failed frames of %zu\n", drift.worst_translation_mm,
              drift.worst_rotation_deg, drift.failed, s.frames.size());
  return drift;
}

// white_room along the orbit, Kinect depth and colour noise, 10 ms exposure, auto-exposure; three
// draws of the sensor noise. Over noise seeds 0-7, at this commit: worst 19-187 mm and 0.21-0.66 deg
// over the 12 frames (0.4 s), no failure; the bounds are 1.5 times the worst, a regression guard,
// not a target (the translation drifts: the view is mostly a white wall and floor at 3 m with
// 2.6 cm depth steps). With the renderer's former colour noise (seven times fr1's) 72-296 mm; with
// noise of fr1's order (1.5 levels a channel) and no search at the region medians
// (point_selection.hpp), 84-553 points a frame, and 90-frame sequences lost 40-66 frames.
TEST(StressScenes, WhiteRoomWithAKinectLikeCameraIsTracked) {
  sim::SensorOptions sensor = sim::kinect_sensor();
  sensor.exposure.exposure_s = 0.01;
  sensor.exposure.samples = 3;
  sensor.auto_exposure.enabled = true;
  for (const std::uint64_t noise_seed : {0, 1, 2}) {
    SCOPED_TRACE(noise_seed);
    const auto s = render_stress(sim::SceneKind::white_room, sim::PathKind::orbit, camera(0.0), sensor, 12, noise_seed);
    const Drift drift = track(s);
    EXPECT_EQ(drift.failed, 0);
    EXPECT_LT(drift.worst_translation_mm, 280.0);
    EXPECT_LT(drift.worst_rotation_deg, 1.0);
  }
}

// textured_room along fast_rpy (237 deg/s peak, 6.4 degrees between the first two frames), a 30 ms
// rolling shutter declared in the intrinsics, Kinect depth and colour noise, 10 ms exposure; three
// draws of the sensor noise. Measured over noise seeds 0-7: worst 4.6-16.8 mm and 0.19-0.26 deg over
// 12 frames (0.4 s, ~60 degrees turned), no failure; the bounds are 1.5 times the worst. Before the
// session's first pair started from a kernel that reaches the turn (keyframe_odometry.hpp), seed 0
// alone passed: 274 and 535 mm, 2.2 and 8.2 deg for seeds 1 and 2, the first pair converging to
// a 0.2 m translation that the constant velocity then carried on. (38.7 mm and 1.89 deg at seed 0
// while the rolling-shutter compensation was dropped beyond 2 deg at the edge rows: twist().)
TEST(StressScenes, FastTurnsUnderARollingShutterAreTrackedFromTheFirstFrame) {
  sim::SensorOptions sensor = sim::kinect_sensor();
  sensor.exposure.exposure_s = 0.01;
  sensor.exposure.samples = 3;
  for (const std::uint64_t noise_seed : {0, 1, 2}) {
    SCOPED_TRACE(noise_seed);
    const auto s =
        render_stress(sim::SceneKind::textured_room, sim::PathKind::fast_rpy, camera(0.03), sensor, 12, noise_seed);
    const Drift drift = track(s);
    EXPECT_EQ(drift.failed, 0);
    EXPECT_LT(drift.worst_translation_mm, 25.0);
    EXPECT_LT(drift.worst_rotation_deg, 0.4);
  }
}

}  // namespace
}  // namespace cvo::odometry
