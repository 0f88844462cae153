// The one mapping from the configuration to every module's parameters (module_parameters.hpp):
// every module's parameter struct holds the core structs whole and nothing tunable besides (a
// tunable lives in its core struct field and its config table row only, libcvo/core/parameters.hpp),
// the mapping hands each section over whole, and every key reaches its module, through --set as
// through a file, in cvo-run end to end.
#include "libcvo/config/module_parameters.hpp"
#include "libcvo/config/mapper_parameters.hpp"

#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::config {
namespace {

// The members of an aggregate, as a type list: the count by aggregate initialisation from
// "anything" (one initialiser per member: the member types all convert from it, so no brace
// elision), the types by a structured binding of that many names.
template <class... T>
struct Types {};

struct AnyMember {
  template <class T>
  operator T() const;  // never defined: used in unevaluated operands only
};

template <class S, class... A>
consteval std::size_t member_count() {
  if constexpr (requires { S{A{}..., AnyMember{}}; })
    return member_count<S, A..., AnyMember>();
  else
    return sizeof...(A);
}

template <class S>
auto member_types(const S& s) {
  constexpr std::size_t n = member_count<S>();
  static_assert(n >= 1 && n <= 8, "member_types: add a case");
#define CVO_T(x) std::remove_cvref_t<decltype(x)>
  if constexpr (n == 1) {
    const auto& [a] = s;
    return Types<CVO_T(a)>{};
  } else if constexpr (n == 2) {
    const auto& [a, b] = s;
    return Types<CVO_T(a), CVO_T(b)>{};
  } else if constexpr (n == 3) {
    const auto& [a, b, c] = s;
    return Types<CVO_T(a), CVO_T(b), CVO_T(c)>{};
  } else if constexpr (n == 4) {
    const auto& [a, b, c, d] = s;
    return Types<CVO_T(a), CVO_T(b), CVO_T(c), CVO_T(d)>{};
  } else if constexpr (n == 5) {
    const auto& [a, b, c, d, e] = s;
    return Types<CVO_T(a), CVO_T(b), CVO_T(c), CVO_T(d), CVO_T(e)>{};
  } else if constexpr (n == 6) {
    const auto& [a, b, c, d, e, f] = s;
    return Types<CVO_T(a), CVO_T(b), CVO_T(c), CVO_T(d), CVO_T(e), CVO_T(f)>{};
  } else if constexpr (n == 7) {
    const auto& [a, b, c, d, e, f, g] = s;
    return Types<CVO_T(a), CVO_T(b), CVO_T(c), CVO_T(d), CVO_T(e), CVO_T(f), CVO_T(g)>{};
  } else {
    const auto& [a, b, c, d, e, f, g, h] = s;
    return Types<CVO_T(a), CVO_T(b), CVO_T(c), CVO_T(d), CVO_T(e), CVO_T(f), CVO_T(g), CVO_T(h)>{};
  }
#undef CVO_T
}

template <class S, class... Expected>
constexpr bool holds_exactly = std::is_same_v<decltype(member_types(std::declval<const S&>())), Types<Expected...>>;

// Each module's parameter struct is the core structs whole, plus what no configuration key sets
// (a start pose, a variant, solver internals). A field that re-declared a tunable (gamma_ell
// beside KeyframeTrackingParameters, say) changes the member list: this file stops compiling.
static_assert(holds_exactly<odometry::FrameToFrameParameters, core::SelectionParameters, core::CvoParameters,
                            core::OdometryParameters, core::SE3>);
static_assert(
    holds_exactly<odometry::KeyframeOdometryParameters, core::SelectionParameters, core::CvoParameters,
                  core::KeyframeParameters, core::KeyframeTrackingParameters, core::OdometryParameters, core::SE3>);
static_assert(holds_exactly<odometry::OpenCvOdometryParameters, odometry::OpenCvVariant, core::SelectionParameters,
                            core::OdometryParameters, core::SE3>);
static_assert(holds_exactly<loop_closure::LoopDetectorParameters, core::LoopClosureParameters,
                            core::LoopVerificationParameters, core::CvoParameters, core::SelectionParameters,
                            core::OdometryParameters, core::KeyframeParameters, core::KeyframeTrackingParameters>);
static_assert(std::is_same_v<slam::BackendParameters, core::PoseGraphParameters>);
static_assert(holds_exactly<slam::MapperParameters, loop_closure::LoopDetectorParameters, slam::BackendParameters,
                            core::LocalizationParameters>);
static_assert(
    holds_exactly<posegraph::OptimizerOptions, core::PoseGraphParameters, double, double, double, bool, double>);

// A member declaration of one of `names`: a plain type, the name, maybe a default, a semicolon
// (so not a function's argument). The name is group 4.
std::regex member_declaration(const std::vector<std::string>& names) {
  std::string alternatives;
  for (const auto& name : names) alternatives += (alternatives.empty() ? "" : "|") + name;
  return std::regex(
      R"((^|\n)[ \t]*(const[ \t]+)?(double|float|int|bool|unsigned|std::size_t|std::uint32_t|std::string)[ \t]+()" +
      alternatives + R"()[ \t]*(=[^;\n]*[^;)\n]|\{[^;\n]*\})?[ \t]*;)");
}

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The guard beyond the structs above, for any module, new ones included: no header outside
// libcvo/core/parameters.hpp and libcvo/config/config.hpp (the daemons' own sections) declares
// a member named as a key of the table, whether its default is copied from the core struct or
// written again.
TEST(ConfigModuleParameters, NoModuleRedeclaresATunable) {
  const std::filesystem::path root = CVO_SOURCE_DIR;
  // Same name, another quantity.
  const std::set<std::pair<std::string, std::string>> other_quantities{
      {"libcvo/loop_closure/vocabulary.hpp", "max_iterations"},  // k-medians iterations of training
      {"libcvo/registration/registration.hpp", "max_points"},    // Capacities: no default, every caller's max_points
      {"libcvo/registration/point_selection.hpp", "cell_size"},  // selection cells in pixels, not map cells
      {"drivers/usb_cameras.hpp", "source"},                     // where a camera's USB ids are published
      {"drivers/usb_cameras.hpp", "mode"},                       // a device node's permission bits
      {"tools/cvo-run/report.hpp", "mode"},                      // the odometry mode run, not the back end's
      {"libcvo/lcm/tracker_messages.hpp", "robot"},              // the resolved name a status carries
      {"libcvo/slam/mapper.hpp", "robot"},                       // the name a session's keyframes carry
      {"libcvo/slam/map_robots.hpp", "robot"},                   // a robot of the map, by that name
  };
  std::set<std::string> names;
  for (const auto& key : config_keys()) names.insert(key.substr(key.find('.') + 1));
  const std::regex member = member_declaration({names.begin(), names.end()});
  const std::set<std::filesystem::path> owners{root / "libcvo/core/parameters.hpp", root / "libcvo/config/config.hpp"};
  std::size_t headers = 0;
  for (const char* folder : {"libcvo", "daemon", "drivers", "tools"}) {
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root / folder)) {
      if (entry.path().extension() != ".hpp" || owners.contains(entry.path())) continue;
      ++headers;
      const std::string text = read_text(entry.path());
      const auto relative = entry.path().lexically_relative(root).generic_string();
      for (auto m = std::sregex_iterator(text.begin(), text.end(), member); m != std::sregex_iterator(); ++m) {
        const std::string name = (*m)[4];
        EXPECT_TRUE(other_quantities.contains({relative, name}))
            << relative << " declares `" << name << "`, a key of the configuration table: hold its core struct "
            << "whole instead (libcvo/core/parameters.hpp)";
      }
    }
  }
  EXPECT_GT(headers, 100u) << "the scan found too few headers under " << root;
}

