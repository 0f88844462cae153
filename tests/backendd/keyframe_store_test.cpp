// KeyframeStore: records survive a reopen in order; damage in the middle (any header field, the
// payload, garbage between records) costs only the damaged record, the damaged original is kept
// aside and a clean store written in its place; a last record cut short costs only itself;
// writes that fail (EFBIG under a file-size limit, as a full disk) lose nothing: records are held
// in order, within a bound that is counted, and written once writing works again; a foreign file
// is refused. A stored record reads back from where append() says it is. read_store reads the
// same records without changing the file, while a store appends to it.
#include <signal.h>
#include <sys/resource.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/io/input_error.hpp"
#include "libcvo/store/keyframe_store.hpp"
#include "libcvo/store/store_records.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::store {
namespace {

namespace fs = std::filesystem;

std::vector<std::uint8_t> payload(int n, std::uint8_t seed) {
  std::vector<std::uint8_t> p(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) p[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(seed + 7 * i);
  return p;
}

// `n` keyframe records of `bytes` bytes each appended, and where each lies.
std::vector<RecordRef> append_keyframes(KeyframeStore& store, int n, int bytes) {
  std::vector<RecordRef> refs(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < refs.size(); ++i)
    EXPECT_EQ(store.append(RecordKind::kKeyframe, payload(bytes, static_cast<std::uint8_t>(i)), &refs[i]),
              Appended::kStored);
  return refs;
}

std::vector<StoredRecord> reopen(const fs::path& file, std::string& warning) {
  std::vector<StoredRecord> records;
  KeyframeStore store(file, records, warning);
  return records;
}

std::string bytes_of(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
void write_bytes(const fs::path& file, const std::string& bytes) {
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
}

// A store of `n` records of different sizes and both kinds, and where each starts.
struct Written {
  std::vector<StoredRecord> records;
  std::vector<std::size_t> starts;
  std::size_t end = 0;
};

RecordKind kind_of(std::size_t i) { return i % 2 == 0 ? RecordKind::kKeyframe : RecordKind::kLocalGraph; }

Written write_store(const fs::path& file, int n) {
  Written w;
  std::vector<StoredRecord> none;
  std::string warning;
  KeyframeStore store(file, none, warning);
  for (int i = 0; i < n; ++i) {
    w.starts.push_back(fs::file_size(file));
    w.records.push_back({kind_of(w.records.size()), payload(300 + 37 * i, static_cast<std::uint8_t>(i))});
    EXPECT_EQ(store.append(w.records.back().kind, w.records.back().payload), Appended::kStored);
  }
  w.end = fs::file_size(file);
  return w;
}

// The records read back are the written ones but those at `missing`, in order.
void expect_all_but(const std::vector<StoredRecord>& got, const Written& w, const std::set<std::size_t>& missing) {
  std::vector<StoredRecord> expected;
  for (std::size_t i = 0; i < w.records.size(); ++i)
    if (!missing.count(i)) expected.push_back(w.records[i]);
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].kind, expected[i].kind) << "record " << i;
    EXPECT_EQ(got[i].payload, expected[i].payload) << "record " << i;
  }
}

std::vector<fs::path> damaged_copies(const fs::path& file) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(file.parent_path()))
    if (e.path().filename().string().starts_with(file.filename().string() + ".damaged-")) out.push_back(e.path());
  return out;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// After a recovery: the store holds the intact records alone (it reads back without a warning),
// and a new record follows the last of them.
void expect_clean_and_appendable(const fs::path& file, const std::vector<StoredRecord>& intact) {
  std::string warning;
  std::vector<StoredRecord> records;
  {
    KeyframeStore store(file, records, warning);
    EXPECT_TRUE(warning.empty()) << warning;
    EXPECT_EQ(records.size(), intact.size());
    EXPECT_EQ(store.append(RecordKind::kLocalGraph, payload(20, 99)), Appended::kStored);
  }
  records = reopen(file, warning);
  EXPECT_TRUE(warning.empty()) << warning;
  ASSERT_EQ(records.size(), intact.size() + 1);
  EXPECT_EQ(records.back().payload, payload(20, 99));
}

