#include "libcvo/lcm/keyframe_conversion.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "libcvo/core/session.hpp"
#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {
namespace {
std::nullopt_t fail(std::string* error, const std::string& what) {
  if (error != nullptr) *error = "cvo_lcm.keyframe_t: " + what;
  return std::nullopt;
}
}  // namespace

RgbdEncoding keyframe_encoding(ColourEncoding colour) {
  RgbdEncoding encoding;
  encoding.colour = colour;
  encoding.depth = DepthEncoding::kPng;
  encoding.png_compression = 4;
  return encoding;
}

std::optional<cvo_lcm::keyframe_t> to_message(const Keyframe& keyframe, const RgbdEncoding& encoding,
                                              std::string* error) {
  // The images travel exactly as in CVO_RGBD: encode them as a frame message and move the bytes.
  auto frame = to_message(keyframe.frame, encoding, error);
  if (!frame) return std::nullopt;
  cvo_lcm::keyframe_t m{};
  m.version = cvo_lcm::keyframe_t::SCHEMA_VERSION;
  m.session = keyframe.session;
  m.id = keyframe.id;
  m.frame_index = frame->frame_index;
  m.utime = frame->utime;
  m.pose = to_message(keyframe.pose);
  m.fx = frame->fx;
  m.fy = frame->fy;
  m.cx = frame->cx;
  m.cy = frame->cy;
  m.width = frame->width;
  m.height = frame->height;
  m.depth_scale = frame->depth_scale;
  std::copy(std::begin(frame->distortion), std::end(frame->distortion), m.distortion);
  m.readout_s = frame->readout_s;
  m.colour_encoding = frame->colour_encoding;
  m.depth_encoding = frame->depth_encoding;
  const auto& cloud = keyframe.cloud;
  m.num_points = static_cast<std::int32_t>(cloud.size());
  m.xyz.resize(cloud.size());
  m.labels.resize(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    m.xyz[i] = {cloud.x()[i], cloud.y()[i], cloud.z()[i]};
    m.labels[i].resize(registration::kFeatureDim);  // lcm-gen makes the fixed inner dimension a vector too
    for (std::size_t c = 0; c < registration::kFeatureDim; ++c) m.labels[i][c] = cloud.feature_channel(c)[i];
  }
  m.colour = std::move(frame->colour);
  m.depth = std::move(frame->depth);
  m.colour_size = static_cast<std::int32_t>(m.colour.size());
  m.depth_size = static_cast<std::int32_t>(m.depth.size());
  m.robot = keyframe.robot;
  return m;
}

std::optional<Keyframe> from_message(const cvo_lcm::keyframe_t& m, std::string* error, ContentFailure* failure) {
  const auto kind = [&](ContentFailure f) {
    if (failure != nullptr) *failure = f;
  };
  kind(ContentFailure::kContent);
  if (m.version != cvo_lcm::keyframe_t::SCHEMA_VERSION)
    return fail(error, "schema version " + std::to_string(m.version));
  if (m.id < 0) return fail(error, "negative keyframe id " + std::to_string(m.id));
  if (auto why = core::robot_name_error(m.robot); !why.empty()) return fail(error, why);
  std::string why;
  const auto pose = from_message(m.pose, &why);
  if (!pose) {
    if (!is_finite(m.pose)) kind(ContentFailure::kNotFinite);
    return fail(error, "pose: " + why);
  }

  cvo_lcm::rgbd_frame_t frame{};
  frame.version = cvo_lcm::rgbd_frame_t::SCHEMA_VERSION;
  frame.utime = m.utime;
  frame.depth_utime = m.utime;
  frame.frame_index = m.frame_index;
  frame.fx = m.fx;
  frame.fy = m.fy;
  frame.cx = m.cx;
  frame.cy = m.cy;
  frame.width = m.width;
  frame.height = m.height;
  frame.depth_scale = m.depth_scale;
  std::copy(std::begin(m.distortion), std::end(m.distortion), frame.distortion);
  frame.readout_s = m.readout_s;
  frame.colour_encoding = m.colour_encoding;
  frame.depth_encoding = m.depth_encoding;
  frame.colour = m.colour;
  frame.depth = m.depth;
  frame.colour_size = m.colour_size;
  frame.depth_size = m.depth_size;
  ContentFailure image_failure = ContentFailure::kContent;
  auto images = from_message(frame, &why, &image_failure);
  if (!images) {
    kind(image_failure);  // an image that is not its declared format, or a bomb, by its own kind
    return fail(error, why);
  }

  // A decoded message has these sizes (decode.hpp checks the counts); one built in memory may not.
  const auto n = static_cast<std::size_t>(std::max(m.num_points, 0));
  if (m.num_points < 0 || m.xyz.size() != n || m.labels.size() != n)
    return fail(error, "num_points " + std::to_string(m.num_points) + " does not match the point arrays");
  for (std::size_t i = 0; i < n; ++i)
    if (m.xyz[i].size() != 3 || m.labels[i].size() != registration::kFeatureDim)
      return fail(error, "point " + std::to_string(i) + " has the wrong number of coordinates or label channels");

  Keyframe k{
      m.session, m.id, std::move(*images), *pose, registration::PointCloud(static_cast<std::size_t>(m.num_points)),
      m.robot};
  for (std::int32_t i = 0; i < m.num_points; ++i) {
    const auto& p = m.xyz[static_cast<std::size_t>(i)];
    registration::Feature f{};
    bool finite = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
    for (std::size_t c = 0; c < registration::kFeatureDim; ++c) {
      f[c] = m.labels[static_cast<std::size_t>(i)][c];
      finite = finite && std::isfinite(f[c]);
    }
    if (!finite) {
      kind(ContentFailure::kNotFinite);
      return fail(error, "point " + std::to_string(i) + " is not finite");
    }
    k.cloud.push_back({p[0], p[1], p[2]}, f);
  }
  return k;
}

}  // namespace cvo::lcm
