#include "libcvo/lcm/map_correction_conversion.hpp"

#include <algorithm>

#include "libcvo/lcm/map_check.hpp"
#include "libcvo/lcm/map_conversion.hpp"
#include "libcvo/lcm/pose_conversion.hpp"

namespace cvo::lcm {

cvo_lcm::map_correction_t to_message(const slam::SessionCorrection& c, std::int64_t utime, std::int64_t epoch,
                                     std::int64_t acknowledged) {
  cvo_lcm::map_correction_t m{};
  m.version = cvo_lcm::map_correction_t::SCHEMA_VERSION;
  m.utime = utime;
  m.epoch = epoch;
  m.revision = static_cast<std::int64_t>(c.revision);
  m.acknowledged = acknowledged;
  m.session = to_message(c.session);
  const std::size_t n = std::min<std::size_t>(c.loops.size(), cvo_lcm::map_correction_t::MAX_LOOPS);
  for (std::size_t i = 0; i < n; ++i) {
    const slam::SessionLoop& l = c.loops[i];
    m.loops.push_back(
        {l.keyframe, l.other_session, l.other_keyframe, to_message(l.measurement), to_message(l.other_pose)});
  }
  m.num_loops = static_cast<std::int32_t>(m.loops.size());
  m.robot = c.session.robot;
  return m;
}

std::optional<slam::SessionCorrection> from_message(const cvo_lcm::map_correction_t& m, std::string* error) {
  if (std::string why = correction_error(m); !why.empty()) {
    if (error != nullptr) *error = std::move(why);
    return std::nullopt;
  }
  // Every pose below converts: correction_error checked each.
  slam::SessionCorrection c{static_cast<std::uint64_t>(m.revision), from_checked_message(m.session), {}};
  c.session.robot = m.robot;
  for (const auto& l : m.loops)
    c.loops.push_back({l.keyframe, l.other_session, l.other_keyframe, *from_message(l.measurement, nullptr),
                       *from_message(l.other_pose, nullptr)});
  return c;
}

}  // namespace cvo::lcm
