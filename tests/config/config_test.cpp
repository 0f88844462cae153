#include "libcvo/config/config.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/core/session.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::config {
namespace {

bool contains(const std::exception& e, const std::string& fragment) {
  return std::string(e.what()).find(fragment) != std::string::npos;
}

TEST(Config, DefaultsAreThePapersTable1) {
  const Config c;
  EXPECT_DOUBLE_EQ(c.keyframe.translation_threshold_m, 0.15);
  EXPECT_DOUBLE_EQ(c.keyframe.rotation_threshold_deg, 30.0);
  EXPECT_DOUBLE_EQ(c.keyframe.inner_product_ratio_threshold, 0.7);
  EXPECT_DOUBLE_EQ(c.loop_closure.similarity_threshold, 0.3);
  EXPECT_DOUBLE_EQ(c.loop_closure.match_ratio, 0.7);
  EXPECT_EQ(c.loop_closure.min_matches, 5);
  EXPECT_DOUBLE_EQ(c.pose_graph.cauchy_delta, 2.0);
  EXPECT_DOUBLE_EQ(c.cvo.sparsification_threshold, 8.315e-3);
  EXPECT_DOUBLE_EQ(c.cvo.ell_init, 0.1);
  EXPECT_DOUBLE_EQ(c.cvo.sigma, 0.1);
  EXPECT_DOUBLE_EQ(c.cvo.ell_color, 0.1);
  EXPECT_DOUBLE_EQ(c.cvo.sigma_color, 1.0);
  EXPECT_DOUBLE_EQ(c.dataset.max_association_dt, 0.02);
  EXPECT_EQ(c.camera, "tum_fr1");
  EXPECT_TRUE(parse_config("") == Config{});
  EXPECT_TRUE(parse_config("# only a comment\n") == Config{});
}

TEST(Config, PartialFileOverridesOnlyThoseKeys) {
  const auto c = parse_config(
      "cvo:\n  ell_init: 0.2\n  max_iterations: 50\nkeyframe: {rotation_threshold_deg: 15}\n"
      "loop_closure:\ncamera: /data/cam.yaml\n");
  Config expected;
  expected.cvo.ell_init = 0.2;
  expected.cvo.max_iterations = 50;
  expected.keyframe.rotation_threshold_deg = 15;
  expected.camera = "/data/cam.yaml";
  EXPECT_TRUE(c == expected);
  EXPECT_FALSE(c == Config{});
}

void expect_error(const std::string& yaml, std::size_t line, const std::string& fragment) {
  try {
    parse_config(yaml, "my.yaml");
    FAIL() << "no error for:\n" << yaml;
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.file(), "my.yaml");
    EXPECT_TRUE(contains(e, fragment)) << e.what();
  }
}

TEST(Config, UnknownKeysAndSectionsAreNamedWithASuggestion) {
  expect_error("cvo:\n  ell_int: 0.2\n", 2, "my.yaml:2: cvo.ell_int: unknown key (did you mean cvo.ell_init?)");
  expect_error("cvo: {translation_threshold_m: 1}\n", 1,
               "cvo.translation_threshold_m: unknown key (did you mean keyframe.translation_threshold_m?)");
  expect_error("cvo:\n  zzz: 1\n", 2, "cvo.zzz: unknown key");
  expect_error("\ncvx:\n  ell_init: 0.2\n", 2, "cvx: unknown section (did you mean cvo?)");
  expect_error("camra: tum_fr2\n", 1, "camra: unknown section (did you mean camera?)");
  try {
    parse_config("cvo: {zzz: 1}\n");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_FALSE(contains(e, "did you mean")) << e.what();
  }
}

