#pragma once
// Canned smooth hand-held camera paths through the simulated room (world z up, see scene.hpp),
// as closed-form functions of time so ground truth is exact at any timestamp. All are periodic
// and stay >= 0.5 m from every surface (so every visible point is beyond a sensor's minimum
// range); speeds stay below 0.5 m/s and, except rpy's and fast_rpy's, 60 deg/s.
//
//   orbit: the optical centre runs once round a 0.5 m circle at 1.3 m (+-0.1 m bob) while the
//          camera looks outwards and ~23 degrees down, so it pans a full 360 degrees over walls, floor
//          and furniture; pitch and roll wobble a little.
//          Period 12 s; pose(12 s) == pose(0), for loop-closure tests.
//   sweep: a 1.7 m diagonal translation with a 40 degree pan towards the furnished +y side, out
//          and back with cosine easing. Period 12 s.
//   wall:  2 m in front of the y = +2.5 wall (the textured_wall plane), drifting on a Lissajous
//          curve (+-0.35 m sideways, +-0.2 m in depth, +-0.12 m up) while looking at a wandering
//          point of the wall and rolling +-5 degrees. Period 10 s.
//   rpy:   TUM fr1/rpy's motion: the camera stays near (0, -0.8, 1.3) m (+-2 cm) looking at the
//          furnished +y side and turns fast about all three axes (yaw +-20 degrees at 5/12 Hz, pitch
//          +-12 at 7/12 Hz, roll +-15 at 1/2 Hz; up to ~85 deg/s), the motion where a tracker's
//          rotation, not its translation, is tested. Period 12 s.
//   fast_rpy: rpy played k = 2.8 times faster (pose(t) = rpy(k t), period 12 / k = 4.29 s): the
//          same turns at a peak angular rate of 1.5 times fr1/rpy's. fr1/rpy's peak, measured on
//          its ground truth (100 Hz motion capture) over the span of frames 0-499, as the rotation
//          angle between the poses 0.05 s before and after each sample divided by 0.1 s (a centred
//          0.1 s window, three frames at 30 Hz, which smooths the capture's jitter): 158.1 deg/s
//          (at 3.8 s after frame 0; 165 deg/s over 0.067 s, 138 over 0.2 s). rpy's peak by the same
//          measure is 87.4 deg/s, so k = 1.5 x 158.1 / 87.4 = 2.80 gives 237 deg/s (about 8 degrees
//          between frames at 30 Hz; 246 deg/s instantaneous). Render it with a rolling shutter:
//          --rolling-shutter 0.03, the readout a Kinect v1's colour camera (rolling-shutter CMOS,
//          rows read continuously at 30 Hz) takes, nearly the whole 33 ms frame; at 237 deg/s the
//          last row then sees the scene 7 degrees turned from the first.
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "libcvo/core/se3.hpp"
#include "libcvo/core/trajectory.hpp"

namespace cvo::sim {

enum class PathKind { orbit, sweep, wall, rpy, fast_rpy };

/// fr1/rpy's peak angular rate (deg/s) over frames 0-499, measured as the header says, and
/// fast_rpy's time scale relative to rpy.
inline constexpr double kFr1RpyPeakRateDegS = 158.1;
inline constexpr double kFastRpyTimeScale = 2.8;

std::string_view path_name(PathKind kind);
std::optional<PathKind> parse_path_kind(std::string_view name);
std::vector<std::string> path_names();

/// Seconds after which the path repeats.
double path_period(PathKind kind);

/// T_world_camera of a camera at `eye` whose optical axis (z) points at `target`, with the image
/// x axis horizontal (world z is up) and then rolled by `roll` radians about the optical axis.
/// `target - eye` must not be vertical.
core::SE3 look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, double roll = 0.0);

/// Pose T_world_camera at `seconds` after the start of the path.
core::SE3 path_pose(PathKind kind, double seconds);

/// `frames` poses stamped start_time + i / rate_hz, each stamp rounded to the microsecond (what
/// TUM file names hold) and the pose taken at exactly that stamp.
core::Trajectory sample_path(PathKind kind, std::size_t frames, double start_time = 1000.0, double rate_hz = 30.0);

}  // namespace cvo::sim
