#pragma once
// Small TUM folders made from the embedded sample, for tests that need to damage a frame, change
// the timestamps, or make a folder appear later.
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <vector>

#include "libcvo/io/tum_dataset.hpp"

namespace cvo::test {

inline const std::filesystem::path kSample = std::filesystem::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";

/// Copies `count` frames of the sample from frame `first` into `dir` (created; name it fr1_... so
/// the camera preset is found), with its ground truth. Frame i is stamped timestamps[i] when given,
/// else its recorded time.
inline void write_tum_copy(const std::filesystem::path& dir, std::size_t count,
                           const std::optional<std::vector<double>>& timestamps = std::nullopt, std::size_t first = 0) {
  namespace fs = std::filesystem;
  const auto sample = io::TumSequence::open(kSample);
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  std::ofstream rgb(dir / "rgb.txt"), depth(dir / "depth.txt");
  rgb << std::fixed << std::setprecision(6);
  depth << std::fixed << std::setprecision(6);
  fs::copy_file(kSample / "groundtruth.txt", dir / "groundtruth.txt", fs::copy_options::overwrite_existing);
  for (std::size_t i = 0; i < count; ++i) {
    const auto& f = sample.files().at(first + i);
    const auto rgb_name = fs::path("rgb") / f.rgb.filename();
    const auto depth_name = fs::path("depth") / f.depth.filename();
    fs::copy_file(f.rgb, dir / rgb_name, fs::copy_options::overwrite_existing);
    fs::copy_file(f.depth, dir / depth_name, fs::copy_options::overwrite_existing);
    const double t = timestamps ? timestamps->at(i) : f.timestamp;
    const double td = timestamps ? timestamps->at(i) : f.depth_timestamp;
    rgb << t << " " << rgb_name.string() << "\n";
    depth << td << " " << depth_name.string() << "\n";
  }
}

}  // namespace cvo::test
