#include "libcvo/registration/point_selection.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

#include "libcvo/sim/camera_path.hpp"
#include "libcvo/sim/sensor.hpp"
#include "tests/registration/registration_fixtures.hpp"

namespace cvo::registration {
namespace {

core::RgbdFrame rendered(sim::SceneKind kind) {
  const auto K = *core::camera_preset("synthetic");
  return sim::render(sim::make_scene(kind, 42), K, testing::camera_looking_north());
}

TEST(PointSelection, SelectsAboutTheTargetWithValidDepthAndLabels) {
  for (const auto kind :
       {sim::SceneKind::textured_room, sim::SceneKind::textureless_room, sim::SceneKind::textured_wall}) {
    const auto frame = rendered(kind);
    PointSelector selector(640, 480, core::SelectionParameters{});
    PointCloud cloud(8192);
    const auto r = selector.select(frame, cloud);
    EXPECT_EQ(r.status, SelectionStatus::kOk) << sim::scene_name(kind);
    EXPECT_FALSE(r.at_median) << sim::scene_name(kind) << ": enough candidates at median + 7";
    // The texture-less room's candidates cluster at its edges: fewer cells; everything else lands
    // near 3000.
    EXPECT_GT(cloud.size(), kind == sim::SceneKind::textureless_room ? 1500u : 2400u) << sim::scene_name(kind);
    EXPECT_LT(cloud.size(), 3600u) << sim::scene_name(kind);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const auto p = cloud.position(i);
      ASSERT_TRUE(p.allFinite());
      ASSERT_GE(p.z(), 0.1f);
      ASSERT_LE(p.z(), 5.0f);
      const auto f = cloud.feature(i);
      for (int c = 0; c < 3; ++c)
        ASSERT_TRUE(f[static_cast<std::size_t>(c)] >= 0.0f && f[static_cast<std::size_t>(c)] <= 1.0f);
      ASSERT_TRUE(std::abs(f[3]) <= 1.0f && std::abs(f[4]) <= 1.0f);
    }
  }
}

// The white room seen by a camera whose colour noise is what fr1's real Kinect frames show, about
// a level at the pixel scale (bench/odometry-tuning.md): median + 7 passes at a few hundred edge
// pixels. Searched again at the region medians, the frame still gets about the target, spread over
// its uniform surfaces (the walls' geometry is what registers it), where the first search alone
// leaves whole quarters of the image empty.
TEST(PointSelection, ATexturelessFrameOfARealisticCameraStillGetsAboutTheTargetOverItsSurfaces) {
  const auto K = *core::camera_preset("synthetic");
  const sim::Scene scene = sim::make_scene(sim::SceneKind::white_room, 42);
  const core::SE3 pose = sim::path_pose(sim::PathKind::orbit, 0.0);
  const sim::Radiance radiance = sim::render_radiance(scene, K, [&](int) { return pose; });
  sim::SensorOptions camera;
  camera.colour_noise.enabled = true;
  camera.colour_noise.read_sigma_levels = 1.2;
  camera.colour_noise.shot_levels = 0.0;
  camera.colour_noise.channel_correlation = 0.0;
  const core::RgbdFrame frame = sim::develop(radiance, K, 1.0, {}, camera, 3);
  PointSelector selector(640, 480, core::SelectionParameters{});
  PointCloud cloud(8192);
  const auto r = selector.select(frame, cloud);
  ASSERT_EQ(r.status, SelectionStatus::kOk);
  EXPECT_TRUE(r.at_median);
  EXPECT_GT(cloud.size(), 2400u);
  EXPECT_LT(cloud.size(), 3600u);
  int quadrant[4] = {0, 0, 0, 0};
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto p = cloud.position(i);
    const double u = K.fx * p.x() / p.z() + K.cx, v = K.fy * p.y() / p.z() + K.cy;
    ++quadrant[(u >= 320 ? 1 : 0) + (v >= 240 ? 2 : 0)];
  }
  for (int q : quadrant) EXPECT_GT(q, static_cast<int>(cloud.size()) / 10);
}