TEST(KeyframeStore, RecordsSurviveAReopenInOrder) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "state" / "keyframes.store";
  const auto written = write_store(file, 3);
  std::string warning;
  const auto records = reopen(file, warning);
  EXPECT_TRUE(warning.empty()) << warning;
  expect_all_but(records, written, {});
}

// Records discarded as garbage (a merged keyframe's, issue #27 item 3) are compacted away once they
// pass a quarter of the file: the rest survive, in order, and the file holds only them. A reference
// given before a compaction still names its record after it (the later discards are of such).
TEST(KeyframeStore, DiscardedRecordsAreCompactedAwayOnceTheyPassAQuarterOfTheFile) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "keyframes.store";
  std::vector<StoredRecord> kept;
  {
    std::vector<StoredRecord> none;
    std::string warning;
    KeyframeStore store(file, none, warning);
    std::vector<RecordRef> refs;
    for (int i = 0; i < 6; ++i) {
      RecordRef where;
      const auto p = payload(1000, static_cast<std::uint8_t>(i));
      ASSERT_EQ(store.append(RecordKind::kKeyframe, p, &where), Appended::kStored);
      refs.push_back(where);
      if (i % 3 == 2) kept.push_back({RecordKind::kKeyframe, p});
    }
    std::vector<int> compacted_at;
    for (const int i : {0, 1, 3, 4})
      if (store.discard(refs[static_cast<std::size_t>(i)])) compacted_at.push_back(i);
    // 1 of 6 equal records is not a quarter of the file (its magic), 2 are; then 1 of 4 is not, 2 are.
    EXPECT_EQ(compacted_at, (std::vector<int>{1, 4}));
    EXPECT_EQ(store.compactions(), 2u);
    EXPECT_EQ(store.records(), 2u);
    std::string error;
    const auto last = store.read(refs[5], &error);  // given before both compactions: void
    EXPECT_FALSE(last);
    EXPECT_NE(error.find("compacted away"), std::string::npos) << error;
  }
  std::string warning;
  const auto records = reopen(file, warning);
  EXPECT_TRUE(warning.empty()) << warning;
  ASSERT_EQ(records.size(), 2u);
  EXPECT_EQ(records[0].payload, kept[0].payload);
  EXPECT_EQ(records[1].payload, kept[1].payload);
  EXPECT_LT(fs::file_size(file), 2 * 1100u);
  EXPECT_FALSE(fs::exists(file.string() + ".recovering"));
}

// A caller that still holds references it must read (records waiting in the store) forbids
// compaction: garbage is only counted, and the references still read their records. Once it allows
// it, the next discard compacts, and a reference from before that compaction reads its record.
TEST(KeyframeStore, NoCompactionWhileTheCallerSaysNoAndReferencesOutliveOneCompaction) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "keyframes.store";
  std::vector<StoredRecord> none;
  std::string warning;
  KeyframeStore store(file, none, warning);
  const auto refs = append_keyframes(store, 6, 1000);
  for (const std::size_t i : {0u, 1u, 2u}) EXPECT_FALSE(store.discard(refs[i], /*may_compact=*/false));
  EXPECT_EQ(store.compactions(), 0u);
  std::string error;
  EXPECT_TRUE(store.read(refs[4], &error)) << error;
  EXPECT_FALSE(store.discard(refs[1])) << "discarded already: nothing changes";
  EXPECT_TRUE(store.discard(refs[3]));  // allowed now: 4 of 6 are garbage
  EXPECT_EQ(store.records(), 2u);
  const auto moved = store.read(refs[5], &error);
  ASSERT_TRUE(moved) << error;
  EXPECT_EQ(moved->payload, payload(1000, 5));
  EXPECT_FALSE(store.read(refs[2], &error)) << "compacted away";
}

