// A keyframe store's merge record, and its settled record, (daemon/backendd/merge_record.hpp) as
// cvo-backendd's start-up and cvo-map decode them: any bytes are refused with a reason, or decode to a merge whose
// encoding decodes again to the same encoding (what a restarted store replays is what was stored).
#include <string>

#include "daemon/backendd/merge_record.hpp"
#include "fuzz/harness.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cvo::fuzz::expect_refusal_or_success([&] {
    std::string error;
    if (const auto settled = cvo::daemon::backendd::decode_settled(data, size, &error)) {  // the other record here
      const auto bytes = cvo::daemon::backendd::encode_settled(*settled);
      const auto again = cvo::daemon::backendd::decode_settled(bytes.data(), bytes.size(), &error);
      if (!again || cvo::daemon::backendd::encode_settled(*again) != bytes)
        cvo::fuzz::fail("a decoded settled record does not encode to the same bytes twice");
    } else if (error.empty()) {
      cvo::fuzz::fail("a settled record refused without a reason");
    }
    if (const auto tally = cvo::daemon::backendd::decode_tally(data, size, &error)) {
      const auto bytes = cvo::daemon::backendd::encode_tally(*tally);
      const auto again = cvo::daemon::backendd::decode_tally(bytes.data(), bytes.size(), &error);
      if (!again || cvo::daemon::backendd::encode_tally(*again) != bytes)
        cvo::fuzz::fail("a decoded tally record does not encode to the same bytes twice");
    } else if (error.empty()) {
      cvo::fuzz::fail("a tally record refused without a reason");
    }
    const auto merge = cvo::daemon::backendd::decode_merge(data, size, &error);
    if (!merge) {
      if (error.empty()) cvo::fuzz::fail("a merge record refused without a reason");
      return;
    }
    const auto bytes = cvo::daemon::backendd::encode_merge(*merge);
    const auto again = cvo::daemon::backendd::decode_merge(bytes.data(), bytes.size(), &error);
    if (!again) cvo::fuzz::fail("a decoded merge record encodes to bytes that do not decode: " + error);
    if (cvo::daemon::backendd::encode_merge(*again) != bytes)
      cvo::fuzz::fail("a decoded merge record does not encode to the same bytes twice");
  });
  return 0;
}
