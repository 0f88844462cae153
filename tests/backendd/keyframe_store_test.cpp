// KeyframeStore: records survive a reopen in order; a corrupt or cut tail is dropped with a
// message (never loaded) and appending continues after the last good record; a foreign file is
// refused.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "daemon/backendd/keyframe_store.hpp"
#include "libcvo/io/input_error.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon::backendd {
namespace {

std::vector<std::uint8_t> payload(int n, std::uint8_t seed) {
  std::vector<std::uint8_t> p(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) p[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(seed + 7 * i);
  return p;
}

std::vector<StoredRecord> reopen(const std::filesystem::path& file, std::string& warning) {
  std::vector<StoredRecord> records;
  KeyframeStore store(file, records, warning);
  return records;
}

TEST(KeyframeStore, RecordsSurviveAReopenInOrder) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "state" / "keyframes.store";
  {
    std::vector<StoredRecord> none;
    std::string warning;
    KeyframeStore store(file, none, warning);
    EXPECT_TRUE(none.empty());
    EXPECT_TRUE(warning.empty());
    store.append(RecordKind::kKeyframe, payload(1000, 1));
    store.append(RecordKind::kLocalGraph, payload(10, 2));
    store.append(RecordKind::kKeyframe, payload(0, 3));
  }
  std::string warning;
  const auto records = reopen(file, warning);
  EXPECT_TRUE(warning.empty()) << warning;
  ASSERT_EQ(records.size(), 3u);
  EXPECT_EQ(records[0].kind, RecordKind::kKeyframe);
  EXPECT_EQ(records[0].payload, payload(1000, 1));
  EXPECT_EQ(records[1].kind, RecordKind::kLocalGraph);
  EXPECT_EQ(records[1].payload, payload(10, 2));
  EXPECT_TRUE(records[2].payload.empty());
}

TEST(KeyframeStore, ACutOrCorruptTailIsDroppedWithAMessageAndAppendingGoesOn) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "keyframes.store";
  std::uintmax_t two_records = 0;
  {
    std::vector<StoredRecord> none;
    std::string warning;
    KeyframeStore store(file, none, warning);
    store.append(RecordKind::kKeyframe, payload(500, 1));
    store.append(RecordKind::kKeyframe, payload(500, 2));
    two_records = std::filesystem::file_size(file);
    store.append(RecordKind::kKeyframe, payload(500, 3));
  }
  // A crash in the middle of the third record: only part of it reached the disk.
  std::filesystem::resize_file(file, two_records + 100);
  std::string warning;
  auto records = reopen(file, warning);
  EXPECT_EQ(records.size(), 2u);
  EXPECT_NE(warning.find("dropped 100 bytes after record 2"), std::string::npos) << warning;
  EXPECT_EQ(std::filesystem::file_size(file), two_records) << "the tail is truncated away";

  // New records follow the last good one.
  {
    std::vector<StoredRecord> again;
    std::string w;
    KeyframeStore store(file, again, w);
    store.append(RecordKind::kLocalGraph, payload(20, 9));
  }
  records = reopen(file, warning);
  ASSERT_EQ(records.size(), 3u);
  EXPECT_EQ(records[2].payload, payload(20, 9));

  // A flipped byte in the last record's payload: its checksum fails, it is not loaded.
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(std::filesystem::file_size(file)) - 5);
    f.put('\x5a');
  }
  warning.clear();
  records = reopen(file, warning);
  EXPECT_EQ(records.size(), 2u);
  EXPECT_NE(warning.find("checksum mismatch"), std::string::npos) << warning;
}

TEST(KeyframeStore, AForeignFileIsRefusedNotOverwritten) {
  cvo::test::TempDir dir;
  const auto file = dir.path() / "notes.txt";
  std::ofstream(file) << "not a keyframe store\n";
  std::vector<StoredRecord> records;
  std::string warning;
  EXPECT_THROW(KeyframeStore(file, records, warning), io::InputError);
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "not a keyframe store");
}

}  // namespace
}  // namespace cvo::daemon::backendd
