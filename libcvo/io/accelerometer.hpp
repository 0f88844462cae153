#pragma once
// TUM RGB-D's accelerometer.txt ("timestamp ax ay az", m/s², the Kinect's own accelerometer):
// which way is up at a frame's time, for the map (libcvo/mapping/up.hpp).
//
// The Kinect v1's accelerometer axes are its camera's rotated half a turn about the optical axis
// (x left, y up, z forward, libfreenect's convention): the camera-frame specific force is
// (-ax, -ay, az). At rest the specific force is gravity's reaction and points up.
#include <filesystem>
#include <optional>
#include <vector>

#include <Eigen/Core>

namespace cvo::io {

struct AccelerometerSample {
  double timestamp = 0;
  Eigen::Vector3d specific_force = Eigen::Vector3d::Zero();  // camera frame, m/s²
};

/// Every sample, in file order; throws InputError naming file and line on a malformed line.
std::vector<AccelerometerSample> read_tum_accelerometer(const std::filesystem::path& file);

/// The mean specific force over [t - half_window, t + half_window] (the camera moves: a mean over
/// a tenth of a second leaves gravity and little of the motion); nullopt when no sample lies there.
std::optional<Eigen::Vector3d> mean_specific_force(const std::vector<AccelerometerSample>& samples, double t,
                                                   double half_window = 0.05);

}  // namespace cvo::io