// The scan above matches what it must: the declarations this rule replaced, and nothing else.
TEST(ConfigModuleParameters, TheScanRecognisesARedeclaredTunable) {
  const std::regex member = member_declaration({"gamma_ell", "max_points"});
  EXPECT_TRUE(
      std::regex_search("struct P {\n  double gamma_ell = core::KeyframeTrackingParameters{}.gamma_ell;\n", member));
  EXPECT_TRUE(std::regex_search("  std::size_t max_points = 8192;  // capacity\n", member));
  EXPECT_TRUE(std::regex_search("  double gamma_ell;\n", member));
  EXPECT_TRUE(std::regex_search("  double gamma_ell{0.1};\n", member));
  EXPECT_FALSE(std::regex_search("  f(int a,\n    double gamma_ell = 0.1);\n", member));  // an argument
  EXPECT_FALSE(std::regex_search("  double gamma_ellipse = 1;\n", member));
  EXPECT_FALSE(std::regex_search("  return parameters.gamma_ell;\n", member));
}

TEST(ConfigModuleParameters, EveryModuleGetsTheConfigurationsStructsWhole) {
  Config c;
  for (const char* assignment :
       {"selection.target_points=1500", "cvo.ell_init=0.15", "odometry.max_points=4096",
        "keyframe.rotation_threshold_deg=20", "keyframe.gamma_ell=0.2", "loop_closure.similarity_threshold=0.4",
        "loop_closure.orb_levels=4", "pose_graph.cauchy_delta=1.5", "dataset.max_association_dt=0.01"})
    apply_override(c, assignment);

  const auto f2f = frame_to_frame_parameters(c);
  EXPECT_EQ(f2f.selection, c.selection);
  EXPECT_EQ(f2f.cvo, c.cvo);
  EXPECT_EQ(f2f.odometry, c.odometry);

  const auto kf = keyframe_odometry_parameters(c);
  EXPECT_EQ(kf.selection, c.selection);
  EXPECT_EQ(kf.cvo, c.cvo);
  EXPECT_EQ(kf.keyframe, c.keyframe);
  EXPECT_EQ(kf.tracking, c.keyframe_tracking);
  EXPECT_EQ(kf.odometry, c.odometry);

  for (const auto variant : {odometry::OpenCvVariant::rgbd, odometry::OpenCvVariant::rgbd_icp}) {
    const auto cv = opencv_odometry_parameters(c, variant);
    EXPECT_EQ(cv.variant, variant);
    EXPECT_EQ(cv.selection, c.selection);
    EXPECT_EQ(cv.odometry, c.odometry);
  }

  const auto mapper = mapper_parameters(c);
  EXPECT_EQ(mapper.detector.loop, c.loop_closure);
  EXPECT_EQ(mapper.detector.verification, c.loop_verification);
  EXPECT_EQ(mapper.detector.cvo, c.cvo);
  EXPECT_EQ(mapper.detector.selection, c.selection);
  EXPECT_EQ(mapper.detector.odometry, c.odometry);
  EXPECT_EQ(mapper.backend, c.pose_graph);

  EXPECT_EQ(tum_options(c).dataset, c.dataset);
}

