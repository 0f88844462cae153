// mapping::MapGrid <-> grid_t (CVO_GRID): a lossless round trip through bytes, and grids that
// cannot be what they say (forged sizes, values, frames, numbers) refused with a message and a kind.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>

#include "lcm/sample_messages.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/grid_conversion.hpp"
#include "tests/lcm/through_bytes.hpp"

namespace cvo::lcm {
namespace {

mapping::MapGrid sample_map_grid() {
  mapping::MapGrid g;
  g.revision = 42;
  g.frame.map_T_grid = core::SE3::exp((core::Vector6d() << 0.5, -0.25, 1.5, 0.02, -0.01, 0.7).finished());
  g.frame.up = mapping::UpSource::floor_plane;
  g.grid.resolution = 0.05;
  g.grid.origin = {-2.35, 0.85};
  g.grid.width = 4;
  g.grid.height = 3;
  g.grid.cells = {-1, 0, 0, 100, 0, 100, -1, -1, 100, 100, 0, 0};
  return g;
}

TEST(GridConversion, RoundTripThroughBytesIsLossless) {
  const auto grid = sample_map_grid();
  const auto message = to_message(grid, 1305031299600000, 1305031200000000);
  EXPECT_EQ(message.frame, "grid");
  EXPECT_EQ(message.num_cells, 12);
  EXPECT_EQ(message.origin[2], 0.0) << "yaw";
  EXPECT_EQ(message.epoch, 1305031200000000);
  const auto decoded = through_bytes(message);
  ASSERT_TRUE(decoded);
  std::string error;
  const auto back = from_message(*decoded, &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->revision, 42u);
  EXPECT_EQ(back->frame.up, mapping::UpSource::floor_plane);
  EXPECT_EQ(back->grid, grid.grid);
  EXPECT_LT((back->frame.map_T_grid.matrix() - grid.frame.map_T_grid.matrix()).norm(), 1e-12);
}

TEST(GridConversion, EveryUpSourceSurvives) {
  for (const auto up : {mapping::UpSource::mount, mapping::UpSource::accelerometer, mapping::UpSource::floor_plane}) {
    auto grid = sample_map_grid();
    grid.frame.up = up;
    const auto back = from_message(to_message(grid, 0, 0), nullptr);
    ASSERT_TRUE(back);
    EXPECT_EQ(back->frame.up, up);
  }
}

TEST(GridConversion, AnEmptyGridIsAGrid) {
  auto grid = sample_map_grid();
  grid.grid.width = grid.grid.height = 0;
  grid.grid.cells.clear();
  std::string error;
  EXPECT_TRUE(from_message(to_message(grid, 0, 0), &error)) << error;
}

struct Forgery {
  const char* what;
  std::function<void(cvo_lcm::grid_t&)> forge;
  const char* says;
  ContentFailure kind;
};

TEST(GridConversion, ForgedGridsAreRefusedSayingWhy) {
  constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  const Forgery forgeries[] = {
      {"more cells than width x height", [](auto& m) { m.cells.push_back(0), ++m.num_cells; }, "7 cells for 3 x 2",
       ContentFailure::kContent},
      {"fewer cells", [](auto& m) { m.cells.pop_back(), --m.num_cells; }, "5 cells for 3 x 2",
       ContentFailure::kContent},
      {"a wider grid", [](auto& m) { m.width = 4; }, "6 cells for 4 x 2", ContentFailure::kContent},
      {"a size whose product overflows", [](auto& m) { m.width = m.height = 65536 * 2; }, "cells for",
       ContentFailure::kContent},
      {"a negative size", [](auto& m) { m.width = -3, m.height = -2; }, "negative size", ContentFailure::kContent},
      {"a probability instead of a trinary value", [](auto& m) { m.cells[4] = 65; }, "cell 4 is 65",
       ContentFailure::kContent},
      {"a negative value other than unknown", [](auto& m) { m.cells[0] = -2; }, "cell 0 is -2",
       ContentFailure::kContent},
      {"a zero resolution", [](auto& m) { m.resolution = 0; }, "not positive", ContentFailure::kContent},
      {"a negative resolution", [](auto& m) { m.resolution = -0.05; }, "not positive", ContentFailure::kContent},
      {"a NaN resolution", [&](auto& m) { m.resolution = kNan; }, "not finite", ContentFailure::kNotFinite},
      {"an infinite origin", [](auto& m) { m.origin[1] = std::numeric_limits<double>::infinity(); }, "not finite",
       ContentFailure::kNotFinite},
      {"a turned origin", [](auto& m) { m.origin[2] = 0.1; }, "yaw", ContentFailure::kContent},
      {"a NaN pose", [&](auto& m) { m.map_T_grid.position[2] = kNan; }, "not finite", ContentFailure::kNotFinite},
      {"a pose that is no rotation", [](auto& m) { m.map_T_grid.orientation[0] = 2; }, "map_T_grid",
       ContentFailure::kContent},
      {"another frame", [](auto& m) { m.frame = "map"; }, "frame 'map'", ContentFailure::kContent},
      {"an unknown up source", [](auto& m) { m.up = 3; }, "up source 3", ContentFailure::kContent},
      {"a negative revision", [](auto& m) { m.revision = -1; }, "negative revision", ContentFailure::kContent},
      {"another schema version", [](auto& m) { m.version = 1; }, "schema version 1", ContentFailure::kVersion},
  };
  for (const auto& f : forgeries) {
    auto message = test::sample_grid();
    ASSERT_TRUE(from_message(message, nullptr)) << "the sample is a grid";
    f.forge(message);
    std::string error;
    auto kind = static_cast<ContentFailure>(-1);
    EXPECT_FALSE(from_message(message, &error, &kind)) << f.what;
    EXPECT_NE(error.find("cvo_lcm.grid_t"), std::string::npos) << f.what << ": " << error;
    EXPECT_NE(error.find(f.says), std::string::npos) << f.what << ": " << error;
    EXPECT_EQ(kind, f.kind) << f.what << ": " << error;
  }
}

// The frame's name follows the cells: its length is found behind them, and a forged one is
// refused before lcm-gen's decoder reads it.
TEST(GridConversion, AForgedFrameLengthAfterTheCellsIsRefusedBeforeDecoding) {
  auto bytes = encode(test::sample_grid());
  // 4-byte length, "grid" and its NUL, then the auth trailer.
  const std::size_t frame_length = bytes.size() - 4 - 5 - static_cast<std::size_t>(kAuthTrailerBytes);
  ASSERT_EQ(bytes[frame_length + 3], 5);
  for (const std::uint32_t bad : {0u, 6u, 0x7f000005u, 0xffffffffu}) {
    for (int i = 0; i < 4; ++i)
      bytes[frame_length + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(bad >> (24 - 8 * i));
    std::string error;
    DecodeFailure failure = DecodeFailure::kTooShort;
    EXPECT_FALSE(decode<cvo_lcm::grid_t>(bytes.data(), static_cast<int>(bytes.size()), &error, &failure)) << bad;
    EXPECT_EQ(failure, DecodeFailure::kBody) << error;
    // A length within the buffer (6: the trailer follows) ends on a byte that is no NUL.
    EXPECT_TRUE(error.find("corrupt string length") != std::string::npos ||
                error.find("not one NUL-terminated text") != std::string::npos)
        << error;
  }
}

}  // namespace
}  // namespace cvo::lcm
