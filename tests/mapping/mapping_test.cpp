// The map from keyframes of a rendered room with exact depth (libcvo/mapping): walls where they
// are, free floor, a cloud on the surfaces, obstacles cleared when they go, which way is up, and
// re-placement after a loop closure that gives the grid a fresh build gives.
#include <gtest/gtest.h>

#include <cmath>

#include "libcvo/mapping/mapping.hpp"
#include "libcvo/sim/scene.hpp"
#include "rendered_room.hpp"
#include "tests/support/map_session.hpp"

namespace cvo::mapping {
namespace {

using testing::camera_at;
using testing::kBox;
using testing::map_of;
using testing::room;

struct Built {
  Mapping mapping;
  std::vector<core::SE3> poses;
};

core::MappingParameters mounted() {
  core::MappingParameters p;
  p.base_T_camera = testing::mount();
  return p;
}

// Keyframes seen from `poses`, the first `with_box` of them rendered with the box there, placed
// at `placed` (`poses` when empty).
Built build(const std::vector<core::SE3>& poses, std::size_t with_box, const core::MappingParameters& parameters,
            bool accelerometer = false, std::vector<core::SE3> placed = {}) {
  if (placed.empty()) placed = poses;
  Built b{Mapping(parameters), placed};
  const auto with = room(true), without = room(false);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const auto frame = sim::render(k < with_box ? with : without, testing::camera(), poses[k]);
    std::optional<Eigen::Vector3d> up;
    if (accelerometer) up = poses[k].rotation().conjugate() * Eigen::Vector3d(0, 0, 9.81);
    EXPECT_TRUE(b.mapping.add_keyframe({1, static_cast<std::int64_t>(k)}, frame, up));
  }
  b.mapping.place(map_of(placed));
  return b;
}

// Eight keyframes turning on the spot in the room's middle: every wall is seen.
std::vector<core::SE3> turning() {
  std::vector<core::SE3> poses;
  for (int k = 0; k < 8; ++k) poses.push_back(camera_at(0, 0, 45.0 * k));
  return poses;
}

// Grid-frame point of a world point (the grid frame's pose in the world follows from the map's).
Eigen::Vector3d in_grid(const MapGrid& grid, const std::vector<core::SE3>& poses, const Eigen::Vector3d& world) {
  return grid.frame.map_T_grid.inverse() * (poses.front().inverse() * world);
}

Cell cell_at_world(const MapGrid& grid, const std::vector<core::SE3>& poses, const Eigen::Vector3d& world) {
  const Eigen::Vector3d g = in_grid(grid, poses, world);
  return grid.grid.at_point(g.x(), g.y());
}

// Distance (m) in the floor plane from a world point to the nearest wall.
double to_wall(const Eigen::Vector3d& p) {
  const auto room_box = sim::room_bounds();
  return std::min(
      {p.x() - room_box.min().x(), room_box.max().x() - p.x(), p.y() - room_box.min().y(), room_box.max().y() - p.y()});
}

TEST(Mapping, WallsAreOccupiedWithinOneCellOfWhereTheyAre) {
  const auto b = build(turning(), 0, mounted());
  const auto grid = b.mapping.grid();
  ASSERT_TRUE(grid);
  const double cell = grid->grid.resolution;
  std::size_t occupied = 0;
  const core::SE3 world_T_grid = b.poses.front() * grid->frame.map_T_grid;
  for (int row = 0; row < grid->grid.height; ++row)
    for (int column = 0; column < grid->grid.width; ++column) {
      if (grid->grid.at(column, row) != Cell::occupied) continue;
      ++occupied;
      const Eigen::Vector3d centre = world_T_grid * Eigen::Vector3d(grid->grid.origin.x() + (column + 0.5) * cell,
                                                                    grid->grid.origin.y() + (row + 0.5) * cell, 0.5);
      EXPECT_LE(std::abs(to_wall(centre)), cell * 1.5) << "an occupied cell at " << centre.transpose() << " is no wall";
    }
  EXPECT_GT(occupied, 200u);
  // Along every wall, at 0.5 m above the floor, some cell within one cell of the wall is occupied.
  std::size_t missed = 0, sampled = 0;
  for (double s = -1.4; s <= 1.4; s += 0.1)
    for (const Eigen::Vector3d& wall : {Eigen::Vector3d(2.0, s, 0.5), Eigen::Vector3d(-2.0, s, 0.5),
                                        Eigen::Vector3d(s, 2.5, 0.5), Eigen::Vector3d(s, -2.5, 0.5)}) {
      bool found = false;
      for (double dx = -cell; dx <= cell + 1e-9; dx += cell)
        for (double dy = -cell; dy <= cell + 1e-9; dy += cell)
          found = found || cell_at_world(*grid, b.poses, wall + Eigen::Vector3d(dx, dy, 0)) == Cell::occupied;
      missed += !found, ++sampled;
    }
  EXPECT_EQ(missed, 0u) << "of " << sampled << " points along the walls";
}

TEST(Mapping, TheFloorBetweenTheCameraAndTheWallsIsFree) {
  const auto b = build(turning(), 0, mounted());
  const auto grid = b.mapping.grid();
  ASSERT_TRUE(grid);
  std::size_t not_free = 0, sampled = 0;
  for (int k = 0; k < 16; ++k) {
    const double a = k * M_PI / 8;
    for (double r = 0.3; r <= 1.7; r += 0.2) {
      const Eigen::Vector3d p(r * std::cos(a), r * std::sin(a), 0);
      if (to_wall(p) < 0.2) continue;
      not_free += cell_at_world(*grid, b.poses, p) != Cell::free, ++sampled;
    }
  }
  EXPECT_EQ(not_free, 0u) << "of " << sampled << " floor points";
}

TEST(Mapping, TheCloudLiesWithinOneCentimetreOfTheRenderedSurfaces) {
  const auto b = build(turning(), 0, mounted());
  const auto cloud = b.mapping.cloud();
  ASSERT_GT(cloud.size(), 10000u);
  const auto scene = room(false);
  double worst = 0;
  for (const auto& p : cloud)
    worst = std::max(worst, sim::distance_to_surface(scene, b.poses.front() * p.position.cast<double>()));
  EXPECT_LT(worst, 0.01);
}

TEST(Mapping, ABoxSeenInTheFirstKeyframesAndGoneFromLaterOnesEndsAsFreeCells) {
  // Two keyframes see the box, six more (from elsewhere) see the floor where it stood.
  std::vector<core::SE3> poses{camera_at(-0.5, -0.5, 50), camera_at(-0.3, -0.6, 55)};
  for (const auto& [x, y, yaw] : std::vector<std::array<double, 3>>{
           {-0.6, -0.2, 45}, {0.2, -0.8, 70}, {-1.0, 0.0, 30}, {0.0, -0.4, 60}, {-0.4, -1.0, 60}, {-1.2, -0.6, 40}})
    poses.push_back(camera_at(x, y, yaw));
  const auto seen = build(std::vector<core::SE3>(poses.begin(), poses.begin() + 2), 2, mounted());
  const auto gone = build(poses, 2, mounted());
  std::size_t box_cells = 0, box_cells_free_later = 0;
  for (double x = kBox.min().x() + 0.05; x < kBox.max().x(); x += 0.1)
    for (double y = kBox.min().y() + 0.05; y < kBox.max().y(); y += 0.1) {
      const Eigen::Vector3d p(x, y, 0);
      if (cell_at_world(*seen.mapping.grid(), seen.poses, p) != Cell::occupied) continue;
      ++box_cells;
      box_cells_free_later += cell_at_world(*gone.mapping.grid(), gone.poses, p) == Cell::free;
    }
  EXPECT_GT(box_cells, 3u) << "the first keyframes see the box as an obstacle";
  EXPECT_EQ(box_cells_free_later, box_cells);
}

TEST(Mapping, ALoopClosureThatMovesKeyframesGivesTheGridABuildFromScratchAtTheNewPosesGives) {
  auto b = build(turning(), 0, mounted());
  // The correction: two keyframes move by 6 cm and 2 degrees.
  auto moved = b.poses;
  for (const std::size_t k : {3u, 5u})
    moved[k] = core::SE3(Eigen::Quaterniond(Eigen::AngleAxisd(2 * M_PI / 180, Eigen::Vector3d::UnitZ())),
                         Eigen::Vector3d(0.06, -0.03, 0)) *
               moved[k];
  const auto before = b.mapping.grid()->grid;
  EXPECT_TRUE(b.mapping.place(map_of(moved, 2)));
  const auto statistics = b.mapping.statistics();
  EXPECT_EQ(statistics.replaced_last, 2u) << "only the keyframes that moved are re-placed";
  EXPECT_EQ(statistics.moved_last, 2u);
  EXPECT_FALSE(statistics.rebuilt_last);
  const auto fresh = build(b.poses, 0, mounted(), false, moved);
  EXPECT_EQ(b.mapping.grid()->grid, fresh.mapping.grid()->grid);
  EXPECT_NE(b.mapping.grid()->grid, before) << "the move changed the grid";
  EXPECT_EQ(b.mapping.grid()->revision, 2u);
  // Moving every keyframe (a global optimisation) rebuilds, with the same result.
  for (auto& pose : moved) pose = core::SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0.02, 0)) * pose;
  moved.front() = b.poses.front();  // the map frame stays the first keyframe's
  EXPECT_TRUE(b.mapping.place(map_of(moved, 3)));
  EXPECT_EQ(b.mapping.grid()->grid, build(turning(), 0, mounted(), false, moved).mapping.grid()->grid);
}

