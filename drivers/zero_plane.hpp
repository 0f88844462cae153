#pragma once
// The focal length a PrimeSense PS1080 (Kinect v1, Xtion, Carmine) gives through its zero-plane
// values instead of a field of view (OpenNI 1 recordings, SensorKinect): the reference plane's
// distance ZPD (mm) and the size of one pixel on it, ZPPS (mm), for the 1280-pixel-wide SXGA
// sensor. PS1080's own driver derives the field of view from them as
// hfov = 2 atan(ZPPS * 1280 / 2 / ZPD) (OpenNI2 Source/Drivers/PS1080/Sensor/XnSensorDepthStream.cpp),
// so an image `width` pixels wide has f = ZPD / ZPPS * width / 1280 (libfreenect's registration
// uses the same: ZPPS doubled for VGA). A Kinect v1's 120 mm and 0.1042 mm give 575.8 px at 640x480.
namespace cvo::drivers {

inline constexpr double kZeroPlaneReferenceWidth = 1280.0;  // SXGA, the sensor's full width

/// Pixels; 0 when either value is not positive (a stream without them).
inline double zero_plane_focal_px(double zpd_mm, double zpps_mm, int width) {
  if (!(zpd_mm > 0) || !(zpps_mm > 0) || width <= 0) return 0.0;
  return zpd_mm / zpps_mm * width / kZeroPlaneReferenceWidth;
}

}  // namespace cvo::drivers
