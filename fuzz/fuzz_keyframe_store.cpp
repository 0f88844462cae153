// cvo-backendd's keyframe store file as it reads one back at start: the bytes are the whole file,
// damaged any way, and recovery must keep what is intact and leave a clean store behind.
#include "daemon/backendd/keyframe_store.hpp"
#include "fuzz/harness.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = cvo::fuzz::scratch_dir() / "keyframes.store";
  cvo::fuzz::write_file(file, cvo::fuzz::as_text(data, size));
  cvo::fuzz::expect_refusal_or_success([&] {
    std::vector<cvo::daemon::backendd::StoredRecord> recovered;
    std::string warning;
    { cvo::daemon::backendd::KeyframeStore store(file, recovered, warning); }
    // keyframe_store.hpp's promise: after recovery FILE holds exactly the intact records, so the
    // next start reads them all again and finds nothing damaged.
    std::vector<cvo::daemon::backendd::StoredRecord> again;
    std::string warning_again;
    { cvo::daemon::backendd::KeyframeStore store(file, again, warning_again); }
    if (!warning_again.empty() || again.size() != recovered.size())
      cvo::fuzz::fail("the recovered store is not clean: " + warning_again);
    for (std::size_t i = 0; i < again.size(); ++i)
      if (again[i].kind != recovered[i].kind || again[i].payload != recovered[i].payload)
        cvo::fuzz::fail("record " + std::to_string(i) + " changed across a recovery");
  });
  return 0;
}
