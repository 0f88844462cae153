// The map's files read back by the tools people use: grid.yaml / grid.pgm as Nav2's map_server
// reads them, octomap.bt through OctoMap's API and its convert_octree, cloud.ply by meshio (a PLY
// reader that is not the writer's).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <octomap/OcTree.h>
#include <yaml-cpp/yaml.h>
#include <opencv2/imgcodecs.hpp>

#include "libcvo/io/input_error.hpp"
#include "libcvo/io/map_files.hpp"
#include "rendered_room.hpp"
#include "tests/support/run_tool.hpp"

namespace cvo::io {
namespace {

namespace fs = std::filesystem;
using mapping::testing::camera_at;

class MapFilesTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    core::MappingParameters parameters;
    parameters.base_T_camera = mapping::testing::mount();
    mapping_ = new mapping::Mapping(parameters);
    for (int k = 0; k < 8; ++k) poses_.push_back(camera_at(0, 0, 45.0 * k));
    for (std::size_t k = 0; k < poses_.size(); ++k)
      mapping_->add_keyframe({1, static_cast<std::int64_t>(k)},
                             sim::render(mapping::testing::room(true), mapping::testing::camera(), poses_[k]));
    mapping_->place(mapping::testing::map_of(poses_, 7));
    dir_ = fs::temp_directory_path() / ("cvo_map_files_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    files_ = write_map_files(dir_, *mapping_);
  }
  static void TearDownTestSuite() {
    fs::remove_all(dir_);
    delete mapping_;
  }

