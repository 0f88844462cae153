// The map's cost and accuracy (libcvo/mapping), a table, not Google Benchmark.
//
//   map_bench [--keyframes N]
//       cost on the rendered room: a keyframe's local map (time to make, bytes), and the grid of
//       N keyframes (default 1000) along a 60 m path: assembled from scratch, re-assembled after
//       a loop closure that moves every keyframe, and after one that moves a tenth of them; one
//       core, medians of 5.
//   map_bench --accuracy SEQUENCE RUN.json MAP_DIR
//       the map cvo-run --mode slam --map MAP_DIR --json > RUN.json wrote for SEQUENCE, against
//       the same keyframes' depth placed at SEQUENCE's ground-truth poses, in the ground truth's
//       frame (ours carried there by the ATE alignment of the run's trajectory, as evaluate_ate.py
//       aligns): median distance of our cloud's points to theirs, the share of their points within
//       3 cm of ours, and the grid's up against the ground truth's (TUM's motion-capture frame has
//       z up).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <open3d/geometry/KDTreeFlann.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/io/PointCloudIO.h>
#include <yaml-cpp/yaml.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <Eigen/SVD>
#include "libcvo/core/pixel_rays.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/eval/percentile.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/io/tum_dataset.hpp"
#include "libcvo/lcm/grid_conversion.hpp"
#include "libcvo/mapping/mapping.hpp"
#include "libcvo/sim/camera_path.hpp"
#include "libcvo/sim/render.hpp"
#include "libcvo/sim/scene.hpp"