TEST(PointSelection, SpreadsPointsOverTheImage) {
  const auto frame = rendered(sim::SceneKind::textured_room);
  PointSelector selector(640, 480, core::SelectionParameters{});
  PointCloud cloud(8192);
  selector.select(frame, cloud);
  // Every quarter of the image gets a fair share (no clumping on the strongest edges).
  int quadrant[4] = {0, 0, 0, 0};
  const auto K = frame.intrinsics;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto p = cloud.position(i);
    const double u = K.fx * p.x() / p.z() + K.cx, v = K.fy * p.y() / p.z() + K.cy;
    ++quadrant[(u >= 320 ? 1 : 0) + (v >= 240 ? 2 : 0)];
  }
  for (int q : quadrant) EXPECT_GT(q, static_cast<int>(cloud.size()) / 10);
}

TEST(PointSelection, DeterministicAndBackProjectsToTheScene) {
  const auto scene = sim::make_scene(sim::SceneKind::textured_room, 42);
  const auto K = *core::camera_preset("synthetic");
  const auto pose = testing::camera_looking_north();
  const auto frame = sim::render(scene, K, pose);
  core::SelectionParameters own_depth;  // the pixel's own depth: exact on any surface
  own_depth.depth_window = 0;
  PointSelector selector(640, 480, own_depth);
  PointCloud a(8192), b(8192);
  selector.select(frame, a);
  selector.select(frame, b);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.position(i), b.position(i));
    ASSERT_EQ(a.feature(i), b.feature(i));
    // Depth is quantised to 0.2 mm, and the point is computed in float.
    ASSERT_LT(sim::distance_to_surface(scene, pose * a.position(i).cast<double>()), 1e-3);
  }
}

// A frame whose depth was taken after its colour image, the camera having moved by `motion` in
// between (2 cm along the view, 1 cm sideways, 1°).
struct LaggedDepth {
  sim::Scene scene = sim::make_scene(sim::SceneKind::textured_room, 42);
  core::SE3 pose = testing::camera_looking_north();
  core::SE3 motion{core::so3_exp(Eigen::Vector3d(0.0, 1.0 * M_PI / 180.0, 0.0)), Eigen::Vector3d(0.01, 0.0, 0.02)};
  core::RgbdFrame frame;
  LaggedDepth() {
    const auto K = *core::camera_preset("synthetic");
    frame = sim::render(scene, K, pose);
    frame.depth = sim::render(scene, K, pose * motion).depth;
  }
};

// Depth taken after the colour image, the camera having moved by M in between (2 cm along the
// view, 1 cm sideways, 1°): read at the colour pixels as they are, every depth is off by about
// the 2 cm; with colour_T_depth = M each point is looked up where its ray was at the depth time
// and lands back on the surface.
TEST(PointSelection, DepthTimeCompensationPutsPointsBackOnTheSurface) {
  const LaggedDepth lagged;
  const auto& [scene, pose, M, frame] = lagged;
  PointSelector selector(640, 480, core::SelectionParameters{});
  const auto surface_errors = [&](const core::SE3& colour_T_depth) {
    PointCloud cloud(8192);
    EXPECT_EQ(selector.select(frame, cloud, colour_T_depth).status, SelectionStatus::kOk);
    std::vector<double> d;
    for (std::size_t i = 0; i < cloud.size(); ++i)
      d.push_back(sim::distance_to_surface(scene, pose * cloud.position(i).cast<double>()));
    std::sort(d.begin(), d.end());
    EXPECT_GT(d.size(), 2000u);
    return d;
  };
  const auto plain = surface_errors(core::SE3());
  const auto compensated = surface_errors(M);
  const auto at = [](const std::vector<double>& d, double q) {
    return d[static_cast<std::size_t>(q * (d.size() - 1))];
  };
  std::printf("distance to the surface, median / p90: as read %.1f / %.1f mm, compensated %.1f / %.1f mm\n",
              1e3 * at(plain, 0.5), 1e3 * at(plain, 0.9), 1e3 * at(compensated, 0.5), 1e3 * at(compensated, 0.9));
  EXPECT_GT(at(plain, 0.5), 0.01);
  EXPECT_LT(at(compensated, 0.5), 0.002);
  EXPECT_LT(at(compensated, 0.9), 0.01);
}

