#pragma once
// cvo-run's SLAM mode: the paper's whole pipeline (its figure "Pipeline for CVO SLAM"), offline
// and in one thread, frame by frame, over one or more sessions (one per folder: a robot mapping a
// building in several runs):
//   every frame       KF-CVO tracks it (odometry::KeyframeOdometry, a new one per session: each
//                     session has its own odometry frame);
//   after each frame  the tracker's step says which local graph closed and which frame became a
//                     keyframe (with the tracker's own keyframe cloud, as cvo-trackerd sends it);
//                     both go to slam::Mapper, the back end cvo-backendd runs too;
//                     with a store (--store), each is appended to it first, as cvo-backendd
//                     stores a record before it uses it (store_output.hpp);
//   end_session()     the session's open local graph (the tracker's finish()) goes to the mapper;
//   finish()          the global optimisation; with a map (--map), every keyframe's local map
//                     (made as it became a keyframe, levelled by the session's accelerometer
//                     where the folder has one) placed at its final pose.
// The tracker never sees the corrections: it runs in its own odometry frame, and the back end
// works on relative poses.
#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

#include "libcvo/config/config.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/io/accelerometer.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/mapping/mapping.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"
#include "libcvo/odometry/track_result.hpp"
#include "libcvo/slam/mapper.hpp"
#include "store_output.hpp"

namespace cvo::tools {

struct SlamStatistics {
  double backend_ms = 0;  // local graphs, loop detection, keyframe optimisations: whole run
  double final_ms = 0;    // end of the last session (its open local graph) and the global optimisation
  double map_ms = 0;      // placing every keyframe's local map at its final pose (--map)
  double store_ms = 0;    // encoding and writing the keyframe store's records (--store), not in backend_ms
};

class SlamPipeline {
 public:
  /// With `map`, keyframes are mapped too (mapping()); with `store`, keyframes and local graphs are
  /// written to a new keyframe store there (throws io::InputError naming it when it exists).
  SlamPipeline(const config::Config& config, loop_closure::Vocabulary vocabulary, bool map = false,
               const std::optional<std::filesystem::path>& store = std::nullopt);
  ~SlamPipeline();

  /// Starts session `session` with frames of width x height (ends the previous one first);
  /// `accelerometer`: its camera's samples, when the recording has them.
  void begin_session(core::SessionId session, int width, int height,
                     std::vector<io::AccelerometerSample> accelerometer = {});
  /// Tracks the frame, then does the back end's share of work for it (see above).
  odometry::TrackStep track(const core::RgbdFrame& frame);
  /// Hands the session's open local graph to the mapper (nothing when none is open).
  void end_session();
  /// Ends the session and runs the global optimisation.
  void finish();

  [[nodiscard]] const SlamStatistics& statistics() const { return statistics_; }
  [[nodiscard]] const slam::Mapper& mapper() const { return mapper_; }
  /// nullptr without a map.
  [[nodiscard]] const mapping::Mapping* mapping() const { return mapping_.get(); }
  /// nullptr without a store.
  [[nodiscard]] const StoreOutput* store() const { return store_.get(); }

 private:
  struct Session;
  void add_local_graph(core::SessionId session, const odometry::HandedLocalGraph& graph);
  template <class Write>
  void to_store(Write&& write);

  config::Config config_;
  slam::Mapper mapper_;
  std::unique_ptr<mapping::Mapping> mapping_;
  std::unique_ptr<StoreOutput> store_;
  std::unique_ptr<Session> session_;
  SlamStatistics statistics_;
};

}  // namespace cvo::tools
