// The one mapping from the configuration to every module's parameters (module_parameters.hpp):
// the defaults it gives are exactly the modules' own (so no program's behaviour changed when the
// hand-written mappings were replaced), and every key reaches its module, through --set as
// through a file, in cvo-run end to end.
#include "libcvo/config/mapper_parameters.hpp"
#include "libcvo/config/module_parameters.hpp"

#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::config {
namespace {

// Field by field, doubles exactly: "the same results bit for bit" needs the same values.
void expect_same(const core::SelectionParameters& a, const core::SelectionParameters& b) {
  EXPECT_EQ(a.target_points, b.target_points);
  EXPECT_EQ(a.min_depth_m, b.min_depth_m);
  EXPECT_EQ(a.max_depth_m, b.max_depth_m);
  EXPECT_EQ(a.gradient_weight, b.gradient_weight);
  EXPECT_EQ(a.depth_time_offset_s, b.depth_time_offset_s);
}

void expect_same(const core::CvoParameters& a, const core::CvoParameters& b) {
  EXPECT_EQ(a.ell_init, b.ell_init);
  EXPECT_EQ(a.ell_min, b.ell_min);
  EXPECT_EQ(a.ell_decay, b.ell_decay);
  EXPECT_EQ(a.sigma, b.sigma);
  EXPECT_EQ(a.ell_color, b.ell_color);
  EXPECT_EQ(a.sigma_color, b.sigma_color);
  EXPECT_EQ(a.sparsification_threshold, b.sparsification_threshold);
  EXPECT_EQ(a.max_iterations, b.max_iterations);
  EXPECT_EQ(a.min_step, b.min_step);
  EXPECT_EQ(a.threads, b.threads);
}

TEST(ConfigModuleParameters, DefaultsAreTheModulesOwn) {
  const Config c;

  const auto f2f = frame_to_frame_parameters(c);
  const odometry::FrameToFrameParameters f2f_default;
  expect_same(f2f.selection, f2f_default.selection);
  expect_same(f2f.cvo, f2f_default.cvo);
  EXPECT_EQ(f2f.max_points, 8192u);
  EXPECT_EQ(f2f.max_points, f2f_default.max_points);
  EXPECT_EQ(f2f.restart_after_failures, 3);
  EXPECT_EQ(f2f.restart_after_failures, f2f_default.restart_after_failures);

  const auto kf = keyframe_odometry_parameters(c);
  const odometry::KeyframeOdometryParameters kf_default;
  expect_same(kf.selection, kf_default.selection);
  expect_same(kf.cvo, kf_default.cvo);
  EXPECT_EQ(kf.keyframe.inner_product_ratio_threshold, kf_default.keyframe.inner_product_ratio_threshold);
  EXPECT_EQ(kf.keyframe.translation_threshold_m, kf_default.keyframe.translation_threshold_m);
  EXPECT_EQ(kf.keyframe.rotation_threshold_deg, kf_default.keyframe.rotation_threshold_deg);
  EXPECT_EQ(kf.max_points, 8192u);
  EXPECT_EQ(kf.local_graph_capacity, 300u);
  EXPECT_EQ(kf.gamma_ell, 0.1);
  EXPECT_EQ(kf.gamma_sigma, 0.316);
  EXPECT_EQ(kf.gamma_stride, 4u);
  EXPECT_EQ(kf.chain_weight, 2.0);
  EXPECT_EQ(kf.chain_full_weight_deg, 3.0);
  EXPECT_EQ(kf.max_points, kf_default.max_points);
  EXPECT_EQ(kf.local_graph_capacity, kf_default.local_graph_capacity);
  EXPECT_EQ(kf.gamma_ell, kf_default.gamma_ell);
  EXPECT_EQ(kf.gamma_sigma, kf_default.gamma_sigma);
  EXPECT_EQ(kf.gamma_stride, kf_default.gamma_stride);
  EXPECT_EQ(kf.chain_weight, kf_default.chain_weight);
  EXPECT_EQ(kf.chain_full_weight_deg, kf_default.chain_full_weight_deg);

  const auto cv = opencv_odometry_parameters(c, odometry::OpenCvVariant::rgbd_icp);
  const odometry::OpenCvOdometryParameters cv_default;
  EXPECT_EQ(cv.variant, odometry::OpenCvVariant::rgbd_icp);
  EXPECT_EQ(opencv_odometry_parameters(c, odometry::OpenCvVariant::rgbd).variant, odometry::OpenCvVariant::rgbd);
  EXPECT_EQ(cv.min_depth_m, cv_default.min_depth_m);
  EXPECT_EQ(cv.max_depth_m, cv_default.max_depth_m);
  EXPECT_EQ(cv.restart_after_failures, cv_default.restart_after_failures);

  const auto orb = orb_parameters(c);
  EXPECT_EQ(orb.features, 1000);
  EXPECT_EQ(orb.scale_factor, 1.2f);  // the float the module had before, to the bit
  EXPECT_EQ(orb.levels, 8);
  EXPECT_EQ(orb.edge_threshold, 31);
  EXPECT_EQ(orb.fast_threshold, 20);
  const loop_closure::OrbParameters orb_default;
  EXPECT_EQ(orb.scale_factor, orb_default.scale_factor);

  const auto loop = loop_detector_parameters(c);
  const loop_closure::LoopDetectorParameters loop_default;
  EXPECT_EQ(loop.loop.similarity_threshold, loop_default.loop.similarity_threshold);
  EXPECT_EQ(loop.loop.match_ratio, loop_default.loop.match_ratio);
  EXPECT_EQ(loop.loop.min_matches, loop_default.loop.min_matches);
  expect_same(loop.cvo, loop_default.cvo);
  expect_same(loop.selection, loop_default.selection);
  EXPECT_EQ(loop.ransac_iterations, 300);
  EXPECT_EQ(loop.ransac_inlier_m, 0.03);
  EXPECT_EQ(loop.min_inliers, 12);
  EXPECT_EQ(loop.min_inlier_retention, 0.5);
  EXPECT_EQ(loop.max_refinements, 3);
  EXPECT_EQ(loop.max_points, 8192u);
  EXPECT_EQ(loop.ransac_seed, 0u);
  EXPECT_EQ(loop.ransac_iterations, loop_default.ransac_iterations);
  EXPECT_EQ(loop.max_refinements, loop_default.max_refinements);
  EXPECT_EQ(loop.orb.features, loop_default.orb.features);

  const auto backend = backend_parameters(c);
  const slam::BackendParameters backend_default;
  EXPECT_EQ(backend.cauchy_delta, 2.0);
  EXPECT_EQ(backend.bridge_information, 1.0);
  EXPECT_EQ(backend.max_iterations, 100);
  EXPECT_EQ(backend.cauchy_delta, backend_default.cauchy_delta);
  EXPECT_EQ(backend.bridge_information, backend_default.bridge_information);
  EXPECT_EQ(backend.max_iterations, backend_default.max_iterations);

  const auto mapper = mapper_parameters(c);
  EXPECT_EQ(mapper.detector.max_refinements, loop.max_refinements);
  EXPECT_EQ(mapper.backend.bridge_information, backend.bridge_information);

  EXPECT_EQ(tum_options(c).max_association_dt, io::TumOptions{}.max_association_dt);
}

// One key set away from its default, and where it must then show in the modules' parameters.
struct Reach {
  std::string assignment;
  std::function<bool(const Config&)> reached;
};

TEST(ConfigModuleParameters, EveryKeyReachesItsModules) {
  const std::vector<Reach> reaches{
      {"selection.target_points=1500",
       [](const Config& c) {
         return frame_to_frame_parameters(c).selection.target_points == 1500 &&
                keyframe_odometry_parameters(c).selection.target_points == 1500 &&
                loop_detector_parameters(c).selection.target_points == 1500;
       }},
      {"selection.max_depth_m=3.5",
       [](const Config& c) {
         return opencv_odometry_parameters(c, odometry::OpenCvVariant::rgbd).max_depth_m == 3.5 &&
                loop_detector_parameters(c).selection.max_depth_m == 3.5 &&
                keyframe_odometry_parameters(c).selection.max_depth_m == 3.5;
       }},
      {"selection.min_depth_m=0.3",
       [](const Config& c) { return opencv_odometry_parameters(c, odometry::OpenCvVariant::rgbd).min_depth_m == 0.3; }},
      {"cvo.ell_init=0.15",
       [](const Config& c) {
         return frame_to_frame_parameters(c).cvo.ell_init == 0.15 && keyframe_odometry_parameters(c).cvo.ell_init == 0.15 &&
                mapper_parameters(c).detector.cvo.ell_init == 0.15;
       }},
      {"odometry.max_points=4096",
       [](const Config& c) {
         return frame_to_frame_parameters(c).max_points == 4096 && keyframe_odometry_parameters(c).max_points == 4096 &&
                loop_detector_parameters(c).max_points == 4096;
       }},
      {"odometry.restart_after_failures=5",
       [](const Config& c) {
         return frame_to_frame_parameters(c).restart_after_failures == 5 &&
                opencv_odometry_parameters(c, odometry::OpenCvVariant::rgbd_icp).restart_after_failures == 5;
       }},
      {"keyframe.rotation_threshold_deg=20",
       [](const Config& c) { return keyframe_odometry_parameters(c).keyframe.rotation_threshold_deg == 20; }},
      {"keyframe.local_graph_capacity=2",
       [](const Config& c) { return keyframe_odometry_parameters(c).local_graph_capacity == 2; }},
      {"keyframe.gamma_ell=0.2", [](const Config& c) { return keyframe_odometry_parameters(c).gamma_ell == 0.2; }},
      {"keyframe.gamma_sigma=0.1", [](const Config& c) { return keyframe_odometry_parameters(c).gamma_sigma == 0.1; }},
      {"keyframe.gamma_stride=1", [](const Config& c) { return keyframe_odometry_parameters(c).gamma_stride == 1; }},
      {"keyframe.chain_weight=0", [](const Config& c) { return keyframe_odometry_parameters(c).chain_weight == 0; }},
      {"keyframe.chain_full_weight_deg=10",
       [](const Config& c) { return keyframe_odometry_parameters(c).chain_full_weight_deg == 10; }},
      {"loop_closure.similarity_threshold=0.4",
       [](const Config& c) { return mapper_parameters(c).detector.loop.similarity_threshold == 0.4; }},
      {"loop_closure.max_refinements=0",
       [](const Config& c) { return mapper_parameters(c).detector.max_refinements == 0; }},
      {"loop_closure.ransac_iterations=50",
       [](const Config& c) { return mapper_parameters(c).detector.ransac_iterations == 50; }},
      {"loop_closure.ransac_inlier_m=0.05",
       [](const Config& c) { return mapper_parameters(c).detector.ransac_inlier_m == 0.05; }},
      {"loop_closure.min_inliers=20", [](const Config& c) { return mapper_parameters(c).detector.min_inliers == 20; }},
      {"loop_closure.min_inlier_retention=0.8",
       [](const Config& c) { return mapper_parameters(c).detector.min_inlier_retention == 0.8; }},
      {"loop_closure.ransac_seed=4294967295",
       [](const Config& c) { return mapper_parameters(c).detector.ransac_seed == 4294967295u; }},
      {"loop_closure.orb_features=500", [](const Config& c) { return mapper_parameters(c).detector.orb.features == 500; }},
      {"loop_closure.orb_scale_factor=1.5",
       [](const Config& c) { return mapper_parameters(c).detector.orb.scale_factor == 1.5f; }},
      {"loop_closure.orb_levels=4", [](const Config& c) { return mapper_parameters(c).detector.orb.levels == 4; }},
      {"loop_closure.orb_edge_threshold=40",
       [](const Config& c) { return mapper_parameters(c).detector.orb.edge_threshold == 40; }},
      {"loop_closure.orb_fast_threshold=10",
       [](const Config& c) { return mapper_parameters(c).detector.orb.fast_threshold == 10; }},
      {"pose_graph.cauchy_delta=1.5", [](const Config& c) { return mapper_parameters(c).backend.cauchy_delta == 1.5; }},
      {"pose_graph.bridge_information=0.25",
       [](const Config& c) { return mapper_parameters(c).backend.bridge_information == 0.25; }},
      {"pose_graph.max_iterations=20", [](const Config& c) { return mapper_parameters(c).backend.max_iterations == 20; }},
      {"dataset.max_association_dt=0.01", [](const Config& c) { return tum_options(c).max_association_dt == 0.01; }},
  };
  for (const auto& r : reaches) {
    EXPECT_FALSE(r.reached(Config{})) << r.assignment << ": already the default";
    Config c;
    apply_override(c, r.assignment);
    EXPECT_TRUE(r.reached(c)) << r.assignment << " (--set) does not reach its module";
    const auto dot = r.assignment.find('.'), eq = r.assignment.find('=');
    const auto yaml = r.assignment.substr(0, dot) + ":\n  " + r.assignment.substr(dot + 1, eq - dot - 1) + ": " +
                      r.assignment.substr(eq + 1) + "\n";
    EXPECT_TRUE(r.reached(parse_config(yaml))) << r.assignment << " (file) does not reach its module:\n" << yaml;
  }
}

// End to end: a key that only the mapping hands to KF-CVO changes what cvo-run does. A local
// graph of two frames is full after one tracked frame, so every frame then makes a keyframe.
TEST(ConfigModuleParameters, CvoRunTracksWithTheMappedParameters) {
  const test::TempDir dir("module_parameters");
  const std::string args = cvo::testing::quoted(CVO_TEST_DATA_DIR "/fr1_rpy_50") + " --out " +
                           cvo::testing::quoted(dir.path() / "t.txt") + " --mode kf-cvo --json --max-frames 6";
  const auto plain = cvo::testing::run_tool("cvo-run", args, dir.path());
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const auto forced = cvo::testing::run_tool("cvo-run", args + " --set keyframe.local_graph_capacity=2", dir.path());
  ASSERT_EQ(forced.exit_code, 0) << forced.err;
  const int plain_keyframes = std::stoi(cvo::testing::json_value(plain.out, "keyframes"));
  const int forced_keyframes = std::stoi(cvo::testing::json_value(forced.out, "keyframes"));
  EXPECT_LE(plain_keyframes, 2) << plain.out;
  EXPECT_GE(forced_keyframes, 4) << forced.out;
}

}  // namespace
}  // namespace cvo::config
