// eval::percentile is numpy's np.percentile (method "linear"): the expected values are numpy's.
#include "libcvo/eval/percentile.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace cvo::eval {
namespace {

TEST(Percentile, IsNumpysLinearInterpolationBetweenOrderStatistics) {
  // numpy's documentation example: np.percentile([[10, 7, 4], [3, 2, 1]], 50) == 3.5
  EXPECT_DOUBLE_EQ(percentile(std::vector<double>{10, 7, 4, 3, 2, 1}, 50), 3.5);
  // np.percentile([15, 20, 35, 40, 50], [0, 30, 40, 100]) == [15, 23, 29, 50]
  const std::vector<double> v{15, 20, 35, 40, 50};
  EXPECT_DOUBLE_EQ(percentile(v, 0), 15);
  EXPECT_DOUBLE_EQ(percentile(v, 30), 23);
  EXPECT_DOUBLE_EQ(percentile(v, 40), 29);
  EXPECT_DOUBLE_EQ(percentile(v, 100), 50);
  // np.percentile([4, 1, 3, 2], [50, 90]) == [2.5, 3.7]: unsorted input, an even count
  EXPECT_DOUBLE_EQ(percentile(std::vector<double>{4, 1, 3, 2}, 50), 2.5);
  EXPECT_DOUBLE_EQ(percentile(std::vector<double>{4, 1, 3, 2}, 90), 3.7);
  // np.percentile(np.arange(100), 99) == 98.01
  std::vector<double> hundred(100);
  std::iota(hundred.begin(), hundred.end(), 0.0);
  EXPECT_DOUBLE_EQ(percentile(hundred, 99), 98.01);
  EXPECT_DOUBLE_EQ(percentile(std::vector<double>{7}, 99), 7);
}

TEST(Percentile, InPlaceGivesTheSameValueAndKeepsTheValues) {
  std::vector<double> values{9, 2, 7, 4, 4, 1, 8};
  const double copied = percentile(values, 75);
  const std::vector<double> before = values;
  EXPECT_EQ(values, before) << "percentile() leaves its input as it was";
  EXPECT_DOUBLE_EQ(percentile_in_place(values, 75), copied);
  std::vector<double> sorted = values, expected = before;
  std::sort(sorted.begin(), sorted.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(sorted, expected) << "reordered, not changed";
}

TEST(Percentile, OfNoValuesIsNaNAndAPercentOutsideZeroToHundredIsAnError) {
  EXPECT_TRUE(std::isnan(percentile(std::vector<double>{}, 50)));
  EXPECT_THROW(percentile(std::vector<double>{1, 2}, 101), std::invalid_argument);
  EXPECT_THROW(percentile(std::vector<double>{1, 2}, -1), std::invalid_argument);
  EXPECT_THROW(percentile(std::vector<double>{1, 2}, std::nan("")), std::invalid_argument);
}

}  // namespace
}  // namespace cvo::eval
