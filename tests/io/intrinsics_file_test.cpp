#include "libcvo/io/intrinsics_file.hpp"

#include <array>
#include <string>

#include <gtest/gtest.h>

#include "libcvo/io/input_error.hpp"
#include "libcvo/io/numbers.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::io {
namespace {

constexpr const char* kValid =
    "# a Kinect\nfx: 525.5\nfy: 524\ncx: 319.5\ncy: 239.5\nwidth: 640\nheight: 480\n"
    "depth_scale: 1000\n";

TEST(IntrinsicsFile, ReadsYaml) {
  const auto k = parse_intrinsics(kValid, "cam.yaml");
  EXPECT_DOUBLE_EQ(k.fx, 525.5);
  EXPECT_DOUBLE_EQ(k.fy, 524.0);
  EXPECT_DOUBLE_EQ(k.cx, 319.5);
  EXPECT_DOUBLE_EQ(k.cy, 239.5);
  EXPECT_EQ(k.width, 640);
  EXPECT_EQ(k.height, 480);
  EXPECT_DOUBLE_EQ(k.depth_scale, 1000.0);
}

constexpr const char* kSeparateDepth =
    "fx: 615\nfy: 615\ncx: 319.5\ncy: 239.5\nwidth: 640\nheight: 480\ndepth_scale: 1000\n"
    "depth_sensor:\n  fx: 425\n  fy: 425\n  cx: 423.5\n  cy: 239.5\n  width: 848\n  height: 480\n"
    "  depth_scale: 1000\n  k1: 0.01\n  T_colour_depth: [-0.015, 0.001, 0, 0, 0, 0.7071068, 0.7071068]\n";

TEST(IntrinsicsFile, ASeparateDepthSensorHasItsOwnIntrinsicsAndItsPoseInTheColourCamera) {
  const CameraFile camera = parse_camera(kSeparateDepth, "d435.yaml");
  EXPECT_EQ(camera.colour.width, 640);
  ASSERT_TRUE(camera.depth_sensor);
  const auto& depth = *camera.depth_sensor;
  EXPECT_EQ(depth.intrinsics.width, 848);
  EXPECT_DOUBLE_EQ(depth.intrinsics.fx, 425.0);
  EXPECT_DOUBLE_EQ(depth.intrinsics.distortion[0], 0.01);
  EXPECT_NEAR(depth.T_colour_depth.translation().x(), -0.015, 1e-12);
  EXPECT_NEAR((depth.T_colour_depth * Eigen::Vector3d::UnitX()).y(), 1.001, 1e-6);  // 90 deg about z, then t
  // Whoever reads only the colour camera reads the same file.
  EXPECT_DOUBLE_EQ(parse_intrinsics(kSeparateDepth, "d435.yaml").fx, 615.0);
  EXPECT_FALSE(parse_camera(kValid, "cam.yaml").depth_sensor);
}

TEST(IntrinsicsFile, ABadDepthSensorSectionNamesWhatIsWrong) {
  const std::string colour = "fx: 615\nfy: 615\ncx: 319.5\ncy: 239.5\nwidth: 640\nheight: 480\n";
  const std::string sensor =
      "depth_sensor:\n  fx: 425\n  fy: 425\n  cx: 423.5\n  cy: 239.5\n  width: 848\n  height: 480\n";
  const auto error_of = [](const std::string& text) {
    try {
      parse_camera(text, "d435.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of(colour + sensor).find("missing key 'T_colour_depth'"), std::string::npos);
  EXPECT_NE(error_of(colour + sensor + "  T_colour_depth: [0, 0, 0]\n").find("[tx, ty, tz, qx, qy, qz, qw]"),
            std::string::npos);
  EXPECT_NE(error_of(colour + sensor + "  T_colour_depth: [0, 0, 0, 0, 0, 0, 0]\n").find("unit quaternion"),
            std::string::npos);
  EXPECT_NE(error_of(colour + sensor + "  T_colour_depth: [0, 0, 0, 0, 0, 0, 1]\n  baseline: 5\n").find("baseline"),
            std::string::npos);
  EXPECT_NE(error_of(colour + "depth_sensor: 5\n").find("expected a mapping"), std::string::npos);
  EXPECT_NE(
      error_of(colour + "depth_sensor:\n  fx: 425\n  T_colour_depth: [0, 0, 0, 0, 0, 0, 1]\n").find("missing key"),
      std::string::npos);
  EXPECT_EQ(error_of(colour + sensor + "  T_colour_depth: [0, 0, 0, 0, 0, 0, 1]\n"), "no error");
}

TEST(IntrinsicsFile, DepthScaleDefaultsToTums) {
  const auto k = parse_intrinsics("{fx: 500, fy: 500, cx: 320, cy: 240, width: 640, height: 480}", "cam.yaml");
  EXPECT_DOUBLE_EQ(k.depth_scale, 5000.0);
  EXPECT_FALSE(k.has_distortion());  // absent coefficients are zero
}

void expect_error(const std::string& text, std::size_t line, const std::string& fragment) {
  try {
    parse_intrinsics(text, "cam.yaml");
    FAIL() << "no error for:\n" << text;
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("cam.yaml", 0), 0u) << e.what();
  }
}

TEST(IntrinsicsFile, YamlErrorsNameTheKey) {
  expect_error("fx: 1\nfz: 2\n", 2, "unknown key 'fz'");
  expect_error("fx: 1\nfy: abc\n", 2, "fy: not a finite number: 'abc'");
  expect_error("fx: .nan\n", 1, "fx: not a finite number");
  expect_error("fx: [1, 2]\n", 1, "fx: expected a number");
  expect_error("fx: 1\nfx: 2\n", 2, "duplicate key 'fx'");
  expect_error("fx: 1\nwidth: 640.5\n", 2, "width: expected an integer");
  expect_error("fx: 1\nfy: 1\ncx: 1\ncy: 1\nwidth: 640\n", 0, "missing key 'height'");
  expect_error("fx: 1\nfy: -1\ncx: 1\ncy: 1\nwidth: 640\nheight: 480\n", 2, "fy must be a positive number");
  expect_error("fx: [1\n", 2, "YAML:");
}

TEST(IntrinsicsFile, ReadsDistortionInOpenCvOrderAbsentOnesZero) {
  const auto k = parse_intrinsics(
      std::string(kValid) + "k1: 0.2624\nk2: -0.9531\np1: -0.0054\np2: 0.0026\nk3: 1.1633\n", "cam.yaml");
  EXPECT_EQ(k.distortion, (std::array{0.2624, -0.9531, -0.0054, 0.0026, 1.1633}));
  const auto radial = parse_intrinsics(std::string(kValid) + "k1: 0.1\nk3: -0.5\n", "cam.yaml");
  EXPECT_EQ(radial.distortion, (std::array{0.1, 0.0, 0.0, 0.0, -0.5}));
  expect_error(std::string(kValid) + "p2: inf\n", 9, "p2: not a finite number");
  expect_error(std::string(kValid) + "k1: 1\nk1: 2\n", 10, "duplicate key 'k1'");
  expect_error(std::string(kValid) + "k4: 1\n", 9, "unknown key 'k4'");
}

TEST(IntrinsicsFile, FormattedYamlReadsBackExactly) {
  for (const char* preset : {"tum_fr1", "tum_fr2", "tum_fr3", "synthetic"}) {
    SCOPED_TRACE(preset);
    auto k = load_camera(preset);
    k.depth_scale = 1000.0 / 3.0;  // no short decimal: the text must still be exact
    const std::string text = format_intrinsics_yaml(k, "a test camera");
    EXPECT_EQ(text.rfind("# a test camera\n", 0), 0u) << text;
    // Distortion keys only when there is distortion: old readers keep reading pinhole files.
    EXPECT_EQ(text.find("k1:") != std::string::npos, k.has_distortion()) << text;
    const auto back = parse_intrinsics(text, "cam.yaml");
    EXPECT_EQ(back.fx, k.fx);
    EXPECT_EQ(back.fy, k.fy);
    EXPECT_EQ(back.cx, k.cx);
    EXPECT_EQ(back.cy, k.cy);
    EXPECT_EQ(back.width, k.width);
    EXPECT_EQ(back.height, k.height);
    EXPECT_EQ(back.depth_scale, k.depth_scale);
    EXPECT_EQ(back.distortion, k.distortion);
    EXPECT_EQ(text.find("readout_s:") != std::string::npos, k.rolling_shutter()) << text;
    EXPECT_EQ(back.readout_s, k.readout_s);
  }
}

TEST(IntrinsicsFile, ARollingShutterDeclaresItsReadoutAGlobalOneNothing) {
  EXPECT_EQ(parse_intrinsics(kValid, "cam.yaml").readout_s, 0.0);
  const auto k = parse_intrinsics(std::string(kValid) + "readout_s: 0.025\n", "cam.yaml");
  EXPECT_DOUBLE_EQ(k.readout_s, 0.025);
  EXPECT_TRUE(k.rolling_shutter());
  expect_error(std::string(kValid) + "readout_s: -0.01\n", 9, "readout_s must be a number of seconds in [0, 1)");
  expect_error(std::string(kValid) + "readout_s: 2\n", 9, "readout_s must be a number of seconds in [0, 1)");
  // The TUM Kinects have rolling shutters; the renderer's camera has a global one.
  EXPECT_TRUE(load_camera("tum_fr1").rolling_shutter());
  EXPECT_FALSE(load_camera("synthetic").rolling_shutter());
}

TEST(IntrinsicsFile, ReadsEth3dOneLiner) {
  const auto k = parse_intrinsics("726.28 726.28 354.65 186.46\n", "calibration.txt");
  EXPECT_DOUBLE_EQ(k.fx, 726.28);
  EXPECT_DOUBLE_EQ(k.cy, 186.46);
  EXPECT_EQ(k.width, 0);  // from the images
  EXPECT_EQ(k.height, 0);
  EXPECT_DOUBLE_EQ(k.depth_scale, 5000.0);
  EXPECT_EQ(validate_allowing_unknown_size(k), "");
  EXPECT_NE(k.validate(), "");
}

TEST(IntrinsicsFile, Eth3dErrorsNameTheLine) {
  expect_error("# comment\n726 726 354\n", 2, "expected 4 fields");
  expect_error("726 726 354 x\n", 1, "not a number: 'x'");
  expect_error("726 726 354 186\n1 2 3 4\n", 2, "one line");
  expect_error("726 0 354 186\n", 1, "fy must be a positive number");
  expect_error("", 0, "empty");
}

TEST(IntrinsicsFile, ReadsFilesAndPresets) {
  const test::TempDir dir;
  const auto file = dir.write("camera.yaml", kValid);
  EXPECT_DOUBLE_EQ(read_intrinsics_file(file).fx, 525.5);
  EXPECT_DOUBLE_EQ(load_camera(file.string()).fx, 525.5);
  EXPECT_DOUBLE_EQ(load_camera("tum_fr2").fx, 520.9);
  EXPECT_THROW(read_intrinsics_file(dir.path() / "absent.yaml"), InputError);
  try {
    load_camera("tum_fr9");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tum_fr1, tum_fr2"), std::string::npos) << e.what();
  }
}

TEST(IntrinsicsFile, StrictNumbers) {
  EXPECT_EQ(to_finite("8.315e-3"), 8.315e-3);
  EXPECT_EQ(to_finite("+2"), 2.0);
  EXPECT_EQ(to_finite("-0.5"), -0.5);
  for (const char* bad : {"", "nan", "inf", "-inf", "1.0x", " 1", "0x10", "+-1", "1e999"})
    EXPECT_FALSE(to_finite(bad)) << bad;
  EXPECT_EQ(to_integer("42"), 42);
  EXPECT_EQ(to_integer("-3"), -3);
  for (const char* bad : {"", "5.0", "1e3", "99999999999999999999", "7 "}) EXPECT_FALSE(to_integer(bad)) << bad;
}

}  // namespace
}  // namespace cvo::io