// A restarted store says where each recovered record lies, so that what a record made garbage
// before the restart (a merged keyframe's) can be discarded again.
TEST(KeyframeStore, RecoveredRecordsSayWhereTheyLie) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "keyframes.store";
  {
    std::vector<StoredRecord> none;
    std::string warning;
    KeyframeStore store(file, none, warning);
    for (int i = 0; i < 4; ++i)
      ASSERT_EQ(store.append(RecordKind::kKeyframe, payload(500, static_cast<std::uint8_t>(i))), Appended::kStored);
  }
  std::vector<StoredRecord> recovered;
  std::string warning;
  KeyframeStore store(file, recovered, warning);
  ASSERT_EQ(recovered.size(), 4u);
  std::string error;
  for (const auto& r : recovered) {
    const auto back = store.read(r.where, &error);
    ASSERT_TRUE(back) << error;
    EXPECT_EQ(back->payload, r.payload);
  }
  store.discard(recovered[0].where);
  EXPECT_TRUE(store.discard(recovered[1].where));
  EXPECT_EQ(store.records(), 2u);
}

// A discard is durable: after a restart the discarded record is not recovered (nor its tombstone),
// read_store leaves it out too, it still counts towards the next compaction, and a clean copy of a
// damaged store leaves it out.
TEST(KeyframeStore, ADiscardedRecordStaysDiscardedAfterARestart) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "keyframes.store";
  {
    std::vector<StoredRecord> none;
    std::string warning;
    KeyframeStore store(file, none, warning);
    const auto refs = append_keyframes(store, 6, 500);
    EXPECT_FALSE(store.discard(refs[1]));
  }
  EXPECT_EQ(read_store(file).scan.records.size(), 5u);
  {
    std::vector<StoredRecord> recovered;
    std::string warning;
    KeyframeStore store(file, recovered, warning);
    EXPECT_TRUE(warning.empty()) << warning;
    ASSERT_EQ(recovered.size(), 5u);
    EXPECT_EQ(recovered[0].payload, payload(500, 0));
    EXPECT_EQ(recovered[1].payload, payload(500, 2)) << "the discarded record is left out";
    EXPECT_TRUE(store.discard(recovered[1].where)) << "with the one from before the restart: a quarter";
    EXPECT_EQ(store.records(), 4u);
  }
  EXPECT_EQ(fs::file_size(file), kStoreMagic.size() + 4 * (kRecordHeaderBytes + 500)) << "no tombstone is copied";

  // Damage in the last record: the clean copy holds the live records only.
  {
    std::vector<StoredRecord> recovered;
    std::string warning;
    KeyframeStore store(file, recovered, warning);
    EXPECT_FALSE(store.discard(recovered[0].where));
  }
  auto bytes = bytes_of(file);  // the store is now 0 (discarded), 3, 4, 5 and a tombstone: 3 damaged
  bytes[kStoreMagic.size() + (kRecordHeaderBytes + 500) + 100] ^= 0x40;
  write_bytes(file, bytes);
  std::string warning;
  const auto records = reopen(file, warning);
  EXPECT_TRUE(contains(warning, "damaged stretch")) << warning;
  ASSERT_EQ(records.size(), 2u);
  EXPECT_EQ(records[0].payload, payload(500, 4));
  EXPECT_EQ(fs::file_size(file), kStoreMagic.size() + 2 * (kRecordHeaderBytes + 500));
}

