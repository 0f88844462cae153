#include "libcvo/core/camera.hpp"

#include <array>
#include <limits>

#include <gtest/gtest.h>

namespace cvo::core {
namespace {

TEST(Camera, TumPresetsHaveBenchmarkValues) {
  const auto fr1 = camera_preset("tum_fr1");
  ASSERT_TRUE(fr1);
  EXPECT_DOUBLE_EQ(fr1->fx, 517.3);
  EXPECT_DOUBLE_EQ(fr1->cy, 255.3);
  EXPECT_DOUBLE_EQ(fr1->depth_scale, 5000.0);
  EXPECT_DOUBLE_EQ(camera_preset("tum_fr3")->fy, 539.2);
  EXPECT_FALSE(camera_preset("tum_fr9"));
  // The benchmark's published d0..d4 (OpenCV's k1 k2 p1 p2 k3); fr3's images come undistorted.
  EXPECT_EQ(fr1->distortion, (std::array{0.2624, -0.9531, -0.0054, 0.0026, 1.1633}));
  EXPECT_EQ(camera_preset("tum_fr2")->distortion, (std::array{0.2312, -0.7849, -0.0033, -0.0001, 0.9172}));
  EXPECT_FALSE(camera_preset("tum_fr3")->has_distortion());
  EXPECT_FALSE(camera_preset("synthetic")->has_distortion());
  EXPECT_TRUE(fr1->has_distortion());
  for (const auto& name : camera_preset_names()) EXPECT_EQ(camera_preset(name)->validate(), "") << name;
}

TEST(Camera, ValidateNamesTheBadField) {
  Intrinsics k = *camera_preset("tum_fr2");
  k.fx = -1;
  EXPECT_NE(k.validate().find("fx"), std::string::npos);
  k = *camera_preset("tum_fr2");
  k.height = 0;
  EXPECT_NE(k.validate().find("height"), std::string::npos);
  k = *camera_preset("tum_fr2");
  k.distortion[4] = std::numeric_limits<double>::infinity();
  EXPECT_NE(k.validate().find("distortion"), std::string::npos);
}

}  // namespace
}  // namespace cvo::core
