#include "libcvo/odometry/keyframe_odometry.hpp"

#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/eval/rpe.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "tests/odometry/odometry_fixtures.hpp"
#include "tests/support/small_camera.hpp"

namespace cvo::odometry {
namespace {

// A half-size synthetic camera keeps these tests fast.
core::Intrinsics small_camera() { return cvo::testing::small_synthetic_camera(2); }

/// Frames seen from start * step^i in the textured room: a constant motion per frame.
std::vector<core::RgbdFrame> constant_motion(const core::SE3& step, int n) {
  const auto scene = sim::make_scene(sim::SceneKind::textured_room, 42);
  const auto camera = small_camera();
  core::SE3 pose = sim::look_at({0.0, -1.2, 1.3}, {0.3, 2.5, 1.0});
  std::vector<core::RgbdFrame> frames;
  for (int i = 0; i < n; ++i) {
    auto frame = sim::render(scene, camera, pose, {}, 0, testing::fast_render());
    frame.index = static_cast<std::uint64_t>(i);
    frame.timestamp = frame.depth_timestamp = 1000.0 + i / 30.0;
    frames.push_back(std::move(frame));
    pose = pose * step;
  }
  return frames;
}

KeyframeOdometryParameters only(double gamma, double translation_m, double rotation_deg) {
  KeyframeOdometryParameters p;
  p.keyframe.inner_product_ratio_threshold = gamma;
  p.keyframe.translation_threshold_m = translation_m;
  p.keyframe.rotation_threshold_deg = rotation_deg;
  return p;
}

struct Switch {
  std::uint64_t at_frame, keyframe;
  KeyframeReason reason;
};

std::vector<Switch> keyframe_switches(const std::vector<core::RgbdFrame>& frames, const KeyframeOdometryParameters& p,
                                      std::vector<double>* gammas = nullptr) {
  KeyframeOdometry odometry(320, 240, p);
  std::vector<Switch> switches;
  for (const auto& f : frames) {
    const auto r = odometry.track(f);
    EXPECT_TRUE(r.tracked()) << "frame " << f.index;
    if (gammas) gammas->push_back(r.gamma);
    if (r.new_keyframe && f.index > 0) switches.push_back({f.index, r.new_keyframe->frame.index, r.reason});
  }
  return switches;
}

TEST(KeyframeOdometry, TranslationAloneTriggersAndFrameBeforeBecomesKeyframe) {
  // 2 cm per frame along the view direction; t_thres 5 cm: frame m+3 (6 cm) trips, m+2 becomes
  // the keyframe, so switches happen at frames 3, 5, 7 with keyframes 2, 4, 6.
  const auto frames = constant_motion(core::SE3::from_translation({0.0, 0.0, 0.02}), 8);
  const auto s = keyframe_switches(frames, only(0.0, 0.05, 180.0));
  ASSERT_EQ(s.size(), 3u);
  for (std::size_t k = 0; k < s.size(); ++k) {
    EXPECT_EQ(s[k].at_frame, 3 + 2 * k);
    EXPECT_EQ(s[k].keyframe, s[k].at_frame - 1);
    EXPECT_EQ(s[k].reason, KeyframeReason::kTranslation);
  }
}

TEST(KeyframeOdometry, RotationAloneTriggers) {
  // 2° of yaw per frame; θ_thres 5°: frame m+3 (6°) trips. The walls are 3-4 m away, so the first
  // frame (identity guess) moves points by ~12 cm: start the schedule wider than the tracker's
  // default reach of ~6 cm.
  const auto frames = constant_motion(core::SE3::from_rotation_vector({0.0, 2.0 * std::numbers::pi / 180.0, 0.0}), 8);
  auto parameters = only(0.0, 10.0, 5.0);
  parameters.cvo.ell_init = 0.3;
  const auto s = keyframe_switches(frames, parameters);
  ASSERT_EQ(s.size(), 3u);
  for (std::size_t k = 0; k < s.size(); ++k) {
    EXPECT_EQ(s[k].at_frame, 3 + 2 * k);
    EXPECT_EQ(s[k].keyframe, s[k].at_frame - 1);
    EXPECT_EQ(s[k].reason, KeyframeReason::kRotation);
  }
}

TEST(KeyframeOdometry, InnerProductRatioAloneTriggers) {
  // γ falls as the view moves away from the keyframe; with t and θ out of the way, a threshold
  // between its values at m+2 and m+4 must make keyframes for the γ reason alone.
  const auto frames = constant_motion(core::SE3::from_translation({0.03, 0.0, 0.0}), 8);
  std::vector<double> gammas;
  keyframe_switches(frames, only(0.0, 10.0, 180.0), &gammas);
  ASSERT_GT(gammas[2], gammas[4]) << "γ must decrease with the distance to the keyframe";
  const double threshold = 0.5 * (gammas[2] + gammas[4]);
  const auto s = keyframe_switches(frames, only(threshold, 10.0, 180.0));
  ASSERT_FALSE(s.empty());
  for (const auto& sw : s) {
    EXPECT_EQ(sw.reason, KeyframeReason::kGamma);
    EXPECT_EQ(sw.keyframe, sw.at_frame - 1);
  }
}

TEST(KeyframeOdometry, TracksConstantMotionAndClosesLocalGraphs) {
  const core::SE3 step = core::SE3::exp((core::Vector6d() << 0.01, 0.0, 0.015, 0.0, 0.015, 0.005).finished());
  const auto frames = constant_motion(step, 10);
  KeyframeOdometry odometry(320, 240, only(0.0, 0.05, 180.0));
  core::SE3 first;
  int closed = 0;
  for (const auto& f : frames) {
    const auto r = odometry.track(f);
    ASSERT_TRUE(r.tracked());
    if (f.index == 0) first = r.pose;
    // Relative to the first frame the camera moved by step^index.
    core::SE3 truth;
    for (std::uint64_t i = 0; i < f.index; ++i) truth = truth * step;
    const auto e = testing::motion_error(truth, first.inverse() * r.pose);
    EXPECT_LT(e.translation_mm, 3.0) << "frame " << f.index;
    EXPECT_LT(e.rotation_deg, 0.15) << "frame " << f.index;
    if (r.closed_graph) {
      ++closed;
      const auto& g = *r.closed_graph->graph;
      // Keyframe first, then every frame tracked against it; the new keyframe is the last node.
      EXPECT_GE(g.nodes().size(), 2u);
      ASSERT_TRUE(r.new_keyframe) << "a graph closes when a keyframe is made";
      EXPECT_EQ(g.nodes().back().frame_index, r.new_keyframe->frame.index);
      EXPECT_GE(g.edges().size(), g.nodes().size() - 1);
      for (const auto& edge : g.edges()) EXPECT_GT(edge.information.trace(), 0.0);
    }
  }
  EXPECT_GE(closed, 2);
}

// Depth images taken 15 ms after their colour images on even frames and 5 ms before on odd ones
// (TUM's stamps jitter like this), the camera moving 0.9° and 1.8 cm a frame. Without
// compensation every other cloud is warped the other way and the frame-to-frame motion errs; with
// the true stamps (no extra offset) KF-CVO reads each depth where its ray was and the motion is
// right. The first frame has no velocity yet and is left as it is, so errors are counted from
// frame 3, between consecutive frames.
TEST(KeyframeOdometry, DepthTimeCompensationFollowsTheStamps) {
  const core::SE3 step = core::SE3::exp((core::Vector6d() << 0.01, 0.0, 0.015, 0.0, 0.015, 0.005).finished());
  const auto scene = sim::make_scene(sim::SceneKind::textured_room, 42);
  const auto camera = small_camera();
  std::vector<core::RgbdFrame> frames = constant_motion(step, 12);
  core::SE3 pose = sim::look_at({0.0, -1.2, 1.3}, {0.3, 2.5, 1.0});
  for (auto& frame : frames) {
    const double lag_s = frame.index % 2 == 0 ? 0.015 : -0.005;
    const core::SE3 lag = core::SE3::exp(lag_s * 30.0 * step.log());
    frame.depth = sim::render(scene, camera, pose * lag, {}, 0, testing::fast_render()).depth;
    frame.depth_timestamp = frame.timestamp + lag_s;
    pose = pose * step;
  }
  const auto rms_error_mm = [&](bool stamped) {
    KeyframeOdometryParameters p;
    p.selection.depth_time_offset_s = 0.0;
    KeyframeOdometry odometry(320, 240, p);
    core::SE3 previous;
    double sum = 0;
    int n = 0;
    for (auto f : frames) {
      if (!stamped) f.depth_timestamp = f.timestamp;
      const auto r = odometry.track(f);
      EXPECT_TRUE(r.tracked()) << "frame " << f.index << (stamped ? " stamped" : " simultaneous");
      if (f.index >= 3) {
        const auto e = testing::motion_error(step, previous.inverse() * r.pose);
        sum += e.translation_mm * e.translation_mm;
        ++n;
      }
      previous = r.pose;
    }
    return std::sqrt(sum / n);
  };
  const double compensated = rms_error_mm(true), plain = rms_error_mm(false);
  std::printf("depth 15 ms late / 5 ms early: frame-to-frame translation error rms %.2f mm compensated, %.2f mm not\n",
              compensated, plain);
  EXPECT_LT(compensated, 0.5 * plain);
}

// A rolling-shutter camera turning fast and unevenly (pitch and yaw swinging as in TUM's fr1/rpy)
// sees each frame sheared by its own rate. (It starts at rest: the first keyframe, selected before
// there is a velocity, is then not sheared either.) Declared (intrinsics.readout_s), the tracker moves every
// row's points to the frame's time with its motion model; declared a global shutter, it tracks the
// same images as they are.
TEST(KeyframeOdometry, RollingShutterRowsAreMovedToTheFramesTime) {
  constexpr double kReadout = 0.03;
  const auto scene = sim::make_scene(sim::SceneKind::textured_room, 42);
  core::Intrinsics camera = small_camera();
  camera.readout_s = kReadout;
  const core::SE3 start = sim::look_at({0.0, -1.2, 1.3}, {0.3, 2.5, 1.0});
  const auto pose_at = [&](double t) {  // from rest to ~70 deg/s
    const double pitch = 0.18 * (1 - std::cos(2 * M_PI * 0.7 * t)), yaw = 0.3 * (1 - std::cos(2 * M_PI * 0.5 * t));
    return start * core::SE3::exp((core::Vector6d() << 0, 0, 0, pitch, yaw, 0.3 * pitch).finished());
  };
  std::vector<core::RgbdFrame> frames;
  std::vector<core::SE3> truth;
  for (int i = 0; i < 24; ++i) {
    const double t = i / 30.0;
    auto frame = sim::render(
        scene, camera, [&](int v) { return pose_at(t + kReadout * (v / 239.0 - 0.5)); }, {}, 0, testing::fast_render());
    frame.index = static_cast<std::uint64_t>(i);
    frame.timestamp = frame.depth_timestamp = 1000.0 + t;
    frames.push_back(std::move(frame));
    truth.push_back(pose_at(t));
  }
  const auto rms_error_deg = [&](double declared_readout) {
    KeyframeOdometry odometry(320, 240, KeyframeOdometryParameters{});
    core::SE3 previous;
    double sum = 0;
    int n = 0;
    for (auto f : frames) {
      f.intrinsics.readout_s = declared_readout;
      const auto r = odometry.track(f);
      EXPECT_TRUE(r.tracked()) << "frame " << f.index;
      if (f.index >= 3) {
        const core::SE3 true_motion = truth[f.index - 1].inverse() * truth[f.index];
        const auto e = testing::motion_error(true_motion, previous.inverse() * r.pose);
        sum += e.rotation_deg * e.rotation_deg;
        ++n;
      }
      previous = r.pose;
    }
    return std::sqrt(sum / n);
  };
  const double compensated = rms_error_deg(kReadout), plain = rms_error_deg(0.0);
  std::printf("rolling shutter %.0f ms: frame-to-frame rotation error rms %.3f deg compensated, %.3f deg not\n",
              1e3 * kReadout, compensated, plain);
  EXPECT_LT(compensated, 0.5 * plain);
}

// Frames of a rendered path from its start, each row seen at its own time when `readout` > 0
// (a rolling shutter), with the true pose of each frame's time.
struct PathFrames {
  std::vector<core::RgbdFrame> frames;
  std::vector<core::SE3> truth;
};
PathFrames path_frames(const std::function<core::SE3(double)>& pose_at, int n, double readout,
                       core::Intrinsics camera = small_camera(), const sim::NoiseOptions& noise = {},
                       std::uint64_t scene_seed = 42) {
  const auto scene = sim::make_scene(sim::SceneKind::textured_room, scene_seed);
  camera.readout_s = readout;
  PathFrames p;
  for (int i = 0; i < n; ++i) {
    const double t = i / 30.0;
    const double last_row = camera.height - 1;
    auto frame = sim::render(
        scene, camera, [&](int v) { return pose_at(t + readout * (v / last_row - 0.5)); }, noise,
        static_cast<std::uint64_t>(i), testing::fast_render());
    frame.index = static_cast<std::uint64_t>(i);
    frame.timestamp = frame.depth_timestamp = 1000.0 + t;
    p.frames.push_back(std::move(frame));
    p.truth.push_back(pose_at(t));
  }
  return p;
}

// The rotation error of every published increment from frame `from` on.
std::vector<double> increment_errors_deg(const PathFrames& p, int from) {
  const auto& K = p.frames.front().intrinsics;
  KeyframeOdometry odometry(K.width, K.height, KeyframeOdometryParameters{});
  std::vector<double> errors;
  core::SE3 previous;
  for (const auto& f : p.frames) {
    const auto r = odometry.track(f);
    EXPECT_TRUE(r.tracked()) << "frame " << f.index;
    if (static_cast<int>(f.index) >= from)
      errors.push_back(
          testing::motion_error(p.truth[f.index - 1].inverse() * p.truth[f.index], previous.inverse() * r.pose)
              .rotation_deg);
    previous = r.pose;
  }
  return errors;
}

double rms(const std::vector<double>& x) {
  double sum = 0;
  for (const double v : x) sum += v * v;
  return std::sqrt(sum / static_cast<double>(x.size()));
}

// A session that starts while the camera already turns at full speed (the rendered rpy path, some
// 70 °/s from its first frame; a tracker restarted while its robot is carried): its first pair has
// no constant-velocity guess, so its frame-to-frame registration starts with a wider kernel and
// lands on the motion, not in an optimum degrees away.
TEST(KeyframeOdometry, ASessionThatStartsTurningAtFullSpeedIsTrackedFromItsFirstPair) {
  sim::NoiseOptions noise;
  noise.enabled = true;
  const auto p = path_frames([](double t) { return sim::path_pose(sim::PathKind::rpy, t); }, 4, 0.0,
                             *core::camera_preset("synthetic"), noise, 0);
  const auto errors = increment_errors_deg(p, 1);
  std::printf("rpy path from its start: rotation error of the first pairs %.3f %.3f %.3f deg\n", errors[0], errors[1],
              errors[2]);
  for (const double e : errors) EXPECT_LT(e, 0.2);
}

// A rolling-shutter session's first frame is selected before any motion is known. Once the second
// frame's motion is measured, the first is selected again with it: the first keyframe, which every
// frame until the next keyframe is registered against, is not left stretched by the turn.
TEST(KeyframeOdometry, TheFirstFrameOfARollingShutterSessionIsSelectedAgainWithTheMotion) {
  const auto p = path_frames([](double t) { return sim::path_pose(sim::PathKind::rpy, t); }, 8, 0.03);
  const auto errors = increment_errors_deg(p, 1);
  std::printf("rpy path, 30 ms rolling shutter, from its start: rotation error rms %.3f deg, first pair %.3f deg\n",
              rms(errors), errors[0]);
  EXPECT_LT(rms(errors), 0.1);
}

// The compensations move a frame's rows by the frame's own motion, measured by a first registration
// (the header): a camera speeding up from rest to ~70 °/s is compensated for the turn it makes, not
// the one it made 1.5 frames before.
TEST(KeyframeOdometry, TheCompensationsFollowTheFramesOwnMotion) {
  const core::SE3 start = sim::look_at({0.0, -1.2, 1.3}, {0.3, 2.5, 1.0});
  const auto p = path_frames(
      [&](double t) {
        const double pitch = 0.18 * (1 - std::cos(2 * M_PI * 0.7 * t)), yaw = 0.3 * (1 - std::cos(2 * M_PI * 0.5 * t));
        return start * core::SE3::exp((core::Vector6d() << 0, 0, 0, pitch, yaw, 0.3 * pitch).finished());
      },
      24, 0.03);
  const auto errors = increment_errors_deg(p, 3);
  std::printf("30 ms rolling shutter, turning from rest to ~70 deg/s: rotation error rms %.4f deg\n", rms(errors));
  EXPECT_LT(rms(errors), 0.025);  // with the last interval's motion: 0.028
}

// Past chain_full_weight_deg of rotation from the keyframe the published pose is the keyframe
// result fused with the frame-to-frame chain; it stays accurate, the graph keeps the raw keyframe
// edge, and chain_weight = 0 publishes exactly that edge (the paper's pure keyframe-to-frame).
TEST(KeyframeOdometry, ChainFusionStaysAccurateAndZeroWeightPublishesTheKeyframeEdge) {
  const core::SE3 step = core::SE3::exp((core::Vector6d() << 0.005, 0.0, 0.005, 0.0, 0.02, 0.01).finished());
  const auto frames = constant_motion(step, 12);
  for (const double weight : {0.0, 2.0}) {
    auto p = only(0.0, 1.0, 180.0);
    p.tracking.chain_weight = weight;
    KeyframeOdometry odometry(320, 240, p);
    core::SE3 first;
    std::vector<core::SE3> poses;
    std::vector<LocalGraph> graphs;  // every closed one, then the open one
    for (const auto& f : frames) {
      const auto r = odometry.track(f);
      ASSERT_TRUE(r.tracked()) << "weight " << weight << " frame " << f.index;
      if (f.index == 0) first = r.pose;
      poses.push_back(r.pose);
      if (r.closed_graph) graphs.push_back(*r.closed_graph->graph);
      core::SE3 truth;
      for (std::uint64_t i = 0; i < f.index; ++i) truth = truth * step;
      const auto e = testing::motion_error(truth, first.inverse() * r.pose);
      EXPECT_LT(e.translation_mm, 3.0) << "weight " << weight << " frame " << f.index;
      EXPECT_LT(e.rotation_deg, 0.2) << "weight " << weight << " frame " << f.index;
    }
    if (weight != 0.0) continue;
    graphs.push_back(*odometry.finish()->graph);
    for (const auto& g : graphs)
      for (const auto& edge : g.edges()) {
        if (edge.from != g.keyframe().frame_index || edge.to < 2) continue;
        const auto d = testing::motion_error(g.keyframe().pose * edge.measurement, poses[edge.to]);
        EXPECT_LT(d.translation_mm, 1e-6) << "frame " << edge.to;
        EXPECT_LT(d.rotation_deg, 1e-6) << "frame " << edge.to;
      }
  }
}

// What a back end needs comes back from track() itself: the keyframe made at frame n is frame
// n-1, whose images it shares (no copy), with its id (from 0), pose and cloud; the graph it closes
// is named by the old keyframe's id; every frame tracked against a keyframe carries its edge's
// covariance; finish() hands out the open graph once and starts a new session.
TEST(KeyframeOdometry, EachStepCarriesWhatItClosedAndMadeAndFinishEndsTheSession) {
  const auto frames = constant_motion(core::SE3::from_translation({0.012, 0.0, 0.0}), 8);
  KeyframeOdometry odometry(320, 240, only(0.0, 0.03, 180.0));
  std::int64_t keyframes = 0, graphs = 0;
  std::uint64_t keyframe_frame = 0;
  for (const auto& f : frames) {
    const auto r = odometry.track(f);
    ASSERT_TRUE(r.tracked()) << "frame " << f.index;
    EXPECT_EQ(r.keyframe_id, keyframes - (r.new_keyframe ? 0 : 1)) << "frame " << f.index;
    if (r.new_keyframe) {
      const auto& k = *r.new_keyframe;
      EXPECT_EQ(k.id, keyframes++);
      const auto& source = f.index == 0 ? f : frames[f.index - 1];
      EXPECT_EQ(k.frame.index, source.index);
      EXPECT_EQ(k.frame.bgr.data, source.bgr.data) << "the keyframe shares its frame's images";
      EXPECT_EQ(k.frame.depth.data, source.depth.data);
      ASSERT_NE(k.cloud, nullptr);
      EXPECT_GT(k.cloud->size(), 100u);
      if (f.index > 0) {
        EXPECT_EQ(r.reason, KeyframeReason::kTranslation);
      }
    }
    if (r.closed_graph) {
      EXPECT_EQ(r.closed_graph->keyframe_id, graphs++) << "graphs close in keyframe order";
      EXPECT_EQ(r.closed_graph->graph->keyframe().frame_index, keyframe_frame) << "named by the old keyframe";
    }
    if (r.new_keyframe) keyframe_frame = r.new_keyframe->frame.index;
    if (f.index > 0) {
      ASSERT_TRUE(r.edge_covariance) << "frame " << f.index;
      EXPECT_GT(r.edge_covariance->trace(), 0.0);
      EXPECT_TRUE(r.edge_covariance->isApprox(r.edge_covariance->transpose(), 1e-9));
    } else {
      EXPECT_FALSE(r.edge_covariance) << "a first frame has no edge";
    }
  }
  ASSERT_GE(keyframes, 3) << "3 cm of translation every 2.5 frames";
  EXPECT_EQ(graphs, keyframes - 1);

  const auto open = odometry.finish();
  ASSERT_TRUE(open);
  EXPECT_EQ(open->keyframe_id, keyframes - 1);
  EXPECT_EQ(open->graph->nodes().back().frame_index, frames.back().index);
  EXPECT_FALSE(odometry.finish()) << "the open graph is handed out once";

  const auto again = odometry.track(frames[0]);
  EXPECT_EQ(again.status, TrackStatus::kFirstFrame);
  ASSERT_TRUE(again.new_keyframe);
  EXPECT_EQ(again.new_keyframe->id, 0) << "a new session counts keyframes from 0";
  EXPECT_FALSE(again.closed_graph);
}

TEST(KeyframeOdometry, FailuresPredictAndRestart) {
  const auto frames = constant_motion(core::SE3::from_translation({0.0, 0.0, 0.01}), 6);
  KeyframeOdometry odometry(320, 240, KeyframeOdometryParameters{});
  odometry.track(frames[0]);
  const auto r1 = odometry.track(frames[1]);
  core::RgbdFrame empty;  // no images: selection fails, the pose is predicted
  empty.index = 2;
  const auto r2 = odometry.track(empty);
  EXPECT_EQ(r2.status, TrackStatus::kSelectionFailed);
  EXPECT_FALSE(r2.tracked());
  EXPECT_LT((r2.pose.translation() - (r1.pose * r1.motion).translation()).norm(), 1e-9);
  // The next usable frame restarts with a keyframe at its predicted pose: no jump, no crash.
  const auto r3 = odometry.track(frames[3]);
  EXPECT_TRUE(r3.keyframe);
  EXPECT_EQ(r3.reason, KeyframeReason::kRestart);
  EXPECT_LT((r3.pose.translation() - r2.pose.translation()).norm(), 0.05);
  EXPECT_TRUE(odometry.track(frames[4]).tracked());
}

TEST(KeyframeOdometry, RealSampleTracks) {
  auto sequence = io::TumSequence::open(std::filesystem::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50");
  KeyframeOdometry odometry(640, 480, KeyframeOdometryParameters{});
  core::Trajectory estimate;
  int keyframes = 0;
  while (const auto frame = sequence.next()) {
    const auto r = odometry.track(*frame);
    EXPECT_TRUE(r.tracked()) << "frame " << frame->index;
    keyframes += r.keyframe;
    estimate.push_back({frame->timestamp, r.pose});
  }
  const auto rpe = eval::relative_pose_error(sequence.groundtruth(), estimate, {});
  std::printf("KF-CVO on fr1_rpy_50: %d keyframes, RPE %.4f m/s, %.3f deg/s\n", keyframes, rpe.translation.rmse,
              rpe.rotation_deg.rmse);
  // Measured 0.055 m/s and 3.8-4.3 deg/s with 12-13 keyframes: worse than frame-to-frame CVO on
  // this clip (0.048, 2.3) — keyframe registrations across > 10° of roll lose accuracy; see the
  // closing note of the KF-CVO work. The bound only catches breakage (drift of a lost tracker is
  // an order of magnitude larger).
  EXPECT_LT(rpe.translation.rmse, 0.10);
  EXPECT_LT(rpe.rotation_deg.rmse, 8.0);
  EXPECT_GT(keyframes, 1);
}

}  // namespace
}  // namespace cvo::odometry
