#pragma once
// The LCM message harnesses: the bytes go through lcm::decode<T> exactly as a daemon receives them,
// then through the type's conversion, after the verify step every receiver runs (auth_harness.hpp). Refusals are
// nullopt by contract (decode.hpp), so the only checks here are the ones decoding promises beyond "no crash".
#include <climits>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "fuzz/auth_harness.hpp"
#include "fuzz/harness.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/map_decision.hpp"

namespace cvo::fuzz {

template <class T, class Convert>
void fuzz_message(const std::uint8_t* data, std::size_t size, Convert&& convert) {
  if (size > static_cast<std::size_t>(INT_MAX)) return;  // LCM sizes are int; the transport never delivers more
  // A receiver with a key verifies the raw bytes first (the seeds are signed with the fuzzing key);
  // decoding is fuzzed whatever the verdict, as a receiver on an open bus decodes everything.
  (void)verify_raw(data, size);
  std::string error;
  const auto message = lcm::decode<T>(data, static_cast<int>(size), &error);
  if (!message) return;
  // What decode accepts, encode must turn into bytes that decode accepts again: otherwise a
  // back end storing a message (keyframe store) could not read it back.
  const auto again = lcm::encode(*message);
  if (!lcm::decode<T>(again.data(), static_cast<int>(again.size()), &error)) {
    fail(std::string("re-encoded ") + T::getTypeName() + " does not decode: " + error);
  }
  convert(*message);
}

// A map message as a tracker of `session` decides on it (libcvo/lcm/map_decision.hpp), in both
// states that reach different checks: one that applied nothing yet (a first placement: the loop
// check) and one placed (the jump bound); `own` are keyframes of its own that the seed's loops name.
template <class Decide>
void decide_as_trackers(std::int64_t session, std::span<const lcm::OwnKeyframe> own, Decide&& decide) {
  lcm::AppliedCorrection placed;
  placed.epoch = 0;
  placed.revision = 1;
  placed.session = session;
  placed.placed = true;
  for (const lcm::AppliedCorrection& last : {lcm::AppliedCorrection{}, placed})
    (void)decide(last, lcm::CorrectionLimits{}, lcm::MapContext{0, 0, own});
}

}  // namespace cvo::fuzz
