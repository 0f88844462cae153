#pragma once
// bench/map_scale's room run: one room revisited without pause, as issue #27 measured it. A real
// sequence is played forward, then backward, over and over (a TUM folder of its own images,
// 30 Hz timestamps) through the real cvo-trackerd, at 30 Hz (or unpaced) and dropping no frame, into the real
// cvo-backendd on the private bus. Every minute a row: frames tracked, keyframes the tracker sent,
// keyframes in the map, the back end's store bytes and RSS, and the records waiting for it (its
// CVO_STATUS queue_depth). At the end the back end is stopped as systemd stops it (SIGTERM), and
// the stop is timed.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace cvo::bench {

/// A TUM folder `dir` listing the associated frames of `sequence` forward, backward, forward, ...
/// `frames` in all, 1/30 s apart; the images stay where they are. The camera is the sequence's
/// (its camera.yaml copied, else the preset its folder name implies, kept in `dir`'s name).
/// Returns `dir`.
std::filesystem::path write_back_and_forth(const std::filesystem::path& sequence, const std::filesystem::path& dir,
                                           std::size_t frames);

struct RoomRun {
  std::filesystem::path sequence;
  double minutes = 0;  // of frames at 30 Hz
  bool paced = true;   // false: as fast as the tracker goes (issue #27's own measurement)
  std::vector<std::string> settings;
};

/// Prints the table; returns the records still waiting for the back end when the tracker was done
/// (0 when it kept up) plus 1 when its stop did not end cleanly within 30 s.
std::size_t room(const RoomRun& run, const std::filesystem::path& scratch);

}  // namespace cvo::bench