// What append() stored can be read back where it says, while the store is open (how the back end
// takes a record that waited in the store); a place that holds no record it wrote, or a record
// damaged since, is refused with a reason.
TEST(KeyframeStore, AStoredRecordIsReadBackWhereAppendSaysItIs) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "keyframes.store";
  std::vector<StoredRecord> none;
  std::string warning;
  KeyframeStore store(file, none, warning);
  RecordRef first, second;
  ASSERT_EQ(store.append(RecordKind::kKeyframe, payload(40, 1), &first), Appended::kStored);
  ASSERT_EQ(store.append(RecordKind::kLocalGraph, payload(7, 2), &second), Appended::kStored);
  EXPECT_EQ(second.offset, first.offset + static_cast<off_t>(first.bytes));

  std::string error;
  const auto a = store.read(first, &error), b = store.read(second, &error);
  ASSERT_TRUE(a && b) << error;
  EXPECT_EQ(a->kind, RecordKind::kKeyframe);
  EXPECT_EQ(a->payload, payload(40, 1));
  EXPECT_EQ(b->kind, RecordKind::kLocalGraph);
  EXPECT_EQ(b->payload, payload(7, 2));

  EXPECT_FALSE(store.read({second.offset + 1, second.bytes}, &error));
  EXPECT_NE(error.find("not within the records written"), std::string::npos) << error;
  EXPECT_FALSE(store.read({first.offset + 1, first.bytes}, &error));
  EXPECT_NE(error.find("bad record magic"), std::string::npos) << error;

  auto bytes = bytes_of(file);  // one payload byte of the first record flipped on disk
  bytes[static_cast<std::size_t>(first.offset) + 20] ^= 0x10;
  std::fstream(file, std::ios::binary | std::ios::in | std::ios::out)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  EXPECT_FALSE(store.read(first, &error));
  EXPECT_NE(error.find("checksum mismatch"), std::string::npos) << error;
  EXPECT_TRUE(store.read(second, &error)) << error;
}

// Each field of the third record of twenty damaged in turn (one bit or byte): the 19 others are
// read back, the damaged original is kept byte for byte beside the store, and the store is clean.
TEST(KeyframeStore, DamageInAMiddleRecordCostsThatRecordAlone) {
  struct Damage {
    const char* what;
    std::size_t offset;  // in the record
    std::uint8_t flip;   // xor mask
    const char* why;     // as the warning says it
  };
  const std::vector<Damage> damages{
      {"a payload bit", 16 + 100, 0x08, "checksum mismatch"},
      {"a checksum bit", 12, 0x01, "checksum mismatch"},
      {"the record magic", 0, 0x20, "bad record magic"},
      {"the kind", 4, 0x08, "unknown record kind"},
      {"an impossible length", 11, 0xF0, "impossible record length"},
      {"a length beyond the file", 10, 0x01, "runs past the end of the file"},
      {"a length one off", 8, 0x01, "checksum mismatch"},
  };
  for (const auto& damage : damages) {
    SCOPED_TRACE(damage.what);
    cvo::test::TempDir dir;
    const auto file = dir.path() / "keyframes.store";
    const auto written = write_store(file, 20);
    auto bytes = bytes_of(file);
    bytes[written.starts[2] + damage.offset] =
        static_cast<char>(bytes[written.starts[2] + damage.offset] ^ damage.flip);
    write_bytes(file, bytes);

    std::string warning;
    const auto records = reopen(file, warning);
    expect_all_but(records, written, {2});
    const auto skipped = written.starts[3] - written.starts[2];
    EXPECT_TRUE(contains(warning, "1 damaged stretch skipped (" + std::to_string(skipped) +
                                      " bytes; the first at byte " + std::to_string(written.starts[2]) + ": "))
        << warning;
    EXPECT_TRUE(contains(warning, damage.why)) << warning;
    EXPECT_TRUE(contains(warning, "19 intact records kept")) << warning;
    const auto copies = damaged_copies(file);
    ASSERT_EQ(copies.size(), 1u);
    EXPECT_TRUE(contains(warning, "the damaged original is kept as " + copies[0].string())) << warning;
    EXPECT_TRUE(bytes_of(copies[0]) == bytes) << "the damaged original, unchanged";
    EXPECT_FALSE(fs::exists(file.string() + ".recovering"));
    expect_clean_and_appendable(file, records);
  }
}