TEST(Config, BadValuesNameKeyAndValue) {
  expect_error("cvo:\n  ell_init: abc\n", 2, "cvo.ell_init: expected a finite number, got 'abc'");
  expect_error("cvo:\n  ell_init: -0.1\n", 2, "cvo.ell_init: must be > 0, got '-0.1'");
  expect_error("cvo:\n  ell_init: .nan\n", 2, "cvo.ell_init: expected a finite number, got '.nan'");
  expect_error("cvo:\n  sigma: nan\n", 2, "cvo.sigma: expected a finite number, got 'nan'");
  expect_error("cvo:\n  sigma: .inf\n", 2, "cvo.sigma: expected a finite number");
  expect_error("cvo:\n  ell_init: [0.1, 0.2]\n", 2, "cvo.ell_init: expected a number, got a sequence");
  expect_error("cvo:\n  ell_init:\n", 2, "cvo.ell_init: expected a number, got nothing");
  expect_error("cvo:\n  max_iterations: 2.5\n", 2, "cvo.max_iterations: expected an integer, got '2.5'");
  expect_error("cvo:\n  max_iterations: 0\n", 2, "cvo.max_iterations: must be >= 1, got '0'");
  expect_error("selection: {target_points: -3}\n", 1, "selection.target_points: must be >= 1, got '-3'");
  expect_error("keyframe: {inner_product_ratio_threshold: 1.5}\n", 1,
               "keyframe.inner_product_ratio_threshold: must be in [0, 1], got '1.5'");
  expect_error("keyframe: {rotation_threshold_deg: 0}\n", 1, "must be in (0, 180], got '0'");
  expect_error("cvo: {threads: 99999999999}\n", 1, "cvo.threads: must be in [1, 1024]");
  expect_error("camera: {fx: 1}\n", 1, "camera: expected a string, got a mapping");
  expect_error("camera: ''\n", 1, "camera: must not be empty");
  expect_error("trackerd: {deterministic: 1}\n", 1, "trackerd.deterministic: expected true or false, got '1'");
  expect_error("trackerd: {paced: ture}\n", 1, "trackerd.paced: expected true or false, got 'ture'");
  expect_error("trackerd: {realtime_priority: 100}\n", 1, "trackerd.realtime_priority: must be in [0, 99]");
  expect_error("trackerd: {ring_slots: 0}\n", 1, "trackerd.ring_slots: must be >= 1");
  expect_error("cvo: 3\n", 1, "cvo: expected a mapping of keys");
  expect_error("- cvo\n", 1, "expected a mapping of sections");
}

TEST(Config, DuplicatesInconsistenciesAndSyntaxErrors) {
  expect_error("cvo:\n  sigma: 1\n  sigma: 2\n", 3, "cvo.sigma: given twice (first on line 2)");
  expect_error("cvo: {}\ncvo: {}\n", 2, "cvo: given twice (first on line 1)");
  expect_error("selection: {min_depth_m: 6}\n", 0, "selection.min_depth_m (6) must be below selection.max_depth_m (5)");
  expect_error("cvo: {ell_min: 0.5}\n", 0, "cvo.ell_min (0.5) must not exceed cvo.ell_init (0.1)");
  expect_error("cvo:\n  ell_init: [0.1\n", 3, "YAML:");
}

TEST(Config, ARobotIsNamedAsAHostIsOrByItsHost) {
  EXPECT_EQ(Config{}.trackerd.robot, kHostName);
  EXPECT_EQ(parse_config("trackerd: {robot: hall-a_2.east}\n").trackerd.robot, "hall-a_2.east");
  expect_error("trackerd: {robot: \"hall a\"}\n", 0,
               "trackerd.robot (hall a) must be $HOSTNAME or 1 to 64 letters, digits, '.', '-' or '_'");
  expect_error("trackerd: {robot: " + std::string(65, 'r') + "}\n", 0, "trackerd.robot (");
  EXPECT_EQ(robot_name("hall-a"), "hall-a");
  EXPECT_TRUE(core::is_robot_name(robot_name(kHostName))) << robot_name(kHostName);  // the host's, or localhost
  EXPECT_NE(robot_name(kHostName), kHostName);
  EXPECT_FALSE(core::is_robot_name(""));
}

TEST(Config, LoadsFilesWithPathAndLineInErrors) {
  const test::TempDir dir("cvo_config");
  const auto good = dir.write("good.yaml", "pose_graph:\n  cauchy_delta: 1.5\n");
  EXPECT_DOUBLE_EQ(load_config(good).pose_graph.cauchy_delta, 1.5);
  const auto bad = dir.write("bad.yaml", "pose_graph:\n  cauchy_delta: -1\n");
  try {
    load_config(bad);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_TRUE(contains(e, bad.string() + ":2: pose_graph.cauchy_delta: must be > 0, got '-1'")) << e.what();
  }
  EXPECT_THROW(load_config(dir.path() / "absent.yaml"), ConfigError);
}

