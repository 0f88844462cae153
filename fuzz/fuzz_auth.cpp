// The authenticated bus on raw bytes (libcvo/auth), as every receiver runs it before decoding:
// verify() never crashes on any buffer; what it accepts, a changed byte makes kAuth, and it is taken
// once by a receiver with replay checks (a second time kReplay); a key file's text parses or is
// refused with KeyFileError, nothing else.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz/auth_harness.hpp"
#include "fuzz/harness.hpp"
#include "libcvo/auth/key.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using cvo::auth::Verdict;
  const auto v = cvo::fuzz::verify_raw(data, size);
  if (v.verdict == Verdict::kOk) {
    std::vector<std::uint8_t> changed(data, data + size);
    changed[size / 2] ^= 0x20;
    if (cvo::fuzz::verify_raw(changed.data(), changed.size()).verdict != Verdict::kAuth)
      cvo::fuzz::fail("a changed byte of an authentic message is not refused as kAuth");
    const auto trailer = cvo::auth::read_trailer(data, size);
    cvo::auth::Verifier receiver(cvo::fuzz::fuzz_keys(), 30'000'000);
    const std::int64_t now = trailer.counter;  // the receiver's clock at the counter: fresh
    const auto first = receiver.verify(cvo::fuzz::kFuzzChannel, data, size, now);
    const auto second = receiver.verify(cvo::fuzz::kFuzzChannel, data, size, now);
    if (first.verdict != Verdict::kOk || second.verdict != Verdict::kReplay)
      cvo::fuzz::fail("an authentic message is not taken exactly once");
  } else if (v.verdict != Verdict::kAuth) {
    cvo::fuzz::fail("a receiver without replay checks answered kReplay");
  }
  try {
    (void)cvo::auth::parse_key_file(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz");
  } catch (const cvo::auth::KeyFileError&) {
  }
  return 0;
}
