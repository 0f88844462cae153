// CVO_MAP as cvo-trackerd receives it (decide_map_correction: decode, convert, trust checks) and as
// cvo-log reads it (decode, from_message).
#include "cvo_lcm/map_t.hpp"
#include "fuzz/lcm_harness.hpp"
#include "libcvo/lcm/map_conversion.hpp"
#include "libcvo/lcm/map_decision.hpp"

namespace {
// The tracker's session: the first session of the seed maps (generate_seeds.cpp), so that mutations
// of a seed reach the checks behind "has an entry for this session".
constexpr std::int64_t kSession = 0x5e5510'0000'0001;
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cvo::fuzz::fuzz_message<cvo_lcm::map_t>(data, size, [](const cvo_lcm::map_t& message) {
    std::string error;
    (void)cvo::lcm::from_message(message, &error);
  });
  if (size > static_cast<std::size_t>(INT_MAX)) return 0;
  const cvo::lcm::OwnKeyframe own[] = {{0, {}}, {1, cvo::core::SE3::from_translation({0.1, 0, 0})}};
  cvo::fuzz::decide_as_trackers(kSession, own, [&](const auto& last, const auto& limits, const auto& context) {
    return cvo::lcm::decide_map_correction(data, static_cast<int>(size), kSession, last, limits, context);
  });
  return 0;
}