// The modules' defaults are the configuration's: a module built without a configuration behaves
// as one built from the defaults.
TEST(ConfigModuleParameters, DefaultsAreTheModulesOwn) {
  const Config c;
  const odometry::KeyframeOdometryParameters kf_default;
  EXPECT_EQ(keyframe_odometry_parameters(c).tracking, kf_default.tracking);
  EXPECT_EQ(keyframe_odometry_parameters(c).odometry, kf_default.odometry);
  const loop_closure::LoopDetectorParameters loop_default;
  EXPECT_EQ(loop_detector_parameters(c).verification, loop_default.verification);
  EXPECT_EQ(backend_parameters(c), slam::BackendParameters{});
  EXPECT_EQ(posegraph::OptimizerOptions{}.pose_graph, c.pose_graph);
  EXPECT_EQ(tum_options(c).dataset, io::TumOptions{}.dataset);
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
         return opencv_odometry_parameters(c, odometry::OpenCvVariant::rgbd).selection.max_depth_m == 3.5 &&
                loop_detector_parameters(c).selection.max_depth_m == 3.5 &&
                keyframe_odometry_parameters(c).selection.max_depth_m == 3.5;
       }},
      {"selection.min_depth_m=0.3",
       [](const Config& c) {
         return opencv_odometry_parameters(c, odometry::OpenCvVariant::rgbd).selection.min_depth_m == 0.3;
       }},
      {"cvo.ell_init=0.15",
       [](const Config& c) {
         return frame_to_frame_parameters(c).cvo.ell_init == 0.15 &&
                keyframe_odometry_parameters(c).cvo.ell_init == 0.15 &&
                mapper_parameters(c).detector.cvo.ell_init == 0.15;
       }},
      {"odometry.max_points=4096",
       [](const Config& c) {
         return frame_to_frame_parameters(c).odometry.max_points == 4096 &&
                keyframe_odometry_parameters(c).odometry.max_points == 4096 &&
                loop_detector_parameters(c).odometry.max_points == 4096;
       }},
      {"odometry.restart_after_failures=5",
       [](const Config& c) {
         return frame_to_frame_parameters(c).odometry.restart_after_failures == 5 &&
                opencv_odometry_parameters(c, odometry::OpenCvVariant::rgbd_icp).odometry.restart_after_failures == 5;
       }},
      {"keyframe.rotation_threshold_deg=20",
       [](const Config& c) { return keyframe_odometry_parameters(c).keyframe.rotation_threshold_deg == 20; }},
      {"keyframe.local_graph_capacity=2",
       [](const Config& c) { return keyframe_odometry_parameters(c).tracking.local_graph_capacity == 2; }},
      {"keyframe.gamma_ell=0.2",
       [](const Config& c) { return keyframe_odometry_parameters(c).tracking.gamma_ell == 0.2; }},
      {"keyframe.gamma_sigma=0.1",
       [](const Config& c) { return keyframe_odometry_parameters(c).tracking.gamma_sigma == 0.1; }},
      {"keyframe.gamma_stride=1",
       [](const Config& c) { return keyframe_odometry_parameters(c).tracking.gamma_stride == 1; }},
      {"keyframe.chain_weight=0",
       [](const Config& c) { return keyframe_odometry_parameters(c).tracking.chain_weight == 0; }},
      {"keyframe.chain_full_weight_deg=10",
       [](const Config& c) { return keyframe_odometry_parameters(c).tracking.chain_full_weight_deg == 10; }},
      {"keyframe.max_turn_rate_deg_s=90",
       [](const Config& c) { return keyframe_odometry_parameters(c).tracking.max_turn_rate_deg_s == 90; }},
      {"loop_closure.similarity_threshold=0.4",
       [](const Config& c) { return mapper_parameters(c).detector.loop.similarity_threshold == 0.4; }},
      {"loop_closure.max_refinements=0",
       [](const Config& c) { return mapper_parameters(c).detector.verification.max_refinements == 0; }},
      {"loop_closure.ransac_iterations=50",
       [](const Config& c) { return mapper_parameters(c).detector.verification.ransac_iterations == 50; }},
      {"loop_closure.ransac_inlier_m=0.05",
       [](const Config& c) { return mapper_parameters(c).detector.verification.ransac_inlier_m == 0.05; }},
      {"loop_closure.min_inliers=20",
       [](const Config& c) { return mapper_parameters(c).detector.verification.min_inliers == 20; }},
      {"loop_closure.min_inlier_retention=0.8",
       [](const Config& c) { return mapper_parameters(c).detector.verification.min_inlier_retention == 0.8; }},
      {"loop_closure.ransac_seed=4294967295",
       [](const Config& c) { return mapper_parameters(c).detector.verification.ransac_seed == 4294967295u; }},
      {"loop_closure.orb_features=500",
       [](const Config& c) { return mapper_parameters(c).detector.verification.orb_features == 500; }},
      {"loop_closure.orb_scale_factor=1.5",
       [](const Config& c) { return mapper_parameters(c).detector.verification.orb_scale_factor == 1.5; }},
      {"loop_closure.orb_levels=4",
       [](const Config& c) { return mapper_parameters(c).detector.verification.orb_levels == 4; }},
      {"loop_closure.orb_edge_threshold=40",
       [](const Config& c) { return mapper_parameters(c).detector.verification.orb_edge_threshold == 40; }},
      {"loop_closure.orb_fast_threshold=10",
       [](const Config& c) { return mapper_parameters(c).detector.verification.orb_fast_threshold == 10; }},
      {"pose_graph.cauchy_delta=1.5", [](const Config& c) { return mapper_parameters(c).backend.cauchy_delta == 1.5; }},
      {"pose_graph.bridge_information=0.25",
       [](const Config& c) { return mapper_parameters(c).backend.bridge_information == 0.25; }},
      {"pose_graph.max_iterations=20",
       [](const Config& c) { return mapper_parameters(c).backend.max_iterations == 20; }},
      {"dataset.max_association_dt=0.01",
       [](const Config& c) { return tum_options(c).dataset.max_association_dt == 0.01; }},
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
