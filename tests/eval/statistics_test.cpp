#include "libcvo/eval/statistics.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace cvo::eval {
namespace {

TEST(CvoEvalStatistics, MatchesNumpyDefinitions) {
  const std::vector<double> e{4, 1, 3, 2};
  const auto s = summarize(e);
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(30.0 / 4));
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);              // even count: mean of the two middle values
  EXPECT_DOUBLE_EQ(s.stddev, std::sqrt(1.25));  // population deviation (ddof = 0)
  EXPECT_DOUBLE_EQ(s.min, 1);
  EXPECT_DOUBLE_EQ(s.max, 4);
  EXPECT_DOUBLE_EQ(summarize(std::vector<double>{5, 1, 3}).median, 3);
}

TEST(CvoEvalStatistics, EmptyListIsAnError) { EXPECT_THROW(summarize(std::vector<double>{}), std::invalid_argument); }

}  // namespace
}  // namespace cvo::eval
