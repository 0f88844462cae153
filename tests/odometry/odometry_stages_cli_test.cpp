// bench/odometry_stages keeps the command-line contract of every program (program/cli.hpp): a
// "--set" that is not KEY=VALUE is a usage error before any frame is read.
#include <filesystem>

#include <gtest/gtest.h>

#include "tests/support/cli_contract.hpp"
#include "tests/support/temp_dir.hpp"

namespace {

TEST(OdometryStagesCli, SetWithoutAnEqualsSignIsAUsageError) {
  if (!std::filesystem::exists(std::filesystem::path(CVO_TOOLS_DIR) / "odometry_stages"))
    GTEST_SKIP() << "odometry_stages is not built here (CVO_BUILD_BENCHMARKS=OFF)";
  const cvo::test::TempDir dir("odometry_stages");
  cvo::testing::expect_set_needs_key_equals_value("odometry_stages", "--frames 1", dir.path());
}

}  // namespace