namespace {

using namespace cvo;
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

template <class F>
double median_ms(int repetitions, F&& f) {
  std::vector<double> times;
  for (int r = 0; r < repetitions; ++r) {
    const auto start = Clock::now();
    f();
    times.push_back(ms_since(start));
  }
  return eval::percentile(times, 50);
}

struct LocalMap {
  std::vector<mapping::CloudPoint> cloud;
  mapping::Footprint footprint;
};

int cost(std::size_t keyframes) {
  const core::MappingParameters parameters;
  const auto scene = sim::make_scene(sim::SceneKind::textured_room, 1);
  const core::Intrinsics camera{525.0, 525.0, 319.5, 239.5, 640, 480, 5000.0};
  const auto rays = core::undistorted_pixel_rays(camera);
  std::vector<LocalMap> local;
  std::vector<double> cloud_ms, footprint_ms, bytes, surfaces, columns, points;
  for (int k = 0; k < 16; ++k) {
    const double yaw = k * 2 * M_PI / 16;
    const Eigen::Vector3d eye(0.6 * std::cos(yaw), 0.6 * std::sin(yaw), 1.0);
    const core::SE3 pose = sim::look_at(eye, eye + Eigen::Vector3d(std::cos(yaw), std::sin(yaw), -0.25));
    const auto frame = sim::render(scene, camera, pose);
    LocalMap m;
    cloud_ms.push_back(median_ms(3, [&] { m.cloud = mapping::make_local_cloud(frame, rays, parameters); }));
    const Eigen::Matrix3d level = mapping::level_rotation(pose.rotation().conjugate() * Eigen::Vector3d::UnitZ());
    footprint_ms.push_back(median_ms(3, [&] { m.footprint = mapping::make_footprint(m.cloud, level, parameters); }));
    bytes.push_back(static_cast<double>(m.cloud.size() * sizeof(mapping::CloudPoint) + m.footprint.bytes()));
    points.push_back(static_cast<double>(m.cloud.size()));
    surfaces.push_back(static_cast<double>(m.footprint.surface_k.size()));
    columns.push_back(static_cast<double>(m.footprint.columns.size()));
    local.push_back(std::move(m));
  }
  std::printf("local map (rendered room, 640x480, defaults), median of 16 keyframes:\n");
  std::printf("  cloud      %8.2f ms   %6.0f points (%zu B each)\n", eval::percentile(cloud_ms, 50),
              eval::percentile(points, 50), sizeof(mapping::CloudPoint));
  std::printf("  footprint  %8.2f ms   %6.0f surface voxels (2 B each), %6.0f columns (8 B each)\n",
              eval::percentile(footprint_ms, 50), eval::percentile(surfaces, 50), eval::percentile(columns, 50));
  std::printf("  bytes      %8.0f per keyframe (cloud and footprint)\n", eval::percentile(bytes, 50));

  // N placements of the 16 footprints along a 60 m path through a 20 m x 20 m building.
  std::vector<mapping::FootprintPlacement> path, moved_all, moved_tenth;
  for (std::size_t k = 0; k < keyframes; ++k) {
    const double s = 60.0 * static_cast<double>(k) / static_cast<double>(keyframes);
    const double x = std::fmod(s, 20.0), y = 4.0 * std::floor(s / 20.0);
    path.push_back({0.37 * static_cast<double>(k), Eigen::Vector3d(x, y, 1.0)});
  }
  moved_all = path, moved_tenth = path;
  for (std::size_t k = 0; k < keyframes; ++k) {
    moved_all[k].yaw += 0.01, moved_all[k].translation.x() += 0.03;
    if (k % 10 == 0) moved_tenth[k].yaw += 0.01, moved_tenth[k].translation.x() += 0.03;
  }
  mapping::OccupancyCounts counts(parameters);
  const auto add_all = [&](const std::vector<mapping::FootprintPlacement>& placements) {
    counts.clear();
    for (std::size_t k = 0; k < placements.size(); ++k) counts.add(local[k % local.size()].footprint, placements[k]);
  };
  const double scratch = median_ms(5, [&] { add_all(path); });
  const double rebuild = median_ms(5, [&] { add_all(moved_all); });
  add_all(path);
  bool forward = true;
  const double tenth = median_ms(5, [&] {
    const auto& from = forward ? path : moved_tenth;
    const auto& to = forward ? moved_tenth : path;
    for (std::size_t k = 0; k < keyframes; k += 10) {
      counts.remove(local[k % local.size()].footprint, from[k]);
      counts.add(local[k % local.size()].footprint, to[k]);
    }
    forward = !forward;
  });
  const double extract = median_ms(5, [&] { (void)counts.grid(); });
  const auto grid = counts.grid();
  std::printf("grid of %zu keyframes (%d x %d cells, counts %.1f MB), one core, median of 5:\n", keyframes, grid.width,
              grid.height, static_cast<double>(counts.bytes()) / 1e6);
  std::printf("  assembled from scratch           %8.1f ms\n", scratch);
  std::printf("  re-assembled, every one moved    %8.1f ms  (a loop closure's optimisation: all anew)\n", rebuild);
  std::printf("  re-placed, a tenth moved         %8.1f ms  (each taken out and put back)\n", tenth);
  std::printf("  trinary grid extracted           %8.1f ms\n", extract);
  return 0;
}

// ---- accuracy against the ground truth ----

core::SE3 pose_at(const core::Trajectory& t, double stamp) {
  const auto stamps = core::timestamps(t);
  return t[core::find_closest_index(stamps, stamp)].pose;
}

// The rigid motion T minimising sum_k |R_T R_k - R_gt,k|² (chordal) + |T p_k - p_gt,k|² over the
// keyframes: the rotation is the projection onto SO(3) of sum_k R_gt,k R_kᵀ, the translation
// the mean residual.
core::SE3 align_poses(const core::Trajectory& groundtruth, const core::Trajectory& estimate,
                      const std::vector<double>& stamps) {
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  for (const double t : stamps)
    sum += pose_at(groundtruth, t).rotation_matrix() * pose_at(estimate, t).rotation_matrix().transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  const Eigen::Matrix3d rotation = svd.matrixU() * d * svd.matrixV().transpose();
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  for (const double t : stamps)
    offset += pose_at(groundtruth, t).translation() - rotation * pose_at(estimate, t).translation();
  return {rotation, offset / static_cast<double>(stamps.size())};
}

int accuracy(const std::filesystem::path& sequence, const std::filesystem::path& run_json,
             const std::filesystem::path& map_dir) {
  const auto run = nlohmann::json::parse(std::ifstream(run_json));
  const std::vector<double> stamps = run.at("map").at("keyframe_timestamps").get<std::vector<double>>();
  const auto seq = io::TumSequence::open(sequence);
  const auto groundtruth = io::read_tum_trajectory(sequence / "groundtruth.txt");
  const auto trajectory = io::read_tum_trajectory(run.at("trajectory").get<std::string>());
  const core::SE3 world_T_map = align_poses(groundtruth, trajectory, stamps);

  // Their cloud: the same keyframes' depth at the ground-truth poses, made as ours is.
  const core::MappingParameters parameters;
  const auto rays = core::undistorted_pixel_rays(seq.intrinsics());
  std::vector<std::vector<mapping::CloudPoint>> clouds;
  std::vector<mapping::PlacedCloud> placed;
  clouds.reserve(stamps.size());
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const double t = seq.files()[i].timestamp;
    if (std::none_of(stamps.begin(), stamps.end(), [t](double s) { return std::abs(s - t) < 1e-6; })) continue;
    clouds.push_back(mapping::make_local_cloud(seq.read(i), rays, parameters));
    placed.push_back({&clouds.back(), pose_at(groundtruth, t)});
  }
  const auto theirs_points = mapping::assemble_cloud(placed, parameters.voxel_size);
  open3d::geometry::PointCloud ours, theirs;
  if (!open3d::io::ReadPointCloud((map_dir / "cloud.ply").string(), ours))
    return std::fprintf(stderr, "cannot read cloud.ply\n"), 1;
  for (auto& p : ours.points_) p = world_T_map * p;
  for (const auto& p : theirs_points) theirs.points_.push_back(p.position.cast<double>());
  const open3d::geometry::KDTreeFlann their_tree(theirs), our_tree(ours);
  std::vector<int> index(1);
  std::vector<double> d2(1);
  std::vector<double> ours_to_theirs;
  for (const auto& p : ours.points_)
    if (their_tree.SearchKNN(p, 1, index, d2) > 0) ours_to_theirs.push_back(std::sqrt(d2[0]));
  std::size_t within = 0;
  for (const auto& p : theirs.points_) within += our_tree.SearchKNN(p, 1, index, d2) > 0 && d2[0] <= 0.03 * 0.03;

