#include "libcvo/sim/scene.hpp"

#include <cmath>

#include <gtest/gtest.h>

#include "libcvo/sim/random.hpp"
#include "libcvo/sim/texture.hpp"

namespace cvo::sim {
namespace {

TEST(SceneKinds, NamesRoundTrip) {
  for (const auto& name : scene_names()) {
    const auto kind = parse_scene_kind(name);
    ASSERT_TRUE(kind) << name;
    EXPECT_EQ(scene_name(*kind), name);
  }
  EXPECT_FALSE(parse_scene_kind("kitchen"));
}

TEST(SceneIntersect, AxisRaysHitTheRoomExactly) {
  const Scene scene = make_scene(SceneKind::textured_room, 1);
  // Straight down from the middle of the room: the floor, 1.3 m below.
  const auto down = intersect(scene, {{0, 0, 1.3}, {0, 0, -2}});
  ASSERT_TRUE(down);
  EXPECT_DOUBLE_EQ(down->t, 0.65);  // direction of length 2
  EXPECT_NEAR(down->point.z(), 0.0, 1e-12);
  EXPECT_TRUE(down->normal.isApprox(Eigen::Vector3d::UnitZ()));
  // Towards -x: the wall at x = -2, whose front faces into the room.
  const auto west = intersect(scene, {{0, 0, 1.3}, {-1, 0, 0}});
  ASSERT_TRUE(west);
  EXPECT_NEAR(west->t, 2.0, 1e-12);
  EXPECT_TRUE(west->normal.isApprox(Eigen::Vector3d::UnitX()));
  // Away from the room nothing is hit.
  EXPECT_FALSE(intersect(scene, {{0, 0, 5}, {0, 0, 1}}));
}

TEST(SceneIntersect, RoomIsClosedAndHitsLieOnSurfaces) {
  const Scene scene = make_scene(SceneKind::textured_room, 2);
  Draws draws(99);
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d origin(draws.uniform(-0.6, 0.6), draws.uniform(-0.6, 0.6), draws.uniform(0.9, 1.7));
    const Eigen::Vector3d dir(draws.uniform(-1, 1), draws.uniform(-1, 1), draws.uniform(-1, 1));
    const auto hit = intersect(scene, {origin, dir});
    ASSERT_TRUE(hit) << "ray escaped the room";
    EXPECT_LT(distance_to_surface(scene, hit->point), 1e-9);
    EXPECT_TRUE(room_bounds().exteriorDistance(hit->point) < 1e-9);
  }
}

TEST(SceneGeometry, FurnitureStandsInsideTheRoomAndOffCentre) {
  const Scene scene = make_scene(SceneKind::textured_room, 0);
  EXPECT_EQ(scene.surfaces.size(), 6u + 5u * 5u);  // room + five furniture boxes without bottoms
  for (const auto& s : scene.surfaces) {
    const Quad& q = s.quad;
    EXPECT_NEAR(q.axis_s.dot(q.axis_t), 0.0, 1e-12);
    for (const double a : {0.0, 1.0})
      for (const double b : {0.0, 1.0}) {
        const Eigen::Vector3d corner = q.origin + a * q.length_s * q.axis_s + b * q.length_t * q.axis_t;
        EXPECT_LT(room_bounds().exteriorDistance(corner), 1e-12);
      }
  }
  EXPECT_GT(distance_to_surface(scene, Eigen::Vector3d(0, 0, 1.3)), 1.0);
}

TEST(SceneDistance, ClosedFormCases) {
  Quad q;  // unit square in z = 0
  EXPECT_DOUBLE_EQ(distance_to_quad(q, {0.5, 0.5, 0.3}), 0.3);
  EXPECT_DOUBLE_EQ(distance_to_quad(q, {2.0, 0.5, 0.0}), 1.0);
  EXPECT_NEAR(distance_to_quad(q, {2.0, 2.0, 1.0}), std::sqrt(3.0), 1e-15);
  const Scene wall = make_scene(SceneKind::textured_wall, 0);
  EXPECT_DOUBLE_EQ(distance_to_surface(wall, {0.1, 0.5, 1.0}), 2.0);
}

TEST(SceneTexture, DeterministicPerSeedAndVaried) {
  const Texture a = random_texture(5), b = random_texture(5), c = random_texture(6);
  int differ = 0;
  for (int i = 0; i < 100; ++i) {
    const double s = 0.037 * i, t = 0.021 * i;
    EXPECT_EQ(albedo(a, s, t), albedo(b, s, t));
    if ((albedo(a, s, t) - albedo(c, s, t)).norm() > 0.02) ++differ;
    const Eigen::Vector3d rgb = albedo(a, s, t);
    EXPECT_TRUE((rgb.array() >= 0).all() && (rgb.array() <= 1).all());
  }
  EXPECT_GT(differ, 80);
  const Texture flat = random_flat_texture(3);
  EXPECT_EQ(albedo(flat, 0.1, 0.2), albedo(flat, 3.4, -1.0));
}

}  // namespace
}  // namespace cvo::sim
