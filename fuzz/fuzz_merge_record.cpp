// A keyframe store's merge record, and its settled record, (libcvo/store/merge_record.hpp) as
// cvo-backendd's start-up and cvo-map decode them: any bytes are refused with a reason, or decode to a merge whose
// encoding decodes again to the same encoding (what a restarted store replays is what was stored).
#include <string>

#include "fuzz/harness.hpp"
#include "libcvo/store/merge_record.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cvo::fuzz::expect_refusal_or_success([&] {
    std::string error;
    // The other records of revisits: refused with a reason, or stable through encode and decode.
    const auto stable = [&](const char* what, auto decode, auto encode) {
      if (const auto value = decode(data, size, &error)) {
        const auto bytes = encode(*value);
        const auto again = decode(bytes.data(), bytes.size(), &error);
        if (!again || encode(*again) != bytes)
          cvo::fuzz::fail(std::string("a decoded ") + what + " record does not encode to the same bytes twice");
      } else if (error.empty()) {
        cvo::fuzz::fail(std::string("a ") + what + " record refused without a reason");
      }
    };
    stable("settled", cvo::store::decode_settled, cvo::store::encode_settled);
    stable("tally", cvo::store::decode_tally, cvo::store::encode_tally);
    const auto merge = cvo::store::decode_merge(data, size, &error);
    if (!merge) {
      if (error.empty()) cvo::fuzz::fail("a merge record refused without a reason");
      return;
    }
    const auto bytes = cvo::store::encode_merge(*merge);
    const auto again = cvo::store::decode_merge(bytes.data(), bytes.size(), &error);
    if (!again) cvo::fuzz::fail("a decoded merge record encodes to bytes that do not decode: " + error);
    if (cvo::store::encode_merge(*again) != bytes)
      cvo::fuzz::fail("a decoded merge record does not encode to the same bytes twice");
  });
  return 0;
}
