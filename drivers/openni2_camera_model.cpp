#include "drivers/openni2_camera_model.hpp"

#include <PS1080.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>

#include "drivers/factory_intrinsics.hpp"
#include "drivers/frame_source.hpp"
#include "drivers/openni2_virtual/virtual_device.hpp"
#include "drivers/zero_plane.hpp"

namespace cvo::drivers {
namespace {

core::Intrinsics centred(double fx, double fy, int width, int height) {
  core::Intrinsics k;
  k.width = width;
  k.height = height;
  k.fx = fx;
  k.fy = fy;
  k.cx = width / 2.0;
  k.cy = height / 2.0;
  return k;
}

// A float field of view holds about 7 digits, a focal length to some 1e-5 px: rounded to 1e-4 px
// so that no digit is made up and a focal length given to 4 decimals comes back exactly.
double focal_of_fov(double size, float fov) { return std::round(size / 2.0 / std::tan(fov / 2.0) * 1e4) / 1e4; }

bool usable_fov(float fov) { return std::isfinite(fov) && fov > 0.0f && fov < 3.1f; }

std::optional<CameraModel> from_fov(const openni::VideoStream& s, const char* name, int width, int height) {
  const float h = s.getHorizontalFieldOfView(), v = s.getVerticalFieldOfView();
  if (!usable_fov(h) || !usable_fov(v)) return std::nullopt;
  return CameraModel{centred(focal_of_fov(width, h), focal_of_fov(height, v), width, height),
                     std::string("the ") + name + " stream's fields of view"};
}

// PS1080 stores ZPD as an unsigned 64-bit integer and ZPPS as a double; a recording hands back the
// bytes it recorded (OpenNI 1's integer properties are 64-bit too), so both are read by their size.
std::optional<double> number_property(const openni::VideoStream& s, int id, bool integer) {
  unsigned char bytes[8] = {};
  int size = sizeof(bytes);
  if (!s.isValid() || s.getProperty(id, bytes, &size) != openni::STATUS_OK) return std::nullopt;
  if (integer) {
    std::uint64_t v = 0;
    std::memcpy(&v, bytes, static_cast<std::size_t>(std::clamp(size, 0, 8)));
    if (size == 4) v &= 0xFFFFFFFFu;
    return static_cast<double>(v);
  }
  if (size == 8) {
    double v = 0;
    std::memcpy(&v, bytes, 8);
    return v;
  }
  if (size == 4) {
    float v = 0;
    std::memcpy(&v, bytes, 4);
    return v;
  }
  return std::nullopt;
}

std::optional<CameraModel> from_zero_plane(const openni::VideoStream& s, const char* name, int width, int height) {
  const auto zpd = number_property(s, XN_STREAM_PROPERTY_ZERO_PLANE_DISTANCE, true);
  const auto zpps = number_property(s, XN_STREAM_PROPERTY_ZERO_PLANE_PIXEL_SIZE, false);
  if (!zpd || !zpps) return std::nullopt;
  const double f = zero_plane_focal_px(*zpd, *zpps, width);
  if (!(f > 0) || !std::isfinite(f)) return std::nullopt;
  char text[160];
  std::snprintf(text, sizeof(text), "the %s stream's zero-plane distance %g mm and pixel size %g mm (PS1080)", name,
                *zpd, *zpps);
  return CameraModel{centred(f, f, width, height), text};
}

std::optional<CameraModel> from_factory(const openni::Device& device, int width, int height) {
  const auto& info = device.getDeviceInfo();
  const auto camera = factory_camera(info.getUsbVendorId(), info.getUsbProductId(), info.getName());
  if (!camera) return std::nullopt;
  const double f = camera->focal_px_at_640 * width / 640.0;
  return CameraModel{centred(f, f, width, height), "ASSUMED: the published focal length of a " +
                                                       std::string(camera->name) + ", " + std::string(camera->source)};
}

std::optional<CameraModel> from_device(const openni::VideoStream& colour, int width, int height) {
  namespace virt = virtual_device;
  virt::StreamIntrinsics own;
  if (!colour.isPropertySupported(virt::kIntrinsicsProperty) ||
      colour.getProperty(virt::kIntrinsicsProperty, &own) != openni::STATUS_OK)
    return std::nullopt;
  core::Intrinsics k = centred(own.fx, own.fy, width, height);
  k.cx = own.cx;
  k.cy = own.cy;
  std::copy(std::begin(own.distortion), std::end(own.distortion), k.distortion.begin());
  k.readout_s = own.readout_s;
  return CameraModel{k, "the device's own camera model"};
}

}  // namespace

CameraModel openni2_camera_model(const openni::Device& device, const openni::VideoStream& depth,
                                 const openni::VideoStream& colour, int width, int height,
                                 const std::optional<core::Intrinsics>& given, const std::string& spec) {
  if (given) return CameraModel{*given, "the camera file (the camera key)"};
  if (auto m = from_device(colour, width, height)) return *m;
  if (auto m = from_fov(colour, "colour", width, height)) return *m;
  if (auto m = from_fov(depth, "depth", width, height)) return *m;
  if (auto m = from_zero_plane(depth, "depth", width, height)) return *m;
  if (auto m = from_zero_plane(colour, "colour", width, height)) return *m;
  if (auto m = from_factory(device, width, height)) return *m;
  throw SourceError(spec, "no intrinsics: neither stream has a field of view or PS1080 zero-plane values, and '" +
                              std::string(device.getDeviceInfo().getName()) +
                              "' is no camera of known focal length; give the camera's intrinsics in a camera file "
                              "(--set camera=FILE.yaml)");
}

}  // namespace cvo::drivers
