// SE3 <-> pose3d_t (w, x, y, z order), 6x6 matrices, utime.
#include <gtest/gtest.h>

#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {
namespace {

TEST(PoseConversion, RoundTripIsExactAndOrderIsWxyz) {
  const core::SE3 pose = core::SE3::exp((core::Vector6d() << 0.3, -1.2, 2.5, 0.4, -0.1, 0.7).finished());
  const auto m = to_message(pose);
  EXPECT_EQ(m.orientation[0], pose.rotation().w());
  EXPECT_EQ(m.orientation[3], pose.rotation().z());
  std::string error;
  const auto back = from_message(m, &error);
  ASSERT_TRUE(back) << error;
  EXPECT_TRUE(back->matrix().isApprox(pose.matrix(), 1e-15));
  EXPECT_EQ(back->translation(), pose.translation());
}

TEST(PoseConversion, RejectsNonUnitAndNonFinite) {
  auto m = to_message(core::SE3());
  m.orientation[0] = 2;
  std::string error;
  EXPECT_FALSE(from_message(m, &error));
  EXPECT_NE(error.find("unit quaternion"), std::string::npos) << error;
  m = to_message(core::SE3());
  m.position[1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(from_message(m, &error));
  EXPECT_NE(error.find("position"), std::string::npos) << error;
}

TEST(PoseConversion, Matrix6IsRowMajor) {
  core::Matrix6d a;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) a(r, c) = 10 * r + c;
  double raw[36];
  matrix6_to_message(a, raw);
  EXPECT_EQ(raw[1], 1);
  EXPECT_EQ(raw[6], 10);
  EXPECT_EQ(matrix6_from_message(raw), a);
}

TEST(PoseConversion, TumTimestampsSurviveUtime) {
  for (double t : {1305031229.528748, 1305031229.564425, 0.000001, 1700000000.999999}) {
    EXPECT_EQ(from_utime(to_utime(t)), t);
  }
  EXPECT_EQ(to_utime(1305031229.528748), 1305031229528748);
}

}  // namespace
}  // namespace cvo::lcm
