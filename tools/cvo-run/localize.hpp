#pragma once
// cvo-run's localization mode (--mode localize --map-store FILE): a sequence localized in a stored
// map, offline, as cvo-backendd's localization mode does it live:
//   the map       the keyframe store (cvo-backendd's, or cvo-run --mode slam --store), read without
//                 changing it (libcvo/store/store_records.hpp's read_store), replayed as cvo-backendd and cvo-map
//                 replay it (libcvo/store/replay.hpp), then the final global optimisation (as cvo-map); from
//                 then on it is read only (slam::Mapper::localize_only);
//   every frame   KF-CVO tracks it in the session's own odometry frame; its map pose is the
//                 session's correction as it stood when the frame was tracked, before the back end
//                 saw this frame's keyframe, times the odometry pose: causal, what a daemon would
//                 publish. Only frames of a LOCALIZED session have one;
//   then          its closed local graph and keyframe go to the mapper, which localizes the session
//                 by the verification that joins sessions (bag of words, RANSAC, CVO, α) and keeps
//                 its keyframes in a bounded window, never in the map;
//   lost          a frame whose odometry failed (TrackStep::lost) ends the session: marked LOST,
//                 the tracker reset, the next frame starts a new session (the kidnapped robot),
//                 localized again without any hint.
// Sessions are numbered after the store's highest, in order.
#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <ostream>

#include "libcvo/config/config.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/odometry/track_result.hpp"
#include "report.hpp"

namespace cvo::tools {

class Localizer {
 public:
  /// Replays the store at `map_store` (each record it cannot use named on `problems`); throws
  /// io::InputError naming it when it cannot be read, is not a keyframe store, or holds no map.
  Localizer(const config::Config& config, loop_closure::Vocabulary vocabulary, const std::filesystem::path& map_store,
            std::ostream& problems);
  ~Localizer();
  Localizer(const Localizer&) = delete;
  Localizer& operator=(const Localizer&) = delete;

  /// Tracks the frame (frames of width x height), then does the back end's share of work for it.
  odometry::TrackResult track(const core::RgbdFrame& frame);

  /// The map poses of the localized frames, in order.
  [[nodiscard]] const core::Trajectory& trajectory() const;
  [[nodiscard]] const LocalizeReport& report() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace cvo::tools