// Garbage between records (with the record magic in it, and a whole plausible header whose
// checksum fails) and a second damaged record: every other record is kept, resynchronised on the
// next valid one each time.
TEST(KeyframeStore, GarbageBetweenRecordsIsSkipped) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "keyframes.store";
  const auto written = write_store(file, 20);
  auto bytes = bytes_of(file);
  bytes[written.starts[12] + 40] = static_cast<char>(bytes[written.starts[12] + 40] ^ 0x40);
  std::string garbage(1000, '\x5a');
  const std::string fake_header("CRFK\x01\0\0\0\x20\0\0\0\x12\x34\x56\x78", 16);  // 32 bytes, wrong checksum
  garbage.replace(100, 4, "CRFK");
  garbage.replace(500, fake_header.size(), fake_header);
  bytes.insert(written.starts[6], garbage);
  write_bytes(file, bytes);

  std::string warning;
  const auto records = reopen(file, warning);
  expect_all_but(records, written, {12});
  const auto damaged_record = written.starts[13] - written.starts[12];
  EXPECT_TRUE(contains(warning, "2 damaged stretches skipped (" + std::to_string(1000 + damaged_record) +
                                    " bytes; the first at byte " + std::to_string(written.starts[6]) +
                                    ": bad record magic"))
      << warning;
  EXPECT_TRUE(contains(warning, "19 intact records kept")) << warning;
  ASSERT_EQ(damaged_copies(file).size(), 1u);
  expect_clean_and_appendable(file, records);
}

// What a crash during a write leaves: the last record cut short, in its payload or its header.
// Every complete record is kept, the cut one (nothing intact in it) is cut off in place.
TEST(KeyframeStore, ATruncatedTailKeepsTheRest) {
  for (const std::size_t cut : {std::size_t{16 + 200}, std::size_t{9}, std::size_t{2}}) {
    SCOPED_TRACE("cut " + std::to_string(cut) + " bytes into the last record");
    cvo::test::TempDir dir;
    const auto file = dir.path() / "keyframes.store";
    const auto written = write_store(file, 20);
    fs::resize_file(file, written.starts[19] + cut);

    std::string warning;
    const auto records = reopen(file, warning);
    expect_all_but(records, written, {19});
    EXPECT_TRUE(contains(warning, "the last record was cut short (" + std::to_string(cut) + " bytes at byte " +
                                      std::to_string(written.starts[19])))
        << warning;
    EXPECT_TRUE(contains(warning, "19 intact records kept")) << warning;
    EXPECT_EQ(fs::file_size(file), written.starts[19]) << "only the cut record is cut off";
    EXPECT_TRUE(damaged_copies(file).empty());
    expect_clean_and_appendable(file, records);
  }
}

// A tail that is no cut record (zeros, as a file system can leave after a crash) is damage: kept
// aside like any other.
TEST(KeyframeStore, AZeroedTailIsKeptAside) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "keyframes.store";
  const auto written = write_store(file, 5);
  write_bytes(file, bytes_of(file) + std::string(4096, '\0'));
  std::string warning;
  const auto records = reopen(file, warning);
  expect_all_but(records, written, {});
  EXPECT_TRUE(contains(warning, "1 damaged stretch skipped (4096 bytes")) << warning;
  EXPECT_EQ(damaged_copies(file).size(), 1u);
  expect_clean_and_appendable(file, records);
}

TEST(KeyframeStore, AForeignFileIsRefusedNotOverwritten) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "notes.txt";
  std::ofstream(file) << "not a keyframe store\n";
  std::vector<StoredRecord> records;
  std::string warning;
  EXPECT_THROW(KeyframeStore(file, records, warning), io::InputError);
  EXPECT_EQ(bytes_of(file), "not a keyframe store\n");
  EXPECT_TRUE(damaged_copies(file).empty());
}

// Under a file-size limit writes fail with EFBIG (SIGXFSZ ignored, as cvo-backendd does): the
// same path as a full disk, without needing a file system to fill. Restores both on the way out.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &saved_);
    previous_ = signal(SIGXFSZ, SIG_IGN);
    set(bytes);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &saved_);
    signal(SIGXFSZ, previous_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;
  void set(rlim_t bytes) {
    rlimit limit = saved_;
    limit.rlim_cur = bytes;
    ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limit), 0);
  }
  void lift() { setrlimit(RLIMIT_FSIZE, &saved_); }

 private:
  rlimit saved_{};
  sighandler_t previous_ = SIG_DFL;
};