TEST(Config, OverridesUseTheSameChecks) {
  Config c;
  apply_override(c, "cvo.ell_init=0.15");
  apply_override(c, " keyframe.rotation_threshold_deg = 20 ");
  apply_override(c, "camera=/data/calibration.txt");
  apply_override(c, "selection.target_points=1500");
  EXPECT_DOUBLE_EQ(c.cvo.ell_init, 0.15);
  EXPECT_DOUBLE_EQ(c.keyframe.rotation_threshold_deg, 20.0);
  EXPECT_EQ(c.camera, "/data/calibration.txt");
  EXPECT_EQ(c.selection.target_points, 1500u);

  const Config before = c;
  const auto expect_rejected = [&](const std::string& assignment, const std::string& fragment) {
    try {
      apply_override(c, assignment);
      FAIL() << "accepted: " << assignment;
    } catch (const ConfigError& e) {
      EXPECT_TRUE(contains(e, fragment)) << e.what();
      EXPECT_TRUE(contains(e, "--set")) << e.what();
    }
    EXPECT_TRUE(c == before) << "changed by the rejected " << assignment;
  };
  expect_rejected("cvo.ell_init", "expected key=value");
  expect_rejected("cvo.ell_int=0.2", "cvo.ell_int: unknown key (did you mean cvo.ell_init?)");
  expect_rejected("cvo.ell_init=abc", "cvo.ell_init: expected a finite number, got 'abc'");
  expect_rejected("cvo.ell_init=nan", "cvo.ell_init: expected a finite number, got 'nan'");
  expect_rejected("cvo.ell_init=", "cvo.ell_init: expected a finite number, got ''");
  expect_rejected("cvo.ell_init=0.01", "cvo.ell_min (0.07) must not exceed cvo.ell_init (0.01)");
  expect_rejected("cvo=1", "cvo: a section");
}

TEST(Config, BooleansAreYamlCoreBooleans) {
  auto c = parse_config("trackerd:\n  deterministic: true\n  paced: False\n");
  EXPECT_TRUE(c.trackerd.deterministic);
  EXPECT_FALSE(c.trackerd.paced);
  apply_override(c, "trackerd.deterministic=false");
  EXPECT_FALSE(c.trackerd.deterministic);
  EXPECT_THROW(apply_override(c, "trackerd.deterministic=yes"), ConfigError);  // YAML 1.1 only
}

TEST(Config, DumpRoundTripsEveryKey) {
  Config c;
  c.selection.target_points = 1234;
  c.cvo.ell_init = 0.1234567890123;
  c.cvo.min_step = 1e-7;
  c.cvo.threads = 4;
  c.loop_closure.min_matches = 12;
  c.dataset.max_association_dt = 0.015;
  c.camera = "/data/my camera: v2.yaml";  // needs quoting in YAML
  c.trackerd.source = "lcm:udpm://239.255.76.67:7667?ttl=0";
  c.trackerd.deterministic = true;
  c.trackerd.lock_memory = false;
  c.trackerd.cpu = 1;
  c.keyframe_tracking.gamma_sigma = 0.123456789;
  c.loop_verification.ransac_seed = 4294967295u;
  c.loop_verification.orb_scale_factor = 1.25;
  c.odometry.max_points = 100000;
  c.pose_graph.bridge_information = 1e-3;
  c.mapping.base_T_camera = core::PoseParameter{0.1, -0.02, 0.45, -0.5, 0.5, -0.5, 0.5};
  const auto text = dump_config(c);
  EXPECT_TRUE(parse_config(text) == c) << text;
  for (const auto& key : config_keys()) {
    const auto member = key.substr(key.find('.') + 1);
    EXPECT_NE(text.find(member + ": "), std::string::npos) << key << " missing from\n" << text;
  }
  EXPECT_EQ(config_keys().size(), 100u) << "a new parameter? add a row to the table and regenerate default.yaml";
}

