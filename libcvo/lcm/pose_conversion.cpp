#include "libcvo/lcm/pose_conversion.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

namespace cvo::lcm {

cvo_lcm::pose3d_t to_message(const core::SE3& pose) {
  cvo_lcm::pose3d_t m{};
  for (int i = 0; i < 3; ++i) m.position[i] = pose.translation()[i];
  const auto& q = pose.rotation();
  m.orientation[0] = q.w();
  m.orientation[1] = q.x();
  m.orientation[2] = q.y();
  m.orientation[3] = q.z();
  return m;
}

std::optional<core::SE3> from_message(const cvo_lcm::pose3d_t& message, std::string* error) {
  const auto fail = [&](const std::string& what) -> std::optional<core::SE3> {
    if (error != nullptr) *error = "pose: " + what;
    return std::nullopt;
  };
  for (double v : message.position)
    if (!std::isfinite(v)) return fail("position is not finite");
  for (double v : message.orientation)
    if (!std::isfinite(v)) return fail("orientation is not finite");
  const Eigen::Quaterniond q(message.orientation[0], message.orientation[1], message.orientation[2],
                             message.orientation[3]);
  if (std::abs(q.norm() - 1.0) > 1e-6)
    return fail("orientation (w, x, y, z) is not a unit quaternion, norm " + std::to_string(q.norm()));
  return core::SE3(q, Eigen::Vector3d(message.position[0], message.position[1], message.position[2]));
}

void matrix6_to_message(const core::Matrix6d& matrix, double (&out)[36]) {
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) out[6 * r + c] = matrix(r, c);
}

core::Matrix6d matrix6_from_message(const double (&in)[36]) {
  core::Matrix6d m;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) m(r, c) = in[6 * r + c];
  return m;
}

std::int64_t to_utime(double seconds) { return std::llround(seconds * 1e6); }
double from_utime(std::int64_t utime) { return static_cast<double>(utime) / 1e6; }

bool is_finite(const cvo_lcm::pose3d_t& p) {
  const auto finite = [](double v) { return std::isfinite(v); };
  return std::all_of(std::begin(p.position), std::end(p.position), finite) &&
         std::all_of(std::begin(p.orientation), std::end(p.orientation), finite);
}

}  // namespace cvo::lcm
