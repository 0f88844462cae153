#include "libcvo/core/trajectory.hpp"

#include <gtest/gtest.h>

namespace cvo::core {
namespace {

TEST(FindClosestIndex, PicksNearestAndClampsAtEnds) {
  const std::vector<double> t{1.0, 2.0, 3.0, 4.0};
  EXPECT_EQ(find_closest_index(t, -5.0), 0u);
  EXPECT_EQ(find_closest_index(t, 2.4), 1u);
  EXPECT_EQ(find_closest_index(t, 2.6), 2u);
  EXPECT_EQ(find_closest_index(t, 3.0), 2u);
  EXPECT_EQ(find_closest_index(t, 99.0), 3u);
}

TEST(Associate, GreedyByDifferenceEachUsedOnce) {
  // 1.00 matches both 1.005 and 0.99; the closer (1.005) wins, 0.99 stays unmatched because
  // nothing else lies within 0.02 of it. 3.0 has no partner within the window.
  const std::vector<double> a{1.0, 2.0, 3.0};
  const std::vector<double> b{0.99, 1.005, 2.015, 3.5};
  const auto m = associate(a, b, 0.02);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0], (std::pair<std::size_t, std::size_t>{0, 1}));
  EXPECT_EQ(m[1], (std::pair<std::size_t, std::size_t>{1, 2}));
}

TEST(Associate, OffsetShiftsSecondList) {
  const std::vector<double> a{10.0, 11.0};
  const std::vector<double> b{0.0, 1.0};
  EXPECT_EQ(associate(a, b, 0.02, 10.0).size(), 2u);
  EXPECT_TRUE(associate(a, b, 0.02, 0.0).empty());
}

TEST(Associate, UnsortedInputAndStrictWindow) {
  const std::vector<double> a{3.0, 1.0};
  const std::vector<double> b{1.02, 2.999};
  const auto m = associate(a, b, 0.02);  // |1.0 - 1.02| == 0.02 is outside (strict, as TUM)
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0], (std::pair<std::size_t, std::size_t>{0, 1}));
}

}  // namespace
}  // namespace cvo::core
