#pragma once
// cvo-map's work: a back end's keyframe store, read without changing it (libcvo/store/store_records.hpp's
// read_store: it may be read while cvo-backendd appends to it), replayed as cvo-backendd replays
// it at start-up (libcvo/store/replay.hpp: the door, the same decode, slam::Mapper), then the final global
// optimisation and the keyframes' local maps placed at its poses (mapping::Mapping).
//
// What is lost costs only itself: a damaged stretch of the file (skipped by the scan), a record
// that does not decode, repeats one let in before or cannot be applied (skipped, each named on
// the `problems` stream with its offset in the file and why). A keyframe whose frame the mapping
// refuses stays in the SLAM map, as in cvo-backendd, and is named as left out of the grid.
#include <cstddef>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "libcvo/config/config.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "libcvo/mapping/mapping.hpp"

namespace cvo::tools {

struct StoreMap {
  std::size_t records = 0;  // intact records in the store
  std::size_t damaged_stretches = 0, damaged_bytes = 0;
  std::size_t torn_bytes = 0;                     // a last record cut short (being written, or a crash)
  std::size_t skipped = 0;                        // intact records not used
  std::size_t keyframes = 0, local_graphs = 0;    // applied to the mapper
  std::vector<std::string> not_mapped{};          // keyframes applied that the mapping refused, and why
  std::size_t sessions = 0, sessions_placed = 0;  // placed: in the map frame
  std::vector<Eigen::Vector3d> trajectory{};      // map-frame keyframe positions of placed sessions, in order
  mapping::Mapping mapping;
};

/// Reads and replays `store`; throws io::InputError naming it when it cannot be read or is not a
/// keyframe store.
StoreMap map_store(const std::filesystem::path& store, const config::Config& config,
                   loop_closure::Vocabulary vocabulary, std::ostream& problems);

}  // namespace cvo::tools
