// CVO_MAP_CORRECTION as cvo-trackerd receives it (decide_session_correction: decode, the session
// first, checks, the one decision CVO_MAP goes through too) and as the back end's conversion reads
// it back (decode, from_message).
#include "cvo_lcm/map_correction_t.hpp"
#include "fuzz/lcm_harness.hpp"
#include "libcvo/lcm/map_correction_conversion.hpp"
#include "libcvo/lcm/map_decision.hpp"

namespace {
// The tracker's session: the seed correction's (generate_seeds.cpp: the second session of the
// sample map), so that mutations of a seed reach the checks behind "this session's".
constexpr std::int64_t kSession = -0x2222'3333'4444'5555;
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cvo::fuzz::fuzz_message<cvo_lcm::map_correction_t>(data, size, [](const cvo_lcm::map_correction_t& message) {
    std::string error;
    (void)cvo::lcm::from_message(message, &error);
  });
  if (size > static_cast<std::size_t>(INT_MAX)) return 0;
  const cvo::lcm::OwnKeyframe own[] = {{4, {}}, {5, cvo::core::SE3::from_translation({0.1, 0, 0})}};
  cvo::fuzz::decide_as_trackers(kSession, own, [&](const auto& last, const auto& limits, const auto& context) {
    return cvo::lcm::decide_session_correction(data, static_cast<int>(size), kSession, last, limits, context);
  });
  return 0;
}