TEST(Mapping, AKeyframeThatMovedLessThanAQuarterCellStaysWhereItWasPlaced) {
  auto b = build(turning(), 0, mounted());
  const auto before = b.mapping.grid()->grid;
  auto nudged = b.poses;
  nudged[4] = core::SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.003, 0, 0)) * nudged[4];
  EXPECT_FALSE(b.mapping.place(map_of(nudged, 2)));
  EXPECT_EQ(b.mapping.statistics().replaced_last, 0u);
  EXPECT_EQ(b.mapping.grid()->grid, before);
}

TEST(Mapping, PlacingTheSameMapAgainChangesNothing) {
  auto b = build(turning(), 0, mounted());
  EXPECT_FALSE(b.mapping.place(map_of(b.poses)));
  EXPECT_EQ(b.mapping.statistics().replaced_last, 0u);
}

TEST(Mapping, AKeyframeTheMapNoLongerListsIsForgottenAndLeavesTheGrid) {
  auto b = build(turning(), 0, mounted());
  const auto held = b.mapping.statistics().local_map_bytes;
  auto merged = map_of(b.poses, 2);  // keyframe 5 merged into one that covers its view
  merged.keyframes.erase(merged.keyframes.begin() + 5);
  EXPECT_TRUE(b.mapping.place(merged));
  const auto statistics = b.mapping.statistics();
  EXPECT_EQ(statistics.forgotten, 1u);
  EXPECT_EQ(statistics.placed, 7u);
  EXPECT_LT(statistics.local_map_bytes, held) << "its cloud is freed";
  EXPECT_FALSE(b.mapping.knows({1, 5}));
  // The grid is the one the seven others make.
  Mapping fresh(mounted());
  const auto without = room(false);
  for (std::size_t k = 0; k < b.poses.size(); ++k)
    if (k != 5)
      fresh.add_keyframe({1, static_cast<std::int64_t>(k)}, sim::render(without, testing::camera(), b.poses[k]));
  fresh.place(merged);
  EXPECT_EQ(b.mapping.grid()->grid, fresh.grid()->grid);
  // Keyframes of a session the map does not name are not its to forget.
  auto other = map_of(b.poses, 3);
  other.sessions.front().session = 2;
  other.keyframes.clear();
  b.mapping.place(other);
  EXPECT_EQ(b.mapping.statistics().forgotten, 1u);
}

