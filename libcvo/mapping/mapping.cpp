#include "libcvo/mapping/mapping.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

#include "libcvo/core/pixel_rays.hpp"

namespace cvo::mapping {

struct Mapping::Keyframe {
  std::vector<CloudPoint> cloud;
  std::optional<Eigen::Vector3d> measured_up;  // camera frame (accelerometer)
  std::optional<Eigen::Vector3d> plane_up;     // camera frame (its dominant horizontal plane)
  std::optional<Footprint> footprint;
  std::optional<FootprintPlacement> placed;  // where its footprint is in counts_
  core::SE3 map_T_camera;                    // at the last place()
};

namespace {

core::SE3 pose_of(const core::PoseParameter& p) {
  return {Eigen::Quaterniond(p[6], p[3], p[4], p[5]).normalized(), Eigen::Vector3d(p[0], p[1], p[2])};
}

double angle_between(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

// Whether a footprint placed at `from` would cover other cells at `to`: some column of it moves
// by a quarter cell or more (an optimisation moves every keyframe a little; re-placing those that
// moved less would change next to nothing and cost the whole grid).
bool moved(const FootprintPlacement& from, const FootprintPlacement& to, const Footprint& footprint) {
  const double tolerance = footprint.half_cell / 2;
  const double reach = footprint.half_cell * std::hypot(std::max<double>(-footprint.i_min, footprint.i_max) + 1,
                                                        std::max<double>(-footprint.j_min, footprint.j_max) + 1);
  const double turn = std::abs(std::remainder(to.yaw - from.yaw, 2 * M_PI));
  return (to.translation.head<2>() - from.translation.head<2>()).norm() + turn * reach >= tolerance ||
         std::abs(to.translation.z() - from.translation.z()) >= tolerance;
}

}  // namespace

std::vector<const slam::MapKeyframe*> placed_keyframes(const slam::Map& map) {
  std::vector<const slam::MapKeyframe*> keyframes;
  for (const auto& session : map.sessions)
    if (session.placed)
      for (const auto& k : map.keyframes)
        if (k.session == session.session) keyframes.push_back(&k);
  return keyframes;
}

Mapping::Mapping(const core::MappingParameters& parameters) : parameters_(parameters), counts_(parameters) {}
Mapping::~Mapping() = default;
Mapping::Mapping(Mapping&&) noexcept = default;
Mapping& Mapping::operator=(Mapping&&) noexcept = default;

bool Mapping::add_keyframe(KeyframeKey key, const core::RgbdFrame& frame, std::optional<Eigen::Vector3d> measured_up) {
  if (keyframes_.count(key)) return false;
  if (pixel_rays_.empty() || !(rays_for_ == frame.intrinsics)) {
    pixel_rays_ = core::undistorted_pixel_rays(frame.intrinsics);
    rays_for_ = frame.intrinsics;
  }
  auto keyframe = std::make_unique<Keyframe>();
  keyframe->cloud = make_local_cloud(frame, pixel_rays_, parameters_);
  if (measured_up && measured_up->allFinite() && measured_up->norm() > 0)
    keyframe->measured_up = measured_up->normalized();
  if (!parameters_.base_T_camera && !keyframe->measured_up)
    keyframe->plane_up = horizontal_plane_up(keyframe->cloud, parameters_.voxel_size);
  keyframes_.emplace(key, std::move(keyframe));
  ++statistics_.keyframes;
  return true;
}

// The grid frame the keyframes in the map give (see up.hpp); the first of them is the map's first.
std::optional<GridFrame> Mapping::decide_frame(const std::vector<Keyframe*>& in_map) const {
  if (in_map.empty()) return std::nullopt;
  const core::SE3& first = in_map.front()->map_T_camera;
  if (parameters_.base_T_camera)
    return GridFrame{first * pose_of(*parameters_.base_T_camera).inverse(), UpSource::mount};

  Eigen::Vector3d measured = Eigen::Vector3d::Zero(), plane = Eigen::Vector3d::Zero();
  for (const auto* k : in_map) {
    if (k->measured_up) measured += k->map_T_camera.rotation() * *k->measured_up;
    if (k->plane_up) plane += k->map_T_camera.rotation() * *k->plane_up;
  }
  const UpSource source = measured.norm() > 0 ? UpSource::accelerometer : UpSource::floor_plane;
  const Eigen::Vector3d up = (source == UpSource::accelerometer ? measured : plane);
  if (up.norm() == 0) return std::nullopt;
  const Eigen::Vector3d unit_up = up.normalized();

  // The floor: the lowest level holding a share of the map's surfaces, along up from the first
  // camera centre (every 4th cloud point: a percentile needs no more).
  const double h = parameters_.cell_size / 2;
  HeightHistogram heights;
  for (const auto* k : in_map) {
    const Eigen::Matrix3d rotation = k->map_T_camera.rotation_matrix();
    const Eigen::Vector3d from_first = k->map_T_camera.translation() - first.translation();
    for (std::size_t i = 0; i < k->cloud.size(); i += 4) {
      const double height = unit_up.dot(rotation * k->cloud[i].position().cast<double>() + from_first);
      heights.add(static_cast<long>(std::floor(height / h)), 1);
    }
  }
  const double floor = heights.floor_bin() ? (*heights.floor_bin() + 0.5) * h : 0.0;
  return GridFrame{core::SE3(grid_rotation(unit_up, first.rotation_matrix()), first.translation() + floor * unit_up),
                   source};
}

Eigen::Matrix3d Mapping::level_of(const Keyframe& keyframe) const {
  if (parameters_.base_T_camera) return pose_of(*parameters_.base_T_camera).rotation_matrix();
  if (keyframe.measured_up) return level_rotation(*keyframe.measured_up);
  if (keyframe.plane_up) return level_rotation(*keyframe.plane_up);
  // No plane of its own: the map's up, seen from where the keyframe is now.
  return level_rotation(keyframe.map_T_camera.rotation().conjugate() * frame_->map_T_grid.rotation() *
                        Eigen::Vector3d::UnitZ());
}

// Keyframes of the map's sessions that it no longer lists were merged into keyframes that cover
// their view (slam/mapper.hpp: revisits): their clouds go, and their footprints leave the grid.
// Returns whether the grid changed.
bool Mapping::forget_merged(const slam::Map& map) {
  std::set<core::SessionId> sessions;
  for (const auto& s : map.sessions) sessions.insert(s.session);
  std::set<KeyframeKey> listed;
  for (const auto& k : map.keyframes) listed.insert({k.session, k.id});
  bool changed = false;
  for (auto it = keyframes_.begin(); it != keyframes_.end();) {
    if (!sessions.contains(it->first.session) || listed.contains(it->first)) {
      ++it;
      continue;
    }
    if (const auto& k = *it->second; k.placed) {
      counts_.remove(*k.footprint, *k.placed);
      statistics_.cells_changed_last += counts_.cells_changed_last();
      changed = true;
    }
    it = keyframes_.erase(it);
    ++statistics_.forgotten;
  }
  return changed;
}

bool Mapping::place(const slam::Map& map) {
  const auto started = std::chrono::steady_clock::now();
  statistics_.cells_changed_last = 0;
  const bool forgot = forget_merged(map);
  std::vector<Keyframe*> in_map;
  for (const auto* k : placed_keyframes(map)) {
    const auto it = keyframes_.find({k->session, k->id});
    if (it == keyframes_.end()) continue;
    it->second->map_T_camera = k->pose;
    in_map.push_back(it->second.get());
  }
  revision_ = map.revision;
  // The frame is decided again only when the map has doubled since (the up and the floor settle
  // as the map grows; a new frame re-places everything).
  const bool decide = !frame_ || in_map.size() >= 2 * decided_with_;
  const auto decided = decide ? decide_frame(in_map) : frame_;
  if (decide && decided) decided_with_ = in_map.size();
  bool rebuild = false;
  if (decided &&
      (!frame_ || frame_->up != decided->up ||
       angle_between(frame_->map_T_grid.rotation_matrix(), decided->map_T_grid.rotation_matrix()) > 0.5 * M_PI / 180 ||
       (frame_->map_T_grid.translation() - decided->map_T_grid.translation()).norm() > parameters_.cell_size / 2)) {
    frame_ = decided;
    rebuild = true;
  }
  statistics_.replaced_last = statistics_.moved_last = 0;
  if (!frame_) return forgot;

  const core::SE3 grid_T_map = frame_->map_T_grid.inverse();
  std::vector<std::pair<Keyframe*, FootprintPlacement>> moves;
  for (auto* k : in_map) {
    if (!k->footprint) k->footprint = make_footprint(k->cloud, level_of(*k), parameters_);
    const auto placement = place_footprint(grid_T_map * k->map_T_camera, k->footprint->level_R_camera);
    if (rebuild || !k->placed || moved(*k->placed, placement, *k->footprint)) moves.emplace_back(k, placement);
  }
  statistics_.moved_last = static_cast<std::size_t>(
      std::count_if(moves.begin(), moves.end(), [](const auto& move) { return move.first->placed.has_value(); }));
  // Most keyframes moved (a loop closure's optimisation moves all a little): placing all anew
  // costs half of taking each out and putting it back.
  rebuild = rebuild || moves.size() * 2 > in_map.size();
  if (rebuild) {
    counts_.clear();
    for (auto& [key, keyframe] : keyframes_) keyframe->placed.reset();
  }
  for (auto& [k, placement] : moves) {
    if (k->placed)
      counts_.remove(*k->footprint, *k->placed), statistics_.cells_changed_last += counts_.cells_changed_last();
    counts_.add(*k->footprint, placement);
    statistics_.cells_changed_last += counts_.cells_changed_last();
    k->placed = placement;
  }
  if (rebuild)  // keyframes that did not move but were cleared
    for (auto* k : in_map)
      if (!k->placed) {
        k->placed = place_footprint(grid_T_map * k->map_T_camera, k->footprint->level_R_camera);
        counts_.add(*k->footprint, *k->placed);
      }
  statistics_.replaced_last = rebuild ? in_map.size() : moves.size();
  statistics_.rebuilt_last = rebuild;
  statistics_.place_ms_last =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
  return forgot || rebuild || !moves.empty();
}

std::optional<MapGrid> Mapping::grid() const {
  if (!frame_) return std::nullopt;
  return MapGrid{revision_, *frame_, counts_.grid()};
}

std::vector<ColouredPoint> Mapping::cloud() const {
  std::vector<PlacedCloud> clouds;
  for (const auto& [key, k] : keyframes_)
    if (k->placed) clouds.push_back({&k->cloud, k->map_T_camera});
  return assemble_cloud(clouds, parameters_.voxel_size);
}

std::unique_ptr<octomap::OcTree> Mapping::octree() const {
  if (!frame_) return nullptr;
  const core::SE3 grid_T_map = frame_->map_T_grid.inverse();
  std::vector<GridPlacedCloud> clouds;
  for (const auto& [key, k] : keyframes_)
    if (k->placed) clouds.push_back({&k->cloud, grid_T_map * k->map_T_camera});
  return make_octree(clouds, parameters_);
}

MappingStatistics Mapping::statistics() const {
  MappingStatistics s = statistics_;
  s.placed = 0;
  s.local_map_bytes = 0;
  for (const auto& [key, k] : keyframes_) {
    s.placed += k->placed.has_value();
    s.local_map_bytes +=
        sizeof(Keyframe) + k->cloud.capacity() * sizeof(CloudPoint) + (k->footprint ? k->footprint->bytes() : 0);
  }
  s.grid_bytes = counts_.bytes();
  return s;
}

}  // namespace cvo::mapping
