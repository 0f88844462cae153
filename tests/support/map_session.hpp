#pragma once
// A slam::MapSession entry from its first six fields, the rest at their defaults (the state
// follows `placed`): what tests that build maps by hand write.
#include "libcvo/slam/mapper.hpp"

namespace cvo::test {

inline slam::MapSession map_session(core::SessionId session, bool placed, core::SessionId piece, std::size_t keyframes,
                                    std::int64_t joined_at_keyframe, const core::SE3& correction) {
  slam::MapSession s;
  s.session = session;
  s.placed = placed;
  s.piece = piece;
  s.keyframes = keyframes;
  s.joined_at_keyframe = joined_at_keyframe;
  s.correction = correction;
  s.state = placed ? core::LocalizationState::kLocalized : core::LocalizationState::kLocalizing;
  return s;
}

}  // namespace cvo::test
