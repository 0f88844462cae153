#include "libcvo/core/camera.hpp"

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
  for (const auto& name : camera_preset_names()) EXPECT_EQ(camera_preset(name)->validate(), "") << name;
}

TEST(Camera, ValidateNamesTheBadField) {
  Intrinsics k = *camera_preset("tum_fr2");
  k.fx = -1;
  EXPECT_NE(k.validate().find("fx"), std::string::npos);
  k = *camera_preset("tum_fr2");
  k.height = 0;
  EXPECT_NE(k.validate().find("height"), std::string::npos);
}

}  // namespace
}  // namespace cvo::core