// A frame with the Kinect-like noise of the renderer (independent per pixel): a point's depth from
// its pixel alone scatters about the surface by the sensor's noise, the mean over its window's
// pixels on the same surface by a fraction of it; and the window never reaches across a depth
// edge (no point pulled off its surface toward another).
TEST(PointSelection, TheDepthWindowAveragesTheSensorNoiseOnThePointsSurface) {
  const auto scene = sim::make_scene(sim::SceneKind::textured_room, 42);
  const auto K = *core::camera_preset("synthetic");
  const auto pose = testing::camera_looking_north();
  sim::NoiseOptions noise;
  noise.enabled = true;
  const core::RgbdFrame frame = sim::render(scene, K, pose, noise, 7);
  const auto surface_errors = [&](int window) {
    core::SelectionParameters p;
    p.depth_window = window;
    PointCloud cloud(8192);
    EXPECT_EQ(PointSelector(640, 480, p).select(frame, cloud).status, SelectionStatus::kOk);
    std::vector<double> d;
    for (std::size_t i = 0; i < cloud.size(); ++i)
      d.push_back(sim::distance_to_surface(scene, pose * cloud.position(i).cast<double>()));
    EXPECT_GT(d.size(), 2000u);
    return d;
  };
  const auto median = [](std::vector<double> d) {
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
    return d[d.size() / 2];
  };
  const auto far = [](const std::vector<double>& d) {
    return std::count_if(d.begin(), d.end(), [](double x) { return x > 0.03; });
  };
  const auto own = surface_errors(0), window = surface_errors(2);
  std::printf(
      "distance to the surface, median: the pixel's own depth %.2f mm, the 5x5 window's %.2f mm; beyond 3 cm: %td, "
      "%td\n",
      1e3 * median(own), 1e3 * median(window), far(own), far(window));
  EXPECT_LT(median(window), 0.5 * median(own));
  EXPECT_LE(far(window), far(own));
}

// reselect(): the frame of the last select() at another compensation gives the very points a full
// select() gives there; another frame is selected in full.
TEST(PointSelection, ReselectingAtAnotherCompensationGivesWhatSelectGives) {
  LaggedDepth lagged;
  lagged.frame.index = 7;
  const auto& [scene, pose, M, frame] = lagged;
  const auto K = frame.intrinsics;
  PointSelector selector(640, 480, core::SelectionParameters{});
  PointCloud first(8192), again(8192), full(8192);
  selector.select(frame, first, core::SE3());
  const auto r = selector.reselect(frame, again, M);
  PointSelector fresh(640, 480, core::SelectionParameters{});
  const auto f = fresh.select(frame, full, M);
  ASSERT_EQ(r.status, f.status);
  EXPECT_EQ(r.selected, f.selected);
  EXPECT_EQ(r.cell_size, f.cell_size);
  ASSERT_EQ(again.size(), full.size());
  bool moved = false;
  for (std::size_t i = 0; i < full.size(); ++i) {
    ASSERT_EQ(again.position(i), full.position(i)) << "point " << i;
    ASSERT_EQ(again.feature(i), full.feature(i));
    moved = moved || (i < first.size() && first.position(i) != full.position(i));
  }
  EXPECT_TRUE(moved) << "the compensation moves points";
  // Another frame (another index) is selected in full, not back-projected with the last winners.
  core::RgbdFrame other = sim::render(scene, K, pose * core::SE3::from_translation(Eigen::Vector3d(0.3, 0, 0)));
  other.index = 8;
  PointCloud reselected(8192), selected(8192);
  selector.reselect(other, reselected, core::SE3());
  fresh.select(other, selected, core::SE3());
  ASSERT_EQ(reselected.size(), selected.size());
  for (std::size_t i = 0; i < selected.size(); ++i) ASSERT_EQ(reselected.position(i), selected.position(i));
}

