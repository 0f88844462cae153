// After construction (and a first warm-up call), select(), align() and inner_product() must not
// touch the heap: the tracker calls them from a realtime thread. This binary links
// program/allocation_counter.cpp, which counts every operator new.
#include <new>

#include <gtest/gtest.h>

#include "libcvo/registration/registration.hpp"
#include "program/allocation_counter.hpp"
#include "tests/registration/registration_fixtures.hpp"

using cvo::program::process_allocations;

namespace cvo::registration {
namespace {

TEST(Allocation, CountingWorks) {
  const auto before = process_allocations();
  void* p = ::operator new(16);  // an explicit call: a new-expression pair may be elided
  ::operator delete(p);
  EXPECT_EQ(process_allocations() - before, 1);
}

TEST(Allocation, SelectAlignAndInnerProductAllocateNothingAfterWarmUp) {
  const auto scene = sim::make_scene(sim::SceneKind::textured_room, 42);
  const auto K = *core::camera_preset("synthetic");
  const auto pose = testing::camera_looking_north();
  const auto M = testing::motion({0, 1, 0}, 2.0, {0.01, 0, 0.01});
  const auto frame_a = sim::render(scene, K, pose);
  const auto frame_b = sim::render(scene, K, pose * M);

  PointSelector selector(K.width, K.height, core::SelectionParameters{});
  PointCloud a(8192), b(8192);
  Registration registration(Capacities{8192}, core::CvoParameters{});
  // Warm-up: first calls may touch lazily initialised library state.
  selector.select(frame_a, a);
  selector.select(frame_b, b);
  // The tracker's situation: a guess (constant velocity) near the answer.
  const auto M_guess = testing::motion({0, 1, 0}, 1.5, {0.008, 0, 0.012});
  registration.align(a, b, M_guess);
  registration.inner_product(a, b, M);

  // Counted separately so a failure names the culprit.
  long selection = 0, alignment = 0, inner_product = 0;
  for (int k = 0; k < 3; ++k) {
    auto before = process_allocations();
    selector.select(frame_a, a);
    selector.select(frame_b, b);
    selection += process_allocations() - before;
    before = process_allocations();
    const auto r = registration.align(a, b, M_guess);
    alignment += process_allocations() - before;
    EXPECT_TRUE(r.converged);
    before = process_allocations();
    EXPECT_GT(registration.inner_product(a, b, r.transform), 0.0);
    inner_product += process_allocations() - before;
  }
  EXPECT_EQ(selection, 0) << "heap allocations in point selection";
  EXPECT_EQ(alignment, 0) << "heap allocations in align()";
  EXPECT_EQ(inner_product, 0) << "heap allocations in inner_product()";
}

TEST(Allocation, DistortedSelectionAllocatesNothingAfterTheFirstFrame) {
  // A distorted camera builds its ray table on its first frame; later frames only read it.
  const auto scene = sim::make_scene(sim::SceneKind::textured_room, 42);
  auto K = *core::camera_preset("synthetic");
  const auto pose = testing::camera_looking_north();
  auto frame_a = sim::render(scene, K, pose);
  auto frame_b = sim::render(scene, K, pose * testing::motion({0, 1, 0}, 2.0, {0.01, 0, 0.01}));
  frame_a.intrinsics.distortion = frame_b.intrinsics.distortion = core::camera_preset("tum_fr1")->distortion;

  PointSelector selector(K.width, K.height, core::SelectionParameters{});
  PointCloud cloud(8192);
  selector.select(frame_a, cloud);  // warm-up: builds the table
  const auto before = process_allocations();
  for (int k = 0; k < 3; ++k) {
    selector.select(frame_a, cloud);
    selector.select(frame_b, cloud);
  }
  EXPECT_EQ(process_allocations() - before, 0) << "heap allocations in distorted point selection";
  EXPECT_GT(cloud.size(), 2000u);
}

}  // namespace
}  // namespace cvo::registration
