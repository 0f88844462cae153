#pragma once
// The map a robot navigates by, from the SLAM map's keyframes (cvo-run --mode slam, cvo-map and
// cvo-backendd all keep one of these beside their slam::Mapper):
//
//   add_keyframe  once per keyframe: its local cloud (local_map.hpp) from its depth and colour;
//                 the frame is not kept. Its footprint is made the first time it is placed, once
//                 its levelling is known (up.hpp).
//   place         the keyframes of every placed session of a slam::Map at their poses: the grid
//                 frame is decided (up.hpp; again each time the map has doubled), new keyframes
//                 are placed, moved ones re-placed (occupancy.hpp: only their cells change), and
//                 every one when the grid frame moved or most keyframes did. A keyframe moved
//                 when some column of its footprint moved by a quarter cell or more; one that
//                 moved less stays where it was placed. A keyframe of the map's sessions that the
//                 map no longer lists (merged into one that covers its view: slam/mapper.hpp,
//                 revisits) is forgotten, its footprint taken out of the grid: the local clouds
//                 follow the area mapped, not the time spent in it.
//   grid, cloud, octree   the products (occupancy.hpp, cloud.hpp, octree.hpp).
//
// Keyframes of sessions not yet in the map frame wait, local clouds made, until their session
// joins.
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/mapping/cloud.hpp"
#include "libcvo/mapping/local_map.hpp"
#include "libcvo/mapping/occupancy.hpp"
#include "libcvo/mapping/octree.hpp"
#include "libcvo/mapping/up.hpp"
#include "libcvo/slam/mapper.hpp"

namespace cvo::mapping {

struct KeyframeKey {
  core::SessionId session = 0;
  std::int64_t id = 0;
  auto operator<=>(const KeyframeKey&) const = default;
};

struct GridFrame {
  core::SE3 map_T_grid;  // the grid frame (z up, z = 0 on the floor) in the map frame
  UpSource up = UpSource::floor_plane;
};

/// A grid with the frame it is in and the map revision it shows.
struct MapGrid {
  std::uint64_t revision = 0;  // slam::Map::revision it was placed at
  GridFrame frame;
  OccupancyGrid grid;
};

struct MappingStatistics {
  std::size_t keyframes = 0;        // local clouds made
  std::size_t forgotten = 0;        // of them, dropped: the map no longer lists their keyframes (merged)
  std::size_t placed = 0;           // footprints in the grid
  std::size_t local_map_bytes = 0;  // every keyframe's cloud and footprint
  std::size_t grid_bytes = 0;       // the counts behind the grid
  std::size_t replaced_last = 0;    // keyframes the last place() placed or re-placed
  std::size_t moved_last = 0;       // of them, placed before and moved (or moved by a new grid frame)
  std::size_t cells_changed_last = 0;
  bool rebuilt_last = false;  // the last place() placed every keyframe anew
  double place_ms_last = 0;   // wall time of the last place()
};

/// The keyframes of the map's placed sessions (in the map frame), sessions in the map's order:
/// what the map is made of, and the trajectory drawn on it.
std::vector<const slam::MapKeyframe*> placed_keyframes(const slam::Map& map);

class Mapping {
 public:
  explicit Mapping(const core::MappingParameters& parameters);
  ~Mapping();
  Mapping(Mapping&&) noexcept;
  Mapping& operator=(Mapping&&) noexcept;

  /// Makes the keyframe's local cloud; false (nothing done) when the key is known. `measured_up`:
  /// the up direction the camera's accelerometer measured at the keyframe, in the camera frame.
  /// Throws std::invalid_argument on a frame whose images do not match its intrinsics.
  bool add_keyframe(KeyframeKey key, const core::RgbdFrame& frame, std::optional<Eigen::Vector3d> measured_up = {});

  /// See the header. Returns whether the grid changed. Keyframes of the map not added are skipped.
  bool place(const slam::Map& map);

  /// Empty (no frame) until some keyframe says which way is up.
  [[nodiscard]] std::optional<MapGrid> grid() const;
  /// Map frame.
  [[nodiscard]] std::vector<ColouredPoint> cloud() const;
  /// Grid frame; nullptr without a grid frame.
  [[nodiscard]] std::unique_ptr<octomap::OcTree> octree() const;
  [[nodiscard]] std::optional<GridFrame> grid_frame() const { return frame_; }
  [[nodiscard]] MappingStatistics statistics() const;
  [[nodiscard]] bool knows(KeyframeKey key) const { return keyframes_.count(key) > 0; }

 private:
  struct Keyframe;
  bool forget_merged(const slam::Map& map);
  [[nodiscard]] std::optional<GridFrame> decide_frame(const std::vector<Keyframe*>& in_map) const;
  [[nodiscard]] Eigen::Matrix3d level_of(const Keyframe& keyframe) const;

  core::MappingParameters parameters_;
  core::Intrinsics rays_for_;  // the intrinsics pixel_rays_ were computed for
  std::vector<float> pixel_rays_;
  std::map<KeyframeKey, std::unique_ptr<Keyframe>> keyframes_;
  std::optional<GridFrame> frame_;
  std::size_t decided_with_ = 0;  // keyframes in the map when the frame was last decided
  OccupancyCounts counts_;
  std::uint64_t revision_ = 0;
  MappingStatistics statistics_;
};

}  // namespace cvo::mapping