// Records that cannot be written are held in order, no torn record stays in the file (one was
// half written when the limit struck), at most the bound is held and what is beyond is counted;
// once writing works every held record is on disk, in order, before the next one.
TEST(KeyframeStore, RecordsThatCannotBeWrittenAreHeldAndWrittenLaterInOrder) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "keyframes.store";
  std::vector<StoredRecord> none;
  std::string warning;
  KeyframeStore store(file, none, warning, 4);
  std::vector<std::vector<std::uint8_t>> payloads;
  for (int i = 0; i < 11; ++i) payloads.push_back(payload(1000 + i, static_cast<std::uint8_t>(i)));
  ASSERT_EQ(store.append(RecordKind::kKeyframe, payloads[0]), Appended::kStored);
  const auto one = fs::file_size(file);
  std::vector<Appended> results;
  {
    FileSizeLimit limit(one + 1500);  // the next record fits; the one after only in part
    for (std::size_t i = 1; i < 8; ++i) results.push_back(store.append(RecordKind::kKeyframe, payloads[i]));
    EXPECT_EQ(fs::file_size(file), one + 16 + payloads[1].size()) << "no torn record left behind";
    const auto health = store.health();
    EXPECT_TRUE(health.failing);
    EXPECT_EQ(health.error, EFBIG);
    EXPECT_EQ(health.unsaved, 4u);
    EXPECT_EQ(health.not_durable, 2u);
    EXPECT_TRUE(contains(describe(health), "store at the file size limit (4 records unsaved)")) << describe(health);
    EXPECT_FALSE(store.retry()) << "still limited";
    limit.lift();
    EXPECT_TRUE(store.retry());
  }
  EXPECT_EQ(results, (std::vector<Appended>{Appended::kStored, Appended::kHeld, Appended::kHeld, Appended::kHeld,
                                            Appended::kHeld, Appended::kNotDurable, Appended::kNotDurable}));
  const auto health = store.health();
  EXPECT_FALSE(health.failing);
  EXPECT_EQ(health.unsaved, 0u);
  EXPECT_TRUE(health.degraded()) << "two records of this run are not on disk";
  EXPECT_EQ(store.append(RecordKind::kKeyframe, payloads[8]), Appended::kStored);
  EXPECT_EQ(store.records(), 7u);

  const auto records = reopen(file, warning);
  EXPECT_TRUE(warning.empty()) << warning;
  std::vector<std::vector<std::uint8_t>> got;
  for (const auto& r : records) got.push_back(r.payload);
  EXPECT_EQ(got, (std::vector<std::vector<std::uint8_t>>{payloads[0], payloads[1], payloads[2], payloads[3],
                                                         payloads[4], payloads[5], payloads[8]}));
}

// A new store that cannot even take its magic starts degraded instead of failing to start, and
// holds what it is given until it can write it.
TEST(KeyframeStore, ANewStoreThatCannotBeWrittenStartsDegraded) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "keyframes.store";
  {
    std::vector<StoredRecord> none;
    std::string warning;
    FileSizeLimit limit(4);
    KeyframeStore store(file, none, warning, 8);
    EXPECT_TRUE(store.health().failing);
    EXPECT_EQ(store.append(RecordKind::kLocalGraph, payload(50, 1)), Appended::kHeld);
    limit.lift();
    EXPECT_TRUE(store.retry());
    EXPECT_FALSE(store.health().degraded());
  }
  std::string warning;
  const auto records = reopen(file, warning);
  EXPECT_TRUE(warning.empty()) << warning;
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].payload, payload(50, 1));
}

// Where no clean copy fits, the damaged store stays as it was (nothing half-written left beside
// it) and is read the same way; once there is room the next start replaces it.
TEST(KeyframeStore, WithoutRoomForACleanCopyTheDamagedStoreStaysAndIsStillRead) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "keyframes.store";
  const auto written = write_store(file, 20);
  auto bytes = bytes_of(file);
  bytes[written.starts[2] + 16] = static_cast<char>(bytes[written.starts[2] + 16] ^ 0x01);
  write_bytes(file, bytes);
  {
    FileSizeLimit limit(written.end / 2);
    std::string warning;
    const auto records = reopen(file, warning);
    expect_all_but(records, written, {2});
    EXPECT_TRUE(contains(warning, "no clean copy could be written")) << warning;
  }
  EXPECT_TRUE(bytes_of(file) == bytes) << "the damaged store is left as it was";
  EXPECT_TRUE(damaged_copies(file).empty());
  EXPECT_FALSE(fs::exists(file.string() + ".recovering"));

  std::string warning;
  const auto records = reopen(file, warning);
  expect_all_but(records, written, {2});
  EXPECT_EQ(damaged_copies(file).size(), 1u) << warning;
  expect_clean_and_appendable(file, records);
}

