#include "libcvo/io/trajectory_io.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "libcvo/io/input_error.hpp"

namespace cvo::io {
namespace {

TEST(TrajectoryIo, RoundTripKeepsPosesAndSorts) {
  core::Trajectory t;
  t.push_back({2.5, core::SE3::exp((core::Vector6d() << 1, 2, 3, 0.1, -0.2, 0.3).finished())});
  t.push_back({1.25, core::SE3::from_translation({-1, 0, 0.5})});
  std::stringstream ss;
  write_tum_trajectory(ss, t);
  const auto back = parse_tum_trajectory(ss, "mem");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_DOUBLE_EQ(back[0].timestamp, 1.25);
  EXPECT_TRUE(back[1].pose.matrix().isApprox(t[0].pose.matrix(), 1e-8));
}

TEST(TrajectoryIo, CommentsBlankLinesAndCommas) {
  std::stringstream ss("# header\n\n1.0 0 0 0 0 0 0 1\n2.0,1,0,0,0,0,0,1 # trailing\n");
  const auto t = parse_tum_trajectory(ss, "mem");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_DOUBLE_EQ(t[1].pose.translation().x(), 1.0);
}

void expect_error(const std::string& text, std::size_t line, const std::string& fragment) {
  std::stringstream ss(text);
  try {
    parse_tum_trajectory(ss, "traj.txt");
    FAIL() << "no error for: " << text;
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("traj.txt:"), std::string::npos) << e.what();
  }
}

TEST(TrajectoryIo, MalformedLinesNameFileAndLine) {
  expect_error("1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n", 2, "expected 8 fields");
  expect_error("# c\n1 0 0 x 0 0 0 1\n", 2, "not a number: 'x'");
  expect_error("1 0 0 nan 0 0 0 1\n", 1, "not a finite number");
  expect_error("1 0 0 0 0 0 0 0\n", 1, "zero norm");
}

TEST(TrajectoryIo, MissingFileIsAClearError) {
  EXPECT_THROW(read_tum_trajectory("/nonexistent/traj.txt"), InputError);
  EXPECT_THROW(write_tum_trajectory("/nonexistent/dir/traj.txt", core::Trajectory{}), InputError);
}

}  // namespace
}  // namespace cvo::io
