#pragma once
// The description of one emulated camera, as the environment gives it (CVO_V4L2_EMULATOR,
// CVO_V4L2_EMULATOR_2 ... _9): comma-separated key=value pairs, e.g.
//   colour=/dev/video90,depth=/dev/video91,tum=/data/fr1_xyz,colour_format=mjpeg,depth_fps=15
// Every key but colour, depth and tum has a default: a RealSense D435 as uvcvideo shows it
// (YUYV 640x480 at 30 Hz, Z16 848x480 at 30 Hz in millimetres). drivers/README.md lists the keys.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace cvo::drivers::v4l2_emulator {

struct FrameSize {
  std::uint32_t width = 0, height = 0;
  friend bool operator==(const FrameSize&, const FrameSize&) = default;
};

/// One capture node: what ENUM_FMT, ENUM_FRAMESIZES and ENUM_FRAMEINTERVALS list, the first of
/// each being what the node streams until told otherwise.
struct NodeConfig {
  std::string path;                    // e.g. /dev/video90; need not exist on disk
  std::vector<std::uint32_t> formats;  // V4L2 fourccs
  std::vector<FrameSize> sizes;        // every format at every size, as many UVC cameras do
  std::vector<std::uint32_t> rates;    // frames per second, each size at each rate
};

enum class AtEnd { kLoop, kUnplug };

struct CameraConfig {
  NodeConfig colour, depth;
  std::filesystem::path tum;            // the recording whose frames the camera "sees"
  double depth_units_per_metre = 1000;  // the Z16 unit (1000: millimetres, as a RealSense)
  double play_fps = 0;                  // recording entries per second; 0: the colour node's first rate
  std::uint64_t unplug_after = 0;       // colour frames before the (one) unplug; 0: never
  double replug_after_s = 1.0;          // the nodes are back this long after the unplug; < 0: never
  AtEnd at_end = AtEnd::kLoop;          // at the end of the recording: play it again, or unplug for good
  bool lossless = false;                // wait for a queued buffer instead of dropping the frame
  std::uint64_t error_every = 0;        // every Nth colour frame carries V4L2_BUF_FLAG_ERROR; 0: none
  std::string card = "Intel(R) RealSense(TM) Depth Ca";  // VIDIOC_QUERYCAP's (truncated as uvcvideo's)
};

/// Parses one camera's description. Throws std::invalid_argument naming the bad key or value.
CameraConfig parse_camera_config(std::string_view text);

/// The cameras the environment describes; a bad description is reported on stderr and skipped
/// (the process itself must go on: the emulator is loaded into every program of a test).
std::vector<CameraConfig> cameras_from_environment();

}  // namespace cvo::drivers::v4l2_emulator