TEST(PointSelection, GradientWeightScalesTheGradientLabel) {
  const auto frame = rendered(sim::SceneKind::textured_room);
  core::SelectionParameters full, half, none;
  full.gradient_weight = 1.0;
  half.gradient_weight = 0.5;
  none.gradient_weight = 0.0;
  PointCloud full_cloud(8192), half_cloud(8192), none_cloud(8192);
  PointSelector(640, 480, full).select(frame, full_cloud);
  PointSelector(640, 480, half).select(frame, half_cloud);
  PointSelector(640, 480, none).select(frame, none_cloud);
  ASSERT_EQ(full_cloud.size(), half_cloud.size());  // the weight changes labels, not the selection
  ASSERT_EQ(full_cloud.size(), none_cloud.size());
  double sum = 0;
  for (std::size_t i = 0; i < full_cloud.size(); ++i) {
    EXPECT_FLOAT_EQ(half_cloud.feature(i)[3], 0.5f * full_cloud.feature(i)[3]);
    EXPECT_FLOAT_EQ(half_cloud.feature(i)[0], full_cloud.feature(i)[0]);
    EXPECT_EQ(none_cloud.feature(i)[4], 0.0f);
    sum += std::abs(full_cloud.feature(i)[3]) + std::abs(full_cloud.feature(i)[4]);
  }
  EXPECT_GT(sum, 0.05 * static_cast<double>(full_cloud.size()));  // selected points do have gradient
}

TEST(PointSelection, BadFramesGiveAStatusNotACrash) {
  PointSelector selector(640, 480, core::SelectionParameters{});
  PointCloud cloud(8192);
  core::RgbdFrame empty;
  EXPECT_EQ(selector.select(empty, cloud).status, SelectionStatus::kEmptyFrame);

  auto frame = rendered(sim::SceneKind::textured_room);
  core::RgbdFrame small = frame;
  small.bgr = frame.bgr(cv::Rect(0, 0, 320, 240)).clone();
  EXPECT_EQ(selector.select(small, cloud).status, SelectionStatus::kEmptyFrame);

  core::RgbdFrame wrong_type = frame;
  frame.depth.convertTo(wrong_type.depth, CV_32F);
  EXPECT_EQ(selector.select(wrong_type, cloud).status, SelectionStatus::kBadImageType);

  core::RgbdFrame no_depth = frame;
  no_depth.depth = cv::Mat::zeros(480, 640, CV_16UC1);
  const auto r = selector.select(no_depth, cloud);
  EXPECT_EQ(r.status, SelectionStatus::kNoValidDepth);
  EXPECT_EQ(cloud.size(), 0u);
}

// The pixels of `plain` (a distortion-free selection) by pinhole projection, rounded.
std::vector<cv::Point2d> pinhole_pixels(const PointCloud& plain, const core::Intrinsics& K) {
  std::vector<cv::Point2d> pixels;
  for (std::size_t i = 0; i < plain.size(); ++i) {
    const Eigen::Vector3d p = plain.position(i).cast<double>();  // a value: position() is one
    pixels.emplace_back(std::round(K.fx * p.x() / p.z() + K.cx), std::round(K.fy * p.y() / p.z() + K.cy));
  }
  return pixels;
}

// Each point of `distorted` must project, through the lens model, onto the pixel it came from.
void expect_rays_through_pixels(const PointCloud& distorted, const core::Intrinsics& K,
                                const std::vector<cv::Point2d>& pixels) {
  ASSERT_EQ(distorted.size(), pixels.size());
  std::vector<cv::Point3d> points;
  for (std::size_t i = 0; i < distorted.size(); ++i) {
    const Eigen::Vector3d p = distorted.position(i).cast<double>();
    points.emplace_back(p.x(), p.y(), p.z());
  }
  std::vector<cv::Point2d> projected;
  const cv::Matx33d camera(K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1);
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera, K.distortion, projected);
  double worst = 0;
  for (std::size_t i = 0; i < pixels.size(); ++i) worst = std::max(worst, cv::norm(projected[i] - pixels[i]));
  EXPECT_LT(worst, 2e-3) << "pixels";  // float rays; OpenCV iterates to 1e-4 px
}

