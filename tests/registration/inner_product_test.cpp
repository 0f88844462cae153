#include <gtest/gtest.h>

#include "libcvo/registration/registration.hpp"
#include "tests/registration/registration_fixtures.hpp"

namespace cvo::registration {
namespace {

using testing::motion;

class InnerProduct : public ::testing::Test {
 protected:
  testing::RenderedPair pair = testing::render_pair(sim::SceneKind::textured_room, testing::camera_looking_north(),
                                                    motion({0, 1, 0}, 2.0, {0.02, 0, 0.01}));
  core::SE3 truth = motion({0, 1, 0}, 2.0, {0.02, 0, 0.01});
  Registration registration{Capacities{8192}, core::CvoParameters{}};
};

TEST_F(InnerProduct, IsSymmetric) {
  // <f_X, T.f_Z> = <f_Z, T^-1.f_X>: the same pairs at the same distances.
  for (const double ell : {0.05, 0.1, 0.3}) {
    const double forward = registration.inner_product(pair.first, pair.second, truth, ell);
    const double backward = registration.inner_product(pair.second, pair.first, truth.inverse(), ell);
    EXPECT_GT(forward, 0.0);
    EXPECT_NEAR(forward, backward, 1e-4 * forward) << "ell " << ell;
  }
}

TEST_F(InnerProduct, IsMaximalNearTheTruePose) {
  // At ℓ = 0.05 m every perturbation of 0.5-1° or 5-10 mm lowers it by more than 2 %...
  const double ell = 0.05;
  const double at_truth = registration.inner_product(pair.first, pair.second, truth, ell);
  for (const auto& delta : {motion({1, 0, 0}, 1.0, {0, 0, 0}), motion({0, 0, 1}, 0.5, {0, 0, 0}),
                            motion({0, 1, 0}, 0.0, {0.01, 0, 0}), motion({0, 1, 0}, 0.0, {0, -0.005, 0.005})}) {
    EXPECT_LT(registration.inner_product(pair.first, pair.second, delta * truth, ell), 0.98 * at_truth);
  }
  // ...and maximising from the truth stays there (the maximum is within 1 mm and 0.05°).
  const auto r = registration.align(pair.first, pair.second, truth);
  EXPECT_LT((truth.inverse() * r.transform).translation().norm(), 1e-3);
  EXPECT_LT(testing::deg((truth.inverse() * r.transform).angle()), 0.05);
  // r.inner_product is at ℓ_min; Gauss-Newton steps ascend only approximately. (It sums what both
  // views see, so this compares a registration that sums everything.)
  core::CvoParameters all_points;
  all_points.mutual_visibility = false;
  Registration summing_all{Capacities{8192}, all_points};
  EXPECT_GE(summing_all.align(pair.first, pair.second, truth).inner_product,
            registration.inner_product(pair.first, pair.second, truth) * 0.995);
}

TEST_F(InnerProduct, GammaIsOneForIdenticalClouds) {
  // γ = <f_Xm, T.f_Xn> / <f_Xm, T'.f_Xm+1> with identical clouds and poses is exactly 1.
  const double reference = registration.inner_product(pair.first, pair.first, core::SE3());
  EXPECT_GT(reference, 0.0);
  EXPECT_DOUBLE_EQ(registration.inner_product(pair.first, pair.first, core::SE3()) / reference, 1.0);
  // An identical cloud moved by T and compared under T is the same cloud: γ = 1 again.
  PointCloud moved(8192);
  const auto T = motion({1, 1, 0}, 3.0, {0.05, 0, 0});
  for (std::size_t i = 0; i < pair.first.size(); ++i)
    moved.push_back((T.inverse() * pair.first.position(i).cast<double>()).cast<float>(), pair.first.feature(i));
  EXPECT_NEAR(registration.inner_product(pair.first, moved, T) / reference, 1.0, 1e-3);
}

TEST_F(InnerProduct, BadInputGivesZeroNotACrash) {
  PointCloud empty(10);
  EXPECT_EQ(registration.inner_product(empty, pair.second, truth), 0.0);
  const core::SE3 nan = core::SE3::from_translation({std::nan(""), 0, 0});
  EXPECT_EQ(registration.inner_product(pair.first, pair.second, nan), 0.0);
}

}  // namespace
}  // namespace cvo::registration
