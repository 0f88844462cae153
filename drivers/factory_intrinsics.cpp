#include "drivers/factory_intrinsics.hpp"

#include <array>

namespace cvo::drivers {
namespace {

struct Entry {
  std::uint16_t vendor, product;
  std::string_view word;  // in the device name
  FactoryCamera camera;
};

// The depth camera's focal length: with depth registered to colour, what OpenNI's own
// depth-to-world conversion uses for both.
constexpr std::string_view kKinectSource =
    "ZPD 120 mm / ZPPS 0.1042 mm x 2 (libfreenect src/registration.c; ROS openni_camera's default depth "
    "focal length 575.8157)";
constexpr std::string_view kPrimeSenseSource =
    "ZPD 120 mm / ZPPS 0.1052 mm x 2 (ROS openni2_camera's PrimeSense default, 570.3422)";
constexpr std::string_view kAstraSource = "Orbbec Astra datasheet: 60 deg horizontal field of view";

constexpr std::array<Entry, 6> kTable{{
    {0x045e, 0x02ae, "Kinect", {"Microsoft Kinect v1", 575.8157, kKinectSource}},
    {0x045e, 0x02bf, "Kinect", {"Microsoft Kinect v1", 575.8157, kKinectSource}},
    {0x1d27, 0x0600, "Xtion", {"PrimeSense PS1080 (Xtion PRO, Carmine 1.08)", 570.3422, kPrimeSenseSource}},
    {0x1d27, 0x0601, "Carmine", {"PrimeSense PS1080 (Xtion PRO LIVE, Carmine 1.09)", 570.3422, kPrimeSenseSource}},
    {0x1d27, 0x0601, "PrimeSense", {"PrimeSense PS1080", 570.3422, kPrimeSenseSource}},
    {0x2bc5, 0x0401, "Astra", {"Orbbec Astra", 554.2563, kAstraSource}},  // 320 / tan(30 deg)
}};

}  // namespace

std::optional<FactoryCamera> factory_camera(std::uint16_t usb_vendor, std::uint16_t usb_product,
                                            std::string_view device_name) {
  for (const auto& e : kTable)
    if (e.vendor == usb_vendor && e.product == usb_product) return e.camera;
  for (const auto& e : kTable)
    if (device_name.find(e.word) != std::string_view::npos) return e.camera;
  return std::nullopt;
}

}  // namespace cvo::drivers
