#pragma once
// A keyframe <-> cvo_lcm::keyframe_t (channel CVO_KEYFRAME): its images (for ORB and loop
// detection in the back end), its pose and its CVO point cloud (for the loop's CVO refinement and
// the α test). The images use rgbd_frame_t's encodings (rgbd_conversion.hpp).
#include <cstdint>
#include <optional>
#include <string>

#include "cvo_lcm/keyframe_t.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"
#include "libcvo/registration/point_cloud.hpp"

namespace cvo::lcm {

struct Keyframe {
  std::int64_t session = 0;           // the tracker session (proto/pose_t.lcm)
  std::int64_t id = 0;                // increasing within the session
  core::RgbdFrame frame;              // the frame it was made from (index, stamps, images, intrinsics)
  core::SE3 pose;                     // T_odom_camera
  registration::PointCloud cloud;     // in the keyframe's camera frame
  std::string robot = std::string();  // the tracker's robot (proto/pose_t.lcm, core::is_robot_name)
};

/// How a keyframe's images are encoded: colour as given, depth PNG at zlib level 4 with deflate's
/// full search. A keyframe goes out about once a second, to be sent over a network (and resent,
/// and stored), where a frame goes out every 33 ms: 3 ms more in the publisher for a depth image
/// 7 % smaller (bench/keyframe_link_bytes).
RgbdEncoding keyframe_encoding(ColourEncoding colour);

/// Fails (nullopt, *error) as rgbd_conversion's to_message does.
std::optional<cvo_lcm::keyframe_t> to_message(const Keyframe& keyframe, const RgbdEncoding& encoding,
                                              std::string* error);

/// Fails on another schema version, a robot name that is none (core::is_robot_name), a bad pose, non-finite points, or
/// images that do not decode; *failure (when given) says which kind (not finite: a NaN or infinite pose or point; image
/// format or image size: an image refused before decoding, as rgbd_conversion's from_message does).
std::optional<Keyframe> from_message(const cvo_lcm::keyframe_t& message, std::string* error,
                                     ContentFailure* failure = nullptr);

}  // namespace cvo::lcm
