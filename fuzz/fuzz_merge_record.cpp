// A keyframe store's merge record (daemon/backendd/merge_record.hpp) as cvo-backendd's start-up and
// cvo-map decode it: any bytes are refused with a reason, or decode to a merge whose encoding
// decodes again to the same encoding (what a restarted store replays is what was stored).
#include <string>

#include "daemon/backendd/merge_record.hpp"
#include "fuzz/harness.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cvo::fuzz::expect_refusal_or_success([&] {
    std::string error;
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