// The values the code was tuned with are keys too (issue 15): the trackers' capacities, KF-CVO's
// γ kernel and chain fusion, loop verification (RANSAC, ORB, refinements), the back end's bridge
// and iterations. Their defaults are the tuned values; module_parameters_test checks they reach
// the modules.
TEST(Config, TunedValuesAreKeysWithTheirDefaults) {
  const std::vector<std::string> tuned{"odometry.max_points",
                                       "odometry.restart_after_failures",
                                       "keyframe.local_graph_capacity",
                                       "keyframe.gamma_ell",
                                       "keyframe.gamma_sigma",
                                       "keyframe.gamma_stride",
                                       "keyframe.chain_weight",
                                       "keyframe.chain_full_weight_deg",
                                       "keyframe.max_turn_rate_deg_s",
                                       "loop_closure.max_refinements",
                                       "loop_closure.ransac_iterations",
                                       "loop_closure.ransac_inlier_m",
                                       "loop_closure.min_inliers",
                                       "loop_closure.min_inlier_retention",
                                       "loop_closure.ransac_seed",
                                       "loop_closure.orb_features",
                                       "loop_closure.orb_scale_factor",
                                       "loop_closure.orb_levels",
                                       "loop_closure.orb_edge_threshold",
                                       "loop_closure.orb_fast_threshold",
                                       "pose_graph.bridge_information",
                                       "pose_graph.max_iterations"};
  const auto keys = config_keys();
  for (const auto& key : tuned) EXPECT_NE(std::find(keys.begin(), keys.end(), key), keys.end()) << key;

  const Config c;
  EXPECT_EQ(c.odometry.max_points, 8192u);
  EXPECT_EQ(c.odometry.restart_after_failures, 3);
  EXPECT_EQ(c.keyframe_tracking.local_graph_capacity, 300u);
  EXPECT_EQ(c.keyframe_tracking.gamma_ell, 0.1);
  EXPECT_EQ(c.keyframe_tracking.gamma_sigma, 0.316);
  EXPECT_EQ(c.keyframe_tracking.gamma_stride, 4u);
  EXPECT_EQ(c.keyframe_tracking.chain_weight, 1.0);
  EXPECT_EQ(c.keyframe_tracking.chain_full_weight_deg, 3.0);
  EXPECT_EQ(c.keyframe_tracking.max_turn_rate_deg_s, 240.0);
  EXPECT_EQ(c.loop_verification.max_refinements, 3);
  EXPECT_EQ(c.loop_verification.ransac_iterations, 300);
  EXPECT_EQ(c.loop_verification.ransac_inlier_m, 0.03);
  EXPECT_EQ(c.loop_verification.min_inliers, 12);
  EXPECT_EQ(c.loop_verification.min_inlier_retention, 0.5);
  EXPECT_EQ(c.loop_verification.ransac_seed, 0u);
  EXPECT_EQ(c.loop_verification.orb_features, 1000);
  EXPECT_EQ(c.loop_verification.orb_scale_factor, 1.2);
  EXPECT_EQ(c.loop_verification.orb_levels, 8);
  EXPECT_EQ(c.loop_verification.orb_edge_threshold, 31);
  EXPECT_EQ(c.loop_verification.orb_fast_threshold, 20);
  EXPECT_EQ(c.pose_graph.bridge_information, 1.0);
  EXPECT_EQ(c.pose_graph.max_iterations, 100);

  // A file and --set set the same member; the paper's keys of a shared section keep working.
  const auto loaded = parse_config(
      "keyframe:\n  rotation_threshold_deg: 20\n  chain_weight: 0\n  local_graph_capacity: 2\n"
      "loop_closure: {match_ratio: 0.8, ransac_seed: 7, orb_scale_factor: 1.5}\n"
      "odometry: {max_points: 4096}\npose_graph: {bridge_information: 0.5}\n");
  Config expected;
  expected.keyframe.rotation_threshold_deg = 20;
  expected.keyframe_tracking.chain_weight = 0;
  expected.keyframe_tracking.local_graph_capacity = 2;
  expected.loop_closure.match_ratio = 0.8;
  expected.loop_verification.ransac_seed = 7;
  expected.loop_verification.orb_scale_factor = 1.5;
  expected.odometry.max_points = 4096;
  expected.pose_graph.bridge_information = 0.5;
  EXPECT_TRUE(loaded == expected) << dump_config(loaded);
  Config overridden;
  for (const char* a :
       {"keyframe.rotation_threshold_deg=20", "keyframe.chain_weight=0", "keyframe.local_graph_capacity=2",
        "loop_closure.match_ratio=0.8", "loop_closure.ransac_seed=7", "loop_closure.orb_scale_factor=1.5",
        "odometry.max_points=4096", "pose_graph.bridge_information=0.5"})
    apply_override(overridden, a);
  EXPECT_TRUE(overridden == expected) << dump_config(overridden);

  // Their ranges: what the modules cannot use is refused, naming the key.
  for (const char* bad : {"odometry.max_points=0",
                          "odometry.restart_after_failures=0",
                          "keyframe.local_graph_capacity=1",
                          "keyframe.gamma_ell=0",
                          "keyframe.gamma_sigma=-1",
                          "keyframe.chain_weight=-0.5",
                          "keyframe.chain_full_weight_deg=181",
                          "loop_closure.max_refinements=-1",
                          "loop_closure.ransac_iterations=0",
                          "loop_closure.ransac_inlier_m=0",
                          "loop_closure.min_inliers=2",
                          "loop_closure.min_inlier_retention=1.5",
                          "loop_closure.ransac_seed=4294967296",
                          "loop_closure.ransac_seed=-1",
                          "loop_closure.orb_features=0",
                          "loop_closure.orb_scale_factor=1",
                          "loop_closure.orb_levels=0",
                          "loop_closure.orb_edge_threshold=-1",
                          "loop_closure.orb_fast_threshold=0",
                          "pose_graph.bridge_information=0",
                          "pose_graph.max_iterations=0"}) {
    Config untouched;
    try {
      apply_override(untouched, bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const ConfigError& e) {
      const std::string key(bad, std::string_view(bad).find('='));
      EXPECT_TRUE(contains(e, key)) << e.what();
    }
    EXPECT_TRUE(untouched == Config{}) << bad;
  }
}

// The map's keys (issue 24): a ground robot's defaults, and the camera's mount as a pose.
TEST(Config, MappingKeysHaveAGroundRobotsDefaultsAndTheMountIsAPose) {
  const Config defaults;
  EXPECT_EQ(defaults.mapping.cell_size, 0.05);
  EXPECT_EQ(defaults.mapping.obstacle_min_height, 0.1);
  EXPECT_EQ(defaults.mapping.obstacle_max_height, 1.8);
  EXPECT_FALSE(defaults.mapping.base_T_camera);

  const auto c = parse_config("mapping:\n  base_T_camera: [0.1, 0, 0.45, -0.5, 0.5, -0.5, 0.5]\n");
  ASSERT_TRUE(c.mapping.base_T_camera);
  EXPECT_EQ((*c.mapping.base_T_camera)[2], 0.45);
  EXPECT_EQ((*c.mapping.base_T_camera)[6], 0.5);
  Config o;
  apply_override(o, "mapping.base_T_camera=0.1 0 0.45 -0.5 0.5 -0.5 0.5");
  EXPECT_TRUE(o == c);
  apply_override(o, "mapping.base_T_camera=none");
  EXPECT_FALSE(o.mapping.base_T_camera);

  const auto error_of = [](const std::string& yaml) {
    try {
      parse_config(yaml);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of("mapping: {base_T_camera: [0, 0, 1, 0, 0, 0]}").find("expected none or [x, y, z"),
            std::string::npos);
  EXPECT_NE(error_of("mapping: {base_T_camera: [0, 0, 1, 0, 0, 0, 2]}").find("unit length"), std::string::npos);
  EXPECT_NE(error_of("mapping: {base_T_camera: [0, 0, nan, 0, 0, 0, 1]}").find("mapping.base_T_camera"),
            std::string::npos);
  EXPECT_NE(error_of("mapping: {obstacle_min_height: 2.0}").find("must be below mapping.obstacle_max_height"),
            std::string::npos);
  EXPECT_NE(error_of("mapping: {cell_size: 0.0001}").find("at most 4000 mapping.cell_size"), std::string::npos);
  EXPECT_NE(error_of("mapping: {hit_probability: 0.4}").find("mapping.hit_probability"), std::string::npos);
}

TEST(Config, DefaultYamlIsInSync) {
  const std::filesystem::path file = CVO_DEFAULT_CONFIG;
  EXPECT_TRUE(load_config(file) == Config{});
  std::ifstream in(file);
  std::stringstream committed;
  committed << in.rdbuf();
  const auto expected = dump_config(Config{});
  if (committed.str() != expected) {
    const auto fresh = std::filesystem::temp_directory_path() / "cvo_default.yaml";
    std::ofstream(fresh) << expected;
    FAIL() << file << " differs from dump_config(Config{}); review and copy: cp " << fresh << " " << file;
  }
}

}  // namespace
}  // namespace cvo::config