  static mapping::Mapping* mapping_;
  static std::vector<core::SE3> poses_;
  static fs::path dir_;
  static MapFiles files_;
};

mapping::Mapping* MapFilesTest::mapping_ = nullptr;
std::vector<core::SE3> MapFilesTest::poses_;
fs::path MapFilesTest::dir_;
MapFiles MapFilesTest::files_;

// map_server's trinary reading (nav2_map_server map_io, negate 0): occupancy = (255 - value) / 255;
// above occupied_thresh occupied (100), below free_thresh free (0), else unknown (-1). The image's
// first row is the map's highest y.
std::vector<std::int8_t> as_map_server_reads(const cv::Mat& image, double occupied, double free) {
  std::vector<std::int8_t> cells;
  for (int row = image.rows - 1; row >= 0; --row)
    for (int column = 0; column < image.cols; ++column) {
      const double occupancy = (255.0 - image.at<std::uint8_t>(row, column)) / 255.0;
      cells.push_back(occupancy > occupied ? 100 : occupancy < free ? 0 : -1);
    }
  return cells;
}

TEST_F(MapFilesTest, GridYamlAndPgmReadBackAsMapServerReadsThem) {
  const auto grid = mapping_->grid();
  const YAML::Node yaml = YAML::LoadFile(files_.grid_yaml.string());
  EXPECT_EQ(yaml["image"].as<std::string>(), "grid.pgm");
  EXPECT_EQ(yaml["mode"].as<std::string>(), "trinary");
  EXPECT_EQ(yaml["negate"].as<int>(), 0);
  EXPECT_DOUBLE_EQ(yaml["resolution"].as<double>(), 0.05);
  ASSERT_EQ(yaml["origin"].size(), 3u);
  EXPECT_NEAR(yaml["origin"][0].as<double>(), grid->grid.origin.x(), 1e-12);
  EXPECT_NEAR(yaml["origin"][1].as<double>(), grid->grid.origin.y(), 1e-12);
  EXPECT_EQ(yaml["origin"][2].as<double>(), 0.0);
  ASSERT_EQ(yaml["map_T_grid"].size(), 7u);
  const auto& t = grid->frame.map_T_grid.translation();
  EXPECT_NEAR(yaml["map_T_grid"][2].as<double>(), t.z(), 1e-12);
  EXPECT_NEAR(yaml["map_T_grid"][6].as<double>(), grid->frame.map_T_grid.rotation().w(), 1e-12);
  EXPECT_EQ(yaml["up"].as<std::string>(), "mount");

  const cv::Mat image =
      cv::imread((files_.grid_yaml.parent_path() / yaml["image"].as<std::string>()).string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(image.type(), CV_8UC1);
  EXPECT_EQ(image.cols, grid->grid.width);
  EXPECT_EQ(image.rows, grid->grid.height);
  EXPECT_EQ(as_map_server_reads(image, yaml["occupied_thresh"].as<double>(), yaml["free_thresh"].as<double>()),
            grid->grid.cells);
  std::ifstream pgm(files_.grid_pgm, std::ios::binary);
  std::string magic;
  pgm >> magic;
  EXPECT_EQ(magic, "P5") << "binary PGM, as map_server's image loader expects";
}

TEST_F(MapFilesTest, OctomapReadsBackThroughOctomapsApiAndItsTools) {
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(files_.octomap_bt.string()));
  EXPECT_DOUBLE_EQ(tree.getResolution(), 0.05);
  // The grid frame is z up with the floor at 0: a wall 2 m ahead of the first camera, seen at
  // 0.5 m above the floor, is occupied; the air between is free.
  const auto grid = mapping_->grid();
  const core::SE3 grid_T_world = grid->frame.map_T_grid.inverse() * poses_.front().inverse();
  const auto node_at = [&](const Eigen::Vector3d& world) {
    const Eigen::Vector3d g = grid_T_world * world;
    return tree.search(g.x(), g.y(), g.z());
  };
  bool wall = false;  // in the voxel just before x = 2 m or just after (the surface is their border)
  for (const double x : {1.98, 2.02})
    if (const auto* node = node_at({x, 0.0, 0.5})) wall = wall || tree.isNodeOccupied(node);
  EXPECT_TRUE(wall);
  const auto* air = node_at({1.0, 0.0, 0.8});
  ASSERT_NE(air, nullptr);
  EXPECT_FALSE(tree.isNodeOccupied(air));

  const auto converted = dir_ / "converted.ot";
  const int status = std::system(("convert_octree " + cvo::testing::quoted(files_.octomap_bt) + " " +
                                  cvo::testing::quoted(converted) + " > /dev/null")
                                     .c_str());
  EXPECT_EQ(status, 0);
  EXPECT_GT(fs::file_size(converted), 0u);
}

TEST_F(MapFilesTest, CloudPlyIsReadByAnotherPlyReader) {
  const auto cloud = mapping_->cloud();
  const auto script = dir_ / "read_ply.py";
  std::ofstream(script) << "import sys, meshio, numpy\n"
                           "m = meshio.read(sys.argv[1])\n"
                           "p = m.points\n"
                           "r = m.point_data['red'].astype(numpy.uint8)\n"  // meshio reads uchar as int8
                           "print(len(p), ' '.join('%.4f' % v for v in (p.min(0).tolist() + p.max(0).tolist())),"
                           " int(r.max()))\n";
  const auto run = cvo::testing::run_program(
      "/usr/bin/python3", cvo::testing::quoted(script) + " " + cvo::testing::quoted(files_.cloud_ply), dir_);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::istringstream out(run.out);
  std::size_t points = 0;
  Eigen::Vector3d lo, hi;
  int red = 0;
  out >> points >> lo.x() >> lo.y() >> lo.z() >> hi.x() >> hi.y() >> hi.z() >> red;
  EXPECT_EQ(points, cloud.size());
  Eigen::Vector3d expected_lo = cloud.front().position.cast<double>(), expected_hi = expected_lo;
  int expected_red = 0;
  for (const auto& p : cloud)
    expected_lo = expected_lo.cwiseMin(p.position.cast<double>()),
    expected_hi = expected_hi.cwiseMax(p.position.cast<double>()), expected_red = std::max<int>(expected_red, p.r);
  EXPECT_LT((lo - expected_lo).norm(), 1e-3);
  EXPECT_LT((hi - expected_hi).norm(), 1e-3);
  EXPECT_EQ(red, expected_red);
}

TEST_F(MapFilesTest, ThePlotShowsTheGrid) {
  const auto png = dir_ / "grid.png";
  std::vector<Eigen::Vector3d> centres;
  for (const auto& pose : poses_) centres.push_back((poses_.front().inverse() * pose).translation());
  write_map_plot(png, *mapping_->grid(), centres);
  const cv::Mat image = cv::imread(png.string());
  ASSERT_FALSE(image.empty());
  EXPECT_GE(std::max(image.cols, image.rows), 800);
}

TEST(MapFiles, AMappingWithoutAGridWritesNothingAndSaysWhy) {
  const mapping::Mapping empty{core::MappingParameters{}};
  const auto dir = fs::temp_directory_path() / ("cvo_map_files_empty_" + std::to_string(::getpid()));
  try {
    write_map_files(dir, empty);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("which way is up"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "grid.yaml"));
}

}  // namespace
}  // namespace cvo::io