TEST(PointSelection, DistortedCameraBackProjectsThroughTheLensModel) {
  const auto frame = rendered(sim::SceneKind::textured_room);
  PointSelector selector(640, 480, core::SelectionParameters{});
  PointCloud plain(8192), distorted(8192);
  selector.select(frame, plain);
  const auto pixels = pinhole_pixels(plain, frame.intrinsics);

  // The same images seen as from a TUM fr1 lens: the same pixels and depths are selected (the
  // selection never looks at the intrinsics), only their rays change.
  auto fr1 = frame;
  fr1.intrinsics.distortion = core::camera_preset("tum_fr1")->distortion;
  selector.select(fr1, distorted);
  ASSERT_EQ(distorted.size(), plain.size());
  double largest_shift = 0;
  for (std::size_t i = 0; i < plain.size(); ++i) {
    ASSERT_EQ(distorted.position(i).z(), plain.position(i).z()) << "z is the measured depth, unchanged";
    ASSERT_EQ(distorted.feature(i), plain.feature(i));
    largest_shift = std::max(largest_shift, static_cast<double>((distorted.position(i) - plain.position(i)).norm()));
  }
  EXPECT_GT(largest_shift, 0.01) << "fr1's lens moves corner rays by centimetres at a metre or more";
  expect_rays_through_pixels(distorted, fr1.intrinsics, pixels);

  // Changed intrinsics rebuild the table; back to zero distortion is the pinhole division again.
  auto fr2 = frame;
  fr2.intrinsics.distortion = core::camera_preset("tum_fr2")->distortion;
  selector.select(fr2, distorted);
  expect_rays_through_pixels(distorted, fr2.intrinsics, pixels);
  selector.select(frame, distorted);
  for (std::size_t i = 0; i < plain.size(); ++i) ASSERT_EQ(distorted.position(i), plain.position(i));
}

TEST(PointSelection, CapacityIsClampedAndReported) {
  const auto frame = rendered(sim::SceneKind::textured_room);
  PointSelector selector(640, 480, core::SelectionParameters{});
  PointCloud tiny(100);
  const auto r = selector.select(frame, tiny);
  EXPECT_EQ(r.status, SelectionStatus::kCapacityClamped);
  EXPECT_EQ(tiny.size(), 100u);
  EXPECT_GT(tiny.overflowed(), 0u);
}

// The depth test runs on raw integer depths through bounds found once per frame from the float
// test !(d <= 0 || d < min || d > max); odd bounds must keep that test's meaning.
TEST(PointSelection, DepthBoundsKeepTheFloatTestsMeaning) {
  const auto frame = rendered(sim::SceneKind::textured_room);
  const auto select_with = [&](double min_depth, double max_depth, PointCloud& cloud) {
    core::SelectionParameters parameters;
    parameters.min_depth_m = min_depth;
    parameters.max_depth_m = max_depth;
    PointSelector selector(640, 480, parameters);
    return selector.select(frame, cloud);
  };
  PointCloud a(8192), b(8192);
  // A NaN bound rejects nothing (every comparison with it is false), as a bound of 0 or of 1e9.
  const auto ra = select_with(std::nan(""), 2.5, a), rb = select_with(0.0, 2.5, b);
  EXPECT_EQ(ra.valid_depth_pixels, rb.valid_depth_pixels);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a.position(i), b.position(i));
  EXPECT_EQ(select_with(0.0, std::nan(""), a).valid_depth_pixels, select_with(0.0, 1e9, b).valid_depth_pixels);
  // Fractional bounds: only whole raw depths inside them count, the ends included.
  const auto ends = select_with(1.0, 2.0, a).valid_depth_pixels;
  const double scale = frame.intrinsics.depth_scale;
  EXPECT_EQ(select_with(1.0 - 0.4 / scale, 2.0 + 0.4 / scale, b).valid_depth_pixels, ends);
  EXPECT_LE(select_with(1.0 + 0.4 / scale, 2.0 - 0.4 / scale, b).valid_depth_pixels, ends);
  EXPECT_EQ(select_with(3.0, 1.0, a).status, SelectionStatus::kNoValidDepth);  // empty range
  EXPECT_EQ(select_with(0.0, 0.0, a).status, SelectionStatus::kNoValidDepth);  // raw 0 is never valid
}

}  // namespace
}  // namespace cvo::registration
