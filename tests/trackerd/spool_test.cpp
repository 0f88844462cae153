// cvo-trackerd's spool (daemon/trackerd/spool.hpp) in a fresh folder: a message kept is read back byte
// for byte and found by a spool opened again on the folder (what a restarted tracker hands over),
// oldest first; an acknowledgement removes that session's files below its prefix and nothing else;
// past the bound the oldest go first, reported once; what cannot be kept says why; a write cut short
// is removed at open, files of other names are left alone, and a folder that cannot be made throws.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "daemon/trackerd/spool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::daemon::trackerd {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Bytes = std::vector<std::uint8_t>;
using Entry = Spool::Entry;
using Key = std::tuple<std::int64_t, std::int64_t, bool, std::uintmax_t>;  // session, id, graph, bytes

constexpr std::int64_t kSession = 0x5e5510'0000'0001;
constexpr auto kOther = static_cast<std::int64_t>(0xfeed'0000'0000'00ab);  // negative: all 16 digits
constexpr std::uintmax_t kRoom = 1 << 20;

// Distinct content for each message (its id and kind in the bytes).
Bytes message(std::int64_t id, bool graph, std::size_t size = 100) {
  Bytes bytes(size, graph ? 0x99 : 0xaa);
  bytes[0] = static_cast<std::uint8_t>(id);
  bytes[size - 1] = 0;  // a zero byte inside: kept as bytes, not as text
  return bytes;
}

Entry keyframe(std::int64_t id, std::int64_t session = kSession) { return {session, id, false, 0}; }
Entry graph(std::int64_t id, std::int64_t session = kSession) { return {session, id, true, 0}; }

std::vector<Key> keys(const std::deque<Entry>& entries) {
  std::vector<Key> out;
  for (const auto& e : entries) out.emplace_back(e.session, e.id, e.graph, e.bytes);
  return out;
}
std::vector<Key> keys(const std::vector<Entry>& entries) {
  return keys(std::deque<Entry>(entries.begin(), entries.end()));
}

// The names of the files in `dir`.
std::set<std::string> files(const fs::path& dir) {
  std::set<std::string> out;
  for (const auto& file : fs::directory_iterator(dir)) out.insert(file.path().filename().string());
  return out;
}

Bytes contents(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(Spool, AMessageKeptIsAFileReadBackByteForByte) {
  test::TempDir dir;
  Spool spool(dir.path() / "spool", kRoom);  // made when missing
  EXPECT_TRUE(spool.entries().empty());
  EXPECT_EQ(spool.bytes(), 0u);

  EXPECT_EQ(spool.keep(keyframe(3), message(3, false, 1000)), "");
  EXPECT_EQ(spool.keep(graph(3), message(3, true, 300)), "");
  EXPECT_EQ(spool.read(keyframe(3)), message(3, false, 1000));
  EXPECT_EQ(spool.read(graph(3)), message(3, true, 300));
  EXPECT_EQ(spool.read(keyframe(4)), std::nullopt) << "never kept";
  EXPECT_EQ(spool.read(keyframe(3, kOther)), std::nullopt) << "another session's keyframe 3";
  EXPECT_EQ(keys(spool.entries()), (std::vector<Key>{{kSession, 3, false, 1000}, {kSession, 3, true, 300}}));
  EXPECT_EQ(spool.bytes(), 1300u);

  // One file per message, named <session: 16 hex digits>-<id>-<k|g>.lcm, nothing else.
  EXPECT_EQ(files(dir.path() / "spool"),
            (std::set<std::string>{"005e551000000001-3-k.lcm", "005e551000000001-3-g.lcm"}));
  EXPECT_EQ(contents(dir.path() / "spool" / "005e551000000001-3-k.lcm"), message(3, false, 1000));
  EXPECT_TRUE(spool.dropped().empty());
}

TEST(Spool, ASpoolOpenedAgainFindsWhatWasKeptOldestFirst) {
  test::TempDir dir;
  const std::vector<std::pair<Entry, Bytes>> kept{
      {keyframe(7, kOther), message(7, false, 50)},
      {keyframe(0), message(0, false, 60)},
      {graph(0), message(0, true, 70)},
      {keyframe(1), message(1, false, 80)},
      {graph(7, kOther), message(7, true, 90)},
  };
  {
    Spool spool(dir.path(), kRoom);  // a tracker that is killed
    for (const auto& [entry, bytes] : kept) ASSERT_EQ(spool.keep(entry, bytes), "");
  }
  // Oldest by the files' times: given a second apart here, since the kernel's file times are coarse
  // (messages kept within the same tick get the same time).
  const auto start = fs::file_time_type::clock::now() - 1h;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    const auto& e = kept[i].first;
    char name[64];
    std::snprintf(name, sizeof name, "%016llx-%lld-%c.lcm", static_cast<unsigned long long>(e.session),
                  static_cast<long long>(e.id), e.graph ? 'g' : 'k');
    fs::last_write_time(dir.path() / name, start + std::chrono::seconds(static_cast<int>(i)));
  }

  const Spool again(dir.path(), kRoom);  // the tracker started again
  EXPECT_EQ(keys(again.entries()), (std::vector<Key>{{kOther, 7, false, 50},
                                                     {kSession, 0, false, 60},
                                                     {kSession, 0, true, 70},
                                                     {kSession, 1, false, 80},
                                                     {kOther, 7, true, 90}}));
  EXPECT_EQ(again.bytes(), 350u);
  for (const auto& [entry, bytes] : kept) EXPECT_EQ(again.read(entry), bytes) << entry.session << " " << entry.id;
}

TEST(Spool, AnAcknowledgementRemovesThatSessionsFilesBelowItsPrefixOnly) {
  test::TempDir dir;
  Spool spool(dir.path(), kRoom);
  for (std::int64_t k = 0; k < 4; ++k) {
    ASSERT_EQ(spool.keep(keyframe(k), message(k, false)), "");
    ASSERT_EQ(spool.keep(graph(k), message(k, true)), "");
  }
  ASSERT_EQ(spool.keep(keyframe(0, kOther), message(0, false)), "");
  ASSERT_EQ(spool.keep(graph(0, kOther), message(0, true)), "");

  spool.acknowledged(kSession, 3);  // keyframes 0-2 held by the back end
  EXPECT_EQ(keys(spool.entries()),
            (std::vector<Key>{
                {kSession, 3, false, 100}, {kSession, 3, true, 100}, {kOther, 0, false, 100}, {kOther, 0, true, 100}}));
  EXPECT_EQ(spool.bytes(), 400u);
  EXPECT_EQ(files(dir.path()), (std::set<std::string>{"005e551000000001-3-k.lcm", "005e551000000001-3-g.lcm",
                                                      "feed0000000000ab-0-k.lcm", "feed0000000000ab-0-g.lcm"}));
  EXPECT_EQ(spool.read(keyframe(2)), std::nullopt);
  EXPECT_EQ(spool.read(keyframe(3)), message(3, false));

  spool.acknowledged(kSession, 1);  // a lower prefix: nothing more to remove, nothing back
  EXPECT_EQ(spool.entries().size(), 4u);
  spool.acknowledged(0x7777, 100);  // a session the spool does not hold
  EXPECT_EQ(spool.entries().size(), 4u);
  spool.acknowledged(kOther, 1);
  spool.acknowledged(kSession, 4);
  EXPECT_TRUE(spool.entries().empty());
  EXPECT_EQ(spool.bytes(), 0u);
  EXPECT_TRUE(files(dir.path()).empty());
  EXPECT_TRUE(spool.dropped().empty()) << "acknowledged is not dropped";
}

TEST(Spool, PastItsBoundTheOldestGoFirstAndAreReportedOnce) {
  test::TempDir dir;
  Spool spool(dir.path(), 350);
  ASSERT_EQ(spool.keep(keyframe(0), message(0, false)), "");
  ASSERT_EQ(spool.keep(graph(0), message(0, true)), "");
  ASSERT_EQ(spool.keep(keyframe(1), message(1, false)), "");
  EXPECT_EQ(spool.bytes(), 300u);
  EXPECT_TRUE(spool.dropped().empty());

  ASSERT_EQ(spool.keep(graph(1), message(1, true, 151)), "");  // 451 > 350, 351 > 350: keyframe 0 and its graph go
  EXPECT_EQ(keys(spool.dropped()), (std::vector<Key>{{kSession, 0, false, 100}, {kSession, 0, true, 100}}));
  EXPECT_TRUE(spool.dropped().empty()) << "reported once";
  EXPECT_EQ(keys(spool.entries()), (std::vector<Key>{{kSession, 1, false, 100}, {kSession, 1, true, 151}}));
  EXPECT_EQ(spool.bytes(), 251u);
  EXPECT_EQ(files(dir.path()), (std::set<std::string>{"005e551000000001-1-k.lcm", "005e551000000001-1-g.lcm"}));
  EXPECT_EQ(spool.read(keyframe(0)), std::nullopt);

  ASSERT_EQ(spool.keep(keyframe(2), message(2, false, 99)), "");  // exactly at the bound: nothing goes
  EXPECT_EQ(spool.bytes(), 350u);
  EXPECT_TRUE(spool.dropped().empty());
}

TEST(Spool, ASpoolOpenedAgainWithASmallerBoundDropsItsOldestAtTheNextKeep) {
  test::TempDir dir;
  {
    Spool spool(dir.path(), kRoom);
    ASSERT_EQ(spool.keep(keyframe(0), message(0, false)), "");
    ASSERT_EQ(spool.keep(keyframe(1), message(1, false)), "");
  }
  fs::last_write_time(dir.path() / "005e551000000001-0-k.lcm", fs::file_time_type::clock::now() - 2h);
  Spool spool(dir.path(), 150);
  EXPECT_EQ(spool.bytes(), 200u) << "what it finds is taken in, over the bound";
  ASSERT_EQ(spool.keep(keyframe(2), message(2, false)), "");
  EXPECT_EQ(keys(spool.dropped()), (std::vector<Key>{{kSession, 0, false, 100}, {kSession, 1, false, 100}}));
  EXPECT_EQ(keys(spool.entries()), (std::vector<Key>{{kSession, 2, false, 100}}));
  EXPECT_EQ(files(dir.path()), (std::set<std::string>{"005e551000000001-2-k.lcm"}));
}

TEST(Spool, AMessageLargerThanTheBoundIsRefusedWithAReasonAndDropsNothing) {
  test::TempDir dir;
  Spool spool(dir.path(), 150);
  ASSERT_EQ(spool.keep(keyframe(0), message(0, false)), "");
  const auto why = spool.keep(keyframe(1), message(1, false, 151));
  EXPECT_NE(why.find("larger than trackerd.spool_bytes"), std::string::npos) << why;
  EXPECT_EQ(keys(spool.entries()), (std::vector<Key>{{kSession, 0, false, 100}}));
  EXPECT_EQ(spool.bytes(), 100u);
  EXPECT_TRUE(spool.dropped().empty());
  EXPECT_EQ(files(dir.path()), (std::set<std::string>{"005e551000000001-0-k.lcm"}));
}

TEST(Spool, AWriteThatFailsIsNotKeptAndSaysWhy) {
  test::TempDir dir;
  Spool spool(dir.path() / "spool", kRoom);
  ASSERT_EQ(spool.keep(keyframe(0), message(0, false)), "");
  fs::remove_all(dir.path() / "spool");  // the disk gone from under it
  const auto why = spool.keep(keyframe(1), message(1, false));
  EXPECT_NE(why.find("cannot write " + (dir.path() / "spool" / "005e551000000001-1-k.lcm").string()), std::string::npos)
      << why;
  EXPECT_NE(why.find("No such file or directory (ENOENT)"), std::string::npos) << "its errno, named: " << why;
  EXPECT_EQ(spool.entries().size(), 1u) << "keyframe 1 not kept";
  EXPECT_EQ(spool.bytes(), 100u);
}

TEST(Spool, AWriteCutShortIsRemovedAtOpenAndNotTakenIn) {
  test::TempDir dir;
  {
    Spool spool(dir.path(), kRoom);
    ASSERT_EQ(spool.keep(keyframe(0), message(0, false)), "");
  }
  dir.write("005e551000000001-1-k.lcm.partial", "half a keyframe");  // killed between write and rename
  const Spool spool(dir.path(), kRoom);
  EXPECT_EQ(keys(spool.entries()), (std::vector<Key>{{kSession, 0, false, 100}}));
  EXPECT_EQ(spool.bytes(), 100u);
  EXPECT_EQ(spool.read(keyframe(1)), std::nullopt);
  EXPECT_EQ(files(dir.path()), (std::set<std::string>{"005e551000000001-0-k.lcm"}));
}

TEST(Spool, FilesOfOtherNamesAreLeftAloneAndNotTakenIn) {
  test::TempDir dir;
  const std::set<std::string> others{
      "notes.txt",
      "005e551000000001-1-x.lcm",      // neither keyframe nor graph
      "005e551000000001--1-k.lcm",     // a negative id
      "005e551000000001-1-k.lcm.bak",  // more after the name
      "005e551000000001-1-k",          // no .lcm
      "005e551000000001-one-k.lcm",
  };
  for (const auto& name : others) dir.write(name, "not a message");
  fs::create_directory(dir.path() / "005e551000000001-2-k.lcm");  // a folder by a spool file's name
  const Spool spool(dir.path(), kRoom);
  EXPECT_TRUE(spool.entries().empty());
  EXPECT_EQ(spool.bytes(), 0u);
  auto expected = others;
  expected.insert("005e551000000001-2-k.lcm");
  EXPECT_EQ(files(dir.path()), expected);
}

TEST(Spool, AFolderThatCannotBeMadeThrowsNamingIt) {
  test::TempDir dir;
  const auto file = dir.write("a-file", "in the way");
  const auto path = file / "spool";  // under a regular file: not even root can make it
  try {
    Spool spool(path, kRoom);
    FAIL() << "opened " << path;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
}

// Issue 48: the daemon checks its spool at the start (trackerd.cpp); what is wrong names its errno.
TEST(Spool, AFolderUnderAFileIsUnusableNamingItsErrno) {
  test::TempDir dir;
  const auto path = dir.write("a-file", "in the way") / "spool";
  const auto why = Spool::unusable(path);
  EXPECT_NE(why.find(path.string()), std::string::npos) << why;
  EXPECT_NE(why.find("Not a directory (ENOTDIR)"), std::string::npos) << why;
}

TEST(Spool, AWritableFolderIsUsableAndItsCheckLeavesNothingThere) {
  test::TempDir dir;
  EXPECT_EQ(Spool::unusable(dir.path() / "spool"), "") << "made, written in, emptied";
  EXPECT_TRUE(fs::is_directory(dir.path() / "spool"));
  EXPECT_TRUE(files(dir.path() / "spool").empty());
}

}  // namespace
}  // namespace cvo::daemon::trackerd
