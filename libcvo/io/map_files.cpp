#include "libcvo/io/map_files.hpp"

#include <cmath>
#include <fstream>
#include <system_error>

#include <open3d/geometry/PointCloud.h>
#include <open3d/io/PointCloudIO.h>
#include <yaml-cpp/yaml.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "libcvo/io/input_error.hpp"

namespace cvo::io {
namespace {

namespace fs = std::filesystem;

// "grid.pgm" -> "grid.tmp.pgm": the writers pick the format by the extension.
fs::path temporary_for(const fs::path& file) {
  return file.parent_path() / (file.stem().string() + ".tmp" + file.extension().string());
}

void commit(const fs::path& temporary, const fs::path& file) {
  std::error_code error;
  fs::rename(temporary, file, error);
  if (error) throw InputError(file, "cannot be written: " + error.message());
}

cv::Mat grid_image(const mapping::OccupancyGrid& grid) {
  cv::Mat image(grid.height, grid.width, CV_8UC1);
  for (int row = 0; row < grid.height; ++row)
    for (int column = 0; column < grid.width; ++column) {
      const auto cell = grid.at(column, row);
      // The image's first row is the grid's last (the highest y), as map_server reads it.
      image.at<std::uint8_t>(grid.height - 1 - row, column) = cell == mapping::Cell::occupied ? 0
                                                              : cell == mapping::Cell::free   ? 254
                                                                                              : 205;
    }
  return image;
}

void write_grid(const fs::path& pgm, const fs::path& yaml, const mapping::MapGrid& map) {
  const auto& grid = map.grid;
  const fs::path pgm_temporary = temporary_for(pgm);
  if (grid.width == 0 || !cv::imwrite(pgm_temporary.string(), grid_image(grid), {cv::IMWRITE_PXM_BINARY, 1}))
    throw InputError(pgm, grid.width == 0 ? "the grid is empty" : "cannot be written");
  commit(pgm_temporary, pgm);

  const auto& t = map.frame.map_T_grid.translation();
  const auto& q = map.frame.map_T_grid.rotation();
  YAML::Emitter out;
  out.SetDoublePrecision(15);  // sub-nanometre, and 0.05 reads 0.05
  out << YAML::BeginMap << YAML::Key << "image" << YAML::Value << pgm.filename().string() << YAML::Key << "mode"
      << YAML::Value << "trinary" << YAML::Key << "resolution" << YAML::Value << grid.resolution << YAML::Key
      << "origin" << YAML::Value << YAML::Flow << YAML::BeginSeq << grid.origin.x() << grid.origin.y() << 0.0
      << YAML::EndSeq << YAML::Key << "negate" << YAML::Value << 0 << YAML::Key << "occupied_thresh" << YAML::Value
      << kOccupiedThreshold << YAML::Key << "free_thresh" << YAML::Value << kFreeThreshold << YAML::Key << "map_T_grid"
      << YAML::Value << YAML::Flow << YAML::BeginSeq << t.x() << t.y() << t.z() << q.x() << q.y() << q.z() << q.w()
      << YAML::EndSeq << YAML::Key << "up" << YAML::Value << std::string(mapping::up_source_name(map.frame.up))
      << YAML::Key << "revision" << YAML::Value << map.revision << YAML::EndMap;
  const fs::path yaml_temporary = temporary_for(yaml);
  {
    std::ofstream file(yaml_temporary);
    file << out.c_str() << '\n';
    if (!file.flush()) throw InputError(yaml, "cannot be written");
  }
  commit(yaml_temporary, yaml);
}

void write_cloud(const fs::path& ply, const std::vector<mapping::ColouredPoint>& points) {
  open3d::geometry::PointCloud cloud;
  cloud.points_.reserve(points.size());
  cloud.colors_.reserve(points.size());
  for (const auto& p : points) {
    cloud.points_.push_back(p.position.cast<double>());
    cloud.colors_.emplace_back(p.r / 255.0, p.g / 255.0, p.b / 255.0);
  }
  open3d::io::WritePointCloudOption option;
  option.write_ascii = open3d::io::WritePointCloudOption::IsAscii::Binary;
  option.print_progress = false;
  const fs::path temporary = temporary_for(ply);
  if (!open3d::io::WritePointCloudToPLY(temporary.string(), cloud, option)) throw InputError(ply, "cannot be written");
  commit(temporary, ply);
}

}  // namespace

MapFiles write_map_files(const fs::path& dir, const mapping::Mapping& mapping) {
  const auto grid = mapping.grid();
  if (!grid) throw InputError(dir, "no map: no keyframe in the map frame said which way is up");
  std::error_code error;
  fs::create_directories(dir, error);
  if (error) throw InputError(dir, "cannot be created: " + error.message());
  const MapFiles files{dir / "grid.pgm", dir / "grid.yaml", dir / "cloud.ply", dir / "octomap.bt"};
  write_grid(files.grid_pgm, files.grid_yaml, *grid);
  write_cloud(files.cloud_ply, mapping.cloud());
  const auto tree = mapping.octree();
  const fs::path temporary = temporary_for(files.octomap_bt);
  if (!tree || !tree->writeBinary(temporary.string())) throw InputError(files.octomap_bt, "cannot be written");
  commit(temporary, files.octomap_bt);
  return files;
}

void write_map_plot(const fs::path& png, const mapping::MapGrid& map, const std::vector<Eigen::Vector3d>& trajectory) {
  const auto& grid = map.grid;
  if (grid.width == 0) throw InputError(png, "the grid is empty");
  const int scale = std::max(1, static_cast<int>(std::ceil(800.0 / std::max(grid.width, grid.height))));
  cv::Mat grey;
  cv::resize(grid_image(grid), grey, {}, scale, scale, cv::INTER_NEAREST);
  cv::Mat image;
  cv::cvtColor(grey, image, cv::COLOR_GRAY2BGR);
  const core::SE3 grid_T_map = map.frame.map_T_grid.inverse();
  const auto pixel = [&](const Eigen::Vector3d& p_map) {
    const Eigen::Vector3d p = grid_T_map * p_map;
    const double column = (p.x() - grid.origin.x()) / grid.resolution,
                 row = (p.y() - grid.origin.y()) / grid.resolution;
    return cv::Point(static_cast<int>(std::lround(column * scale)),
                     static_cast<int>(std::lround((grid.height - row) * scale)));
  };
  std::vector<cv::Point> line;
  for (const auto& p : trajectory) line.push_back(pixel(p));
  if (!line.empty()) {
    cv::polylines(image, line, false, {200, 80, 0}, 2, cv::LINE_AA);
    cv::circle(image, line.front(), 6, {0, 160, 0}, cv::FILLED, cv::LINE_AA);
  }
  const std::string caption = std::to_string(grid.width) + " x " + std::to_string(grid.height) + " cells of " +
                              std::to_string(static_cast<int>(std::lround(grid.resolution * 100))) + " cm, up from " +
                              std::string(mapping::up_source_name(map.frame.up));
  cv::putText(image, caption, {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {0, 0, 200}, 2, cv::LINE_AA);
  if (!cv::imwrite(png.string(), image)) throw InputError(png, "cannot be written");
}

}  // namespace cvo::io