// ---------------------------------------------------------------------------------------------
// read_store (store_records.hpp): the same scan, read only.

// The payloads read_store found, in order.
std::vector<StoredRecord> payloads(const StoreSnapshot& snapshot) {
  std::vector<StoredRecord> out;
  for (const auto& r : snapshot.scan.records) {
    const auto* p = snapshot.payload(r);
    out.push_back({r.kind, {p, p + StoreSnapshot::payload_bytes(r)}});
  }
  return out;
}

// A damaged record and a last record cut short: read_store keeps every intact record, says where
// the damage is, and leaves the file as it was (no copy aside, nothing cut off); the daemon's
// recovery, after it, keeps the very same records (one scan).
TEST(StoreRecords, ReadStoreReadsADamagedStoreWithoutChangingIt) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "keyframes.store";
  const auto written = write_store(file, 20);
  auto bytes = bytes_of(file);
  bytes[written.starts[7] + kRecordHeaderBytes + 5] ^= 0x01;
  bytes.resize(written.starts[19] + 30);
  write_bytes(file, bytes);

  const auto snapshot = read_store(file);
  expect_all_but(payloads(snapshot), written, {7, 19});
  ASSERT_EQ(snapshot.scan.damaged.size(), 1u);
  EXPECT_EQ(snapshot.scan.damaged[0].at, written.starts[7]);
  EXPECT_EQ(snapshot.scan.damaged[0].bytes, written.starts[8] - written.starts[7]);
  EXPECT_EQ(snapshot.scan.damaged[0].why, "checksum mismatch");
  ASSERT_TRUE(snapshot.scan.torn);
  EXPECT_EQ(snapshot.scan.torn->at, written.starts[19]);
  EXPECT_EQ(snapshot.scan.records[7].at, written.starts[8]) << "records say where they lie";
  EXPECT_TRUE(bytes_of(file) == bytes) << "read_store changed the file";
  EXPECT_TRUE(damaged_copies(file).empty());
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator{}), 1);

  std::string warning;
  expect_all_but(reopen(file, warning), written, {7, 19});
}

// While a KeyframeStore holds the file open and appends: each read sees what was stored by then.
TEST(StoreRecords, ReadStoreReadsAStoreThatIsOpenForAppending) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "keyframes.store";
  std::vector<StoredRecord> none;
  std::string warning;
  KeyframeStore store(file, none, warning);
  EXPECT_TRUE(read_store(file).scan.records.empty());
  for (std::uint8_t i = 0; i < 5; ++i) {
    ASSERT_EQ(store.append(RecordKind::kKeyframe, payload(100 + i, i)), Appended::kStored);
    const auto snapshot = read_store(file);
    EXPECT_TRUE(snapshot.scan.clean());
    ASSERT_EQ(snapshot.scan.records.size(), i + 1u);
    EXPECT_EQ(payloads(snapshot).back().payload, payload(100 + i, i));
  }
}

TEST(StoreRecords, ReadStoreRefusesAMissingOrForeignFileNamingIt) {
  cvo::test::TempDir dir;
  const auto missing = dir.path() / "none.store";
  const auto foreign = dir.write("notes.txt", "not a keyframe store\n");
  for (const auto& file : {missing, foreign, dir.path()}) {
    try {
      (void)read_store(file);
      ADD_FAILURE() << file << " was read as a store";
    } catch (const io::InputError& e) {
      EXPECT_TRUE(contains(e.what(), file.string())) << e.what();
    }
  }
  EXPECT_FALSE(fs::exists(missing)) << "read_store created the store";
  EXPECT_EQ(bytes_of(foreign), "not a keyframe store\n");
}

}  // namespace
}  // namespace cvo::store
