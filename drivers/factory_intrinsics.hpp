#pragma once
// The published focal lengths of OpenNI2 cameras, for a device or recording that carries neither a
// field of view nor zero-plane values: a last guess before refusing, said in the log as an
// assumption (each unit differs from its model's value by a few percent; a calibration is better).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace cvo::drivers {

struct FactoryCamera {
  std::string_view name;
  double focal_px_at_640 = 0;  // a 640-pixel-wide image; scaled with the width, square pixels
  std::string_view source;     // where the value is published
};

/// The camera by its USB ids, else by a word of its OpenNI device name ("Kinect", "Xtion",
/// "Carmine", "PrimeSense", "Astra"); nullopt when none is known.
std::optional<FactoryCamera> factory_camera(std::uint16_t usb_vendor, std::uint16_t usb_product,
                                            std::string_view device_name);

}  // namespace cvo::drivers
