#pragma once
// Renders a camera path into a folder laid out like a TUM RGB-D sequence, so every dataset reader,
// tool and evaluation script runs on synthetic data unchanged:
//   rgb/STAMP.png      8-bit BGR colour            rgb.txt          "stamp rgb/STAMP.png"
//   depth/STAMP.png    16-bit depth, depth_scale   depth.txt        "stamp depth/STAMP.png"
//   groundtruth.txt    T_world_camera per frame (TUM trajectory format, io::write_tum_trajectory)
//   camera.yaml        fx fy cx cy width height depth_scale
// Frame i is stamped start_time + i / rate_hz rounded to the microsecond (STAMP has 6 decimals);
// depth shares the colour stamp. The textures come from `seed`, the depth noise of frame i from
// hash(seed, i): the same options give byte-identical files. The sensor effects (sensor.hpp) apply
// per frame, the auto-exposure loop across frames in order; the ground truth is the pose at each
// frame's stamp (the middle row's, mid-exposure).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "libcvo/core/camera.hpp"
#include "libcvo/sim/camera_path.hpp"
#include "libcvo/sim/render.hpp"
#include "libcvo/sim/scene.hpp"
#include "libcvo/sim/sensor.hpp"

namespace cvo::sim {

struct SequenceOptions {
  SceneKind scene = SceneKind::textured_room;
  PathKind path = PathKind::orbit;
  std::size_t frames = 360;
  std::uint64_t seed = 0;
  NoiseOptions noise;
  SensorOptions sensor;
  RenderOptions render;
  core::Intrinsics intrinsics{525.0, 525.0, 319.5, 239.5, 640, 480, 5000.0};  // the "synthetic" preset
  double start_time = 1000.0;
  double rate_hz = 30.0;
};

struct SequenceSummary {
  std::size_t frames = 0;
  double duration_s = 0;            // last stamp - first stamp
  double path_length_m = 0;         // sum of translation steps
  double valid_depth_fraction = 0;  // over all pixels of all frames
};

/// Writes the sequence into `dir` (created if needed; files of the same names are overwritten).
/// Throws io::InputError naming the path when something cannot be created or written.
SequenceSummary write_sequence(const std::filesystem::path& dir, const SequenceOptions& options);

/// The TUM file-name form of a stamp: fixed, 6 decimals.
std::string stamp_string(double seconds);

}  // namespace cvo::sim
