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
  // Both a tracker that applied nothing yet and one with a placed correction: the plausibility
  // check (a jump from the last correction) only runs in the second.
  cvo::lcm::AppliedCorrection placed;
  placed.epoch = 0;
  placed.revision = 1;
  placed.session = kSession;
  placed.placed = true;
  // Keyframes of its own, so that a placement's loop check runs too.
  const cvo::lcm::OwnKeyframe own[] = {{0, {}}, {1, cvo::core::SE3::from_translation({0.1, 0, 0})}};
  for (const cvo::lcm::AppliedCorrection& last : {cvo::lcm::AppliedCorrection{}, placed}) {
    (void)cvo::lcm::decide_map_correction(data, static_cast<int>(size), kSession, last, cvo::lcm::CorrectionLimits{},
                                          cvo::lcm::MapContext{0, 0, own});
  }
  return 0;
}