  const YAML::Node yaml = YAML::LoadFile((map_dir / "grid.yaml").string());
  const auto q = yaml["map_T_grid"];
  const Eigen::Quaterniond map_R_grid(q[6].as<double>(), q[3].as<double>(), q[4].as<double>(), q[5].as<double>());
  const Eigen::Vector3d our_up = world_T_map.rotation() * (map_R_grid * Eigen::Vector3d::UnitZ());
  const Eigen::Vector3d their_up = Eigen::Vector3d::UnitZ();
  std::printf("map of %s (%zu keyframes, up from the %s) against the ground truth:\n", sequence.c_str(), stamps.size(),
              yaml["up"].as<std::string>().c_str());
  std::printf("  our %zu points to theirs   median %.4f m, p90 %.4f m\n", ours.points_.size(),
              eval::percentile(ours_to_theirs, 50), eval::percentile(ours_to_theirs, 90));
  std::printf("  their %zu points within 3 cm of ours   %.1f %%\n", theirs.points_.size(),
              100.0 * static_cast<double>(within) / static_cast<double>(theirs.points_.size()));
  // CVO_GRID of this grid, as the back end would send it.
  const cv::Mat pgm = cv::imread((map_dir / "grid.pgm").string(), cv::IMREAD_UNCHANGED);
  mapping::MapGrid grid;
  grid.grid.width = pgm.cols, grid.grid.height = pgm.rows;
  grid.grid.cells.assign(pgm.total(), -1);
  const auto message = lcm::to_message(grid, 0, 0);
  std::printf("  CVO_GRID of its %d x %d cells   %d bytes\n", pgm.cols, pgm.rows, message.getEncodedSize());
  std::printf("  grid up against the ground truth's   %.2f deg\n",
              std::acos(std::clamp(our_up.dot(their_up), -1.0, 1.0)) * 180 / M_PI);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.size() == 4 && args[0] == "--accuracy") return accuracy(args[1], args[2], args[3]);
  if (args.empty()) return cost(1000);
  if (args.size() == 2 && args[0] == "--keyframes") return cost(std::stoul(args[1]));
  std::fprintf(stderr, "usage: map_bench [--keyframes N] | map_bench --accuracy SEQUENCE RUN.json MAP_DIR\n");
  return 2;
}