// The grid frame's z in the world, and its origin's height above the floor.
void expect_level_and_on_the_floor(const Built& b, double degrees, double metres) {
  const auto grid = b.mapping.grid();
  ASSERT_TRUE(grid);
  const core::SE3 world_T_grid = b.poses.front() * grid->frame.map_T_grid;
  const Eigen::Vector3d up = world_T_grid.rotation() * Eigen::Vector3d::UnitZ();
  EXPECT_LT(std::acos(std::min(1.0, up.z())) * 180 / M_PI, degrees);
  EXPECT_NEAR(world_T_grid.translation().z(), 0.0, metres);
}

TEST(Mapping, TheMountSaysWhichWayIsUpAndWhereTheFloorIs) {
  const auto b = build(turning(), 0, mounted());
  EXPECT_EQ(b.mapping.grid()->frame.up, UpSource::mount);
  expect_level_and_on_the_floor(b, 1e-6, 1e-9);
}

TEST(Mapping, WithoutAMountTheAccelerometerSaysWhichWayIsUp) {
  const auto b = build(turning(), 0, core::MappingParameters{}, true);
  EXPECT_EQ(b.mapping.grid()->frame.up, UpSource::accelerometer);
  expect_level_and_on_the_floor(b, 0.01, 0.03);
}

TEST(Mapping, WithNeitherTheFloorPlaneSaysWhichWayIsUp) {
  const auto b = build(turning(), 0, core::MappingParameters{});
  EXPECT_EQ(b.mapping.grid()->frame.up, UpSource::floor_plane);
  expect_level_and_on_the_floor(b, 0.5, 0.03);
}

TEST(Mapping, KeyframesOfASessionNotInTheMapWaitUntilItJoins) {
  auto b = build(turning(), 0, mounted());
  const auto alone = b.mapping.grid()->grid;
  ASSERT_TRUE(b.mapping.add_keyframe({2, 0}, sim::render(room(true), testing::camera(), camera_at(0.5, 0.5, 60))));
  EXPECT_FALSE(b.mapping.add_keyframe({2, 0}, sim::render(room(true), testing::camera(), camera_at(0.5, 0.5, 60))));
  auto map = map_of(b.poses, 2);
  map.sessions.push_back(test::map_session(2, false, 2, 1, -1, core::SE3()));
  map.keyframes.push_back({2, 0, 0, core::SE3()});
  b.mapping.place(map);
  EXPECT_EQ(b.mapping.grid()->grid, alone);
  EXPECT_EQ(b.mapping.statistics().placed, 8u);
  map.sessions.back().placed = true;
  map.keyframes.back().pose = b.poses.front().inverse() * camera_at(0.5, 0.5, 60);
  b.mapping.place(map);
  EXPECT_EQ(b.mapping.statistics().placed, 9u);
}

TEST(Mapping, AFrameWhoseImagesDoNotMatchItsIntrinsicsIsRefused) {
  Mapping mapping{core::MappingParameters{}};
  auto frame = sim::render(room(false), testing::camera(), camera_at(0, 0, 0));
  frame.intrinsics.width = 640;  // the images are 320 wide
  EXPECT_THROW(mapping.add_keyframe({1, 0}, frame), std::invalid_argument);
  EXPECT_FALSE(mapping.knows({1, 0}));
}

}  // namespace
}  // namespace cvo::mapping
