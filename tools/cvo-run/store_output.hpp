#pragma once
// cvo-run --mode slam --store FILE: the keyframe store cvo-backendd would write from the same
// keyframes and local graphs, so that a map made offline serves a daemon (cvo-backendd --store
// FILE resumes it, cvo-map reads it). Each record is what the daemon stores: the CVO_KEYFRAME or
// CVO_LOCAL_GRAPH that cvo-trackerd would send, in libcvo/lcm's encoding (colour as
// trackerd.keyframe_colour_encoding, depth PNG), written by the daemon's own KeyframeStore
// (libcvo/store/keyframe_store.hpp: the file format, the checksums, fdatasync).
//
// Sessions are cvo-run's (1, 2, ... one per folder). A local graph's `utime` ("when the graph was
// closed") is its newest frame's sensor time, not the wall clock: the same input writes the same
// bytes. The file must not exist: a store is a robot's map, and cvo-run neither appends to one
// (its session ids would collide) nor overwrites one.
#include <cstdint>
#include <filesystem>
#include <memory>

#include "libcvo/config/config.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/odometry/local_graph.hpp"
#include "libcvo/registration/point_cloud.hpp"
#include "libcvo/slam/mapper.hpp"

namespace cvo::tools {

class StoreOutput {
 public:
  /// Creates the store at `file`; throws io::InputError naming it when it exists or cannot be made.
  StoreOutput(const std::filesystem::path& file, const config::Config& config);
  ~StoreOutput();
  StoreOutput(const StoreOutput&) = delete;
  StoreOutput& operator=(const StoreOutput&) = delete;

  /// Appends the keyframe's record, durably; throws io::InputError naming the file when it cannot.
  void keyframe(core::SessionId session, std::int64_t id, const core::RgbdFrame& frame, const core::SE3& pose,
                const registration::PointCloud& cloud);
  /// Appends the local graph's record (keyframe `keyframe_id` of `session`), as above.
  void local_graph(core::SessionId session, std::int64_t keyframe_id, const odometry::LocalGraph& graph);

  /// Appends the record of a merge the mapper made (libcvo/store/merge_record.hpp), after the
  /// keyframe's own record, as above; that record is garbage then, and the store compacts when
  /// garbage passes half of it (keyframe_store.hpp).
  void merge(const slam::KeyframeMerge& merge);

  [[nodiscard]] std::uint64_t records() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace cvo::tools
