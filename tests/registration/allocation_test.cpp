// After construction (and a first warm-up call), align() and inner_product() must not touch the
// heap: the tracker calls them from a realtime thread. This binary replaces the global
// operator new/delete to count every allocation.
#include <atomic>
#include <cstdlib>
#include <new>

#include <gtest/gtest.h>

#include "libcvo/registration/registration.hpp"
#include "tests/registration/registration_fixtures.hpp"

namespace {
std::atomic<long> g_allocations{0};
}

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, std::align_val_t alignment) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  const auto a = static_cast<std::size_t>(alignment);
  if (void* p = std::aligned_alloc(a, (size + a - 1) / a * a)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size, std::align_val_t alignment) { return operator new(size, alignment); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace cvo::registration {
namespace {

TEST(Allocation, CountingWorks) {
  const long before = g_allocations.load();
  void* p = ::operator new(16);  // an explicit call: a new-expression pair may be elided
  ::operator delete(p);
  EXPECT_EQ(g_allocations.load() - before, 1);
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
    long before = g_allocations.load();
    selector.select(frame_a, a);
    selector.select(frame_b, b);
    selection += g_allocations.load() - before;
    before = g_allocations.load();
    const auto r = registration.align(a, b, M_guess);
    alignment += g_allocations.load() - before;
    EXPECT_TRUE(r.converged);
    before = g_allocations.load();
    EXPECT_GT(registration.inner_product(a, b, r.transform), 0.0);
    inner_product += g_allocations.load() - before;
  }
  EXPECT_EQ(selection, 0) << "heap allocations in point selection";
  EXPECT_EQ(alignment, 0) << "heap allocations in align()";
  EXPECT_EQ(inner_product, 0) << "heap allocations in inner_product()";
}

}  // namespace
}  // namespace cvo::registration
