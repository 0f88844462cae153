// cvo-backendd's keyframe store file as it reads one back at start: the bytes are the whole file,
// damaged any way, and recovery must keep what is intact and leave a clean store behind. cvo-map's
// read-only reader (read_store) must find the very records recovery keeps, and change nothing.
#include <algorithm>
#include <string>
#include <vector>

#include "fuzz/harness.hpp"
#include "libcvo/store/keyframe_store.hpp"
#include "libcvo/store/store_records.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = cvo::fuzz::scratch_dir() / "keyframes.store";
  cvo::fuzz::write_file(file, cvo::fuzz::as_text(data, size));
  cvo::fuzz::expect_refusal_or_success([&] {
    const auto snapshot = cvo::store::read_store(file);
    if (snapshot.bytes.size() != size || !std::equal(snapshot.bytes.begin(), snapshot.bytes.end(), data))
      cvo::fuzz::fail("read_store did not read the file as it is");
    std::vector<cvo::store::StoredRecord> recovered;
    std::string warning;
    {
      cvo::store::KeyframeStore store(file, recovered, warning);
      // Each recovered record says where it lies in the store as recovery left it (issue 27: what a
      // restart discards as garbage is named so).
      for (const auto& r : recovered) {
        std::string error;
        const auto back = store.read(r.where, &error);
        if (!back || back->kind != r.kind || back->payload != r.payload)
          cvo::fuzz::fail("a recovered record is not where it says it lies: " + error);
      }
    }
    if (recovered.size() != snapshot.scan.records.size())
      cvo::fuzz::fail("read_store found " + std::to_string(snapshot.scan.records.size()) + " records, recovery " +
                      std::to_string(recovered.size()));
    for (std::size_t i = 0; i < recovered.size(); ++i) {
      const auto& r = snapshot.scan.records[i];
      const auto* p = snapshot.payload(r);
      if (r.kind != recovered[i].kind || !std::equal(p, p + cvo::store::StoreSnapshot::payload_bytes(r),
                                                     recovered[i].payload.begin(), recovered[i].payload.end()))
        cvo::fuzz::fail("record " + std::to_string(i) + " differs between read_store and recovery");
    }
    // keyframe_store.hpp's promise: after recovery FILE holds exactly the intact records, so the
    // next start reads them all again and finds nothing damaged.
    std::vector<cvo::store::StoredRecord> again;
    std::string warning_again;
    { cvo::store::KeyframeStore store(file, again, warning_again); }
    if (!warning_again.empty() || again.size() != recovered.size())
      cvo::fuzz::fail("the recovered store is not clean: " + warning_again);
    for (std::size_t i = 0; i < again.size(); ++i)
      if (again[i].kind != recovered[i].kind || again[i].payload != recovered[i].payload)
        cvo::fuzz::fail("record " + std::to_string(i) + " changed across a recovery");
  });
  return 0;
}
