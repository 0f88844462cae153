// Key files: written mode 0600 and read back to the same keys; never overwritten; refused with a
// message that says what to do when the mode lets others in, or the text is not a key file.
#include <sys/stat.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "libcvo/auth/key.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::auth {
namespace {

namespace fs = std::filesystem;

KeyRing ring(std::size_t n) {
  std::vector<Key> keys;
  for (std::size_t i = 0; i < n; ++i) keys.push_back(Key::generate());
  return KeyRing(std::move(keys));
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const KeyFileError& e) {
    return e.what();
  }
  return "";
}

std::string hex(char c) { return std::string(64, c); }

TEST(KeyFile, IsWrittenMode0600AndReadsBackTheSameKeysInOrder) {
  const cvo::test::TempDir dir("cvo_key");
  const auto file = dir.path() / "cvo-slam.key";
  const KeyRing keys = ring(2);
  create_key_file(file, keys);
  struct stat st {};
  ASSERT_EQ(stat(file.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  const KeyRing read = read_key_file(file);
  ASSERT_EQ(read.keys().size(), 2u);
  EXPECT_EQ(read.signing().id(), keys.signing().id());
  EXPECT_EQ(read.keys()[1].id(), keys.keys()[1].id());
  EXPECT_NE(read.signing().id(), read.keys()[1].id());
}

TEST(KeyFile, IsNeverOverwrittenButReplacedWhole) {
  const cvo::test::TempDir dir("cvo_key");
  const auto file = dir.path() / "cvo-slam.key";
  const KeyRing first = ring(1);
  create_key_file(file, first);
  EXPECT_NE(error_of([&] { create_key_file(file, ring(1)); }).find("exists already"), std::string::npos);
  EXPECT_EQ(read_key_file(file).signing().id(), first.signing().id());
  const KeyRing second = ring(1);
  replace_key_file(file, second);
  EXPECT_EQ(read_key_file(file).signing().id(), second.signing().id());
  struct stat st {};
  ASSERT_EQ(stat(file.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1) << "no file left beside";
}

TEST(KeyFile, ThatOthersMayReadIsRefusedWithWhatToDo) {
  const cvo::test::TempDir dir("cvo_key");
  const auto file = dir.path() / "cvo-slam.key";
  create_key_file(file, ring(1));
  for (const auto mode : {0644, 0640, 0604, 0660}) {
    ASSERT_EQ(chmod(file.c_str(), static_cast<mode_t>(mode)), 0);
    const auto error = error_of([&] { (void)read_key_file(file); });
    EXPECT_NE(error.find(file.string()), std::string::npos) << error;
    EXPECT_NE(error.find("chmod 600"), std::string::npos) << error;
  }
  ASSERT_EQ(chmod(file.c_str(), 0400), 0);  // systemd's credentials are 0400
  EXPECT_NO_THROW((void)read_key_file(file));
  EXPECT_NE(error_of([&] { (void)read_key_file(dir.path() / "missing.key"); }).find("cannot open"), std::string::npos);
}

TEST(KeyFile, TextThatIsNotAKeyFileIsRefusedByLine) {
  const std::string header = "cvo-slam key file 1\n";
  const auto parse = [](const std::string& text) { return error_of([&] { (void)parse_key_file(text, "k"); }); };
  EXPECT_NE(parse("key " + hex('a') + "\n").find("k:1: not a cvo-slam key file"), std::string::npos);
  EXPECT_NE(parse("cvo-slam key file 2\nkey " + hex('a') + "\n").find("k:1:"), std::string::npos);
  EXPECT_NE(parse(header).find("holds no key"), std::string::npos);
  EXPECT_NE(parse("").find("empty"), std::string::npos);
  EXPECT_NE(parse(header + "key 1234\n").find("k:2: a key is 64 hex digits"), std::string::npos);
  EXPECT_NE(parse(header + "key " + hex('g') + "\n").find("64 hex digits"), std::string::npos);
  EXPECT_NE(parse(header + "sign " + hex('a') + "\n").find("k:2: expected 'key'"), std::string::npos);
  EXPECT_NE(parse(header + "key " + hex('a') + "\nkey " + hex('a') + "\n").find("the same key twice"),
            std::string::npos);
  EXPECT_NE(parse(header + "key " + hex('a') + "\nkey " + hex('b') + "\nkey " + hex('c') + "\n").find("more than two"),
            std::string::npos);
  // Comments and blank lines are fine; the key never appears in a message.
  const KeyRing keys = parse_key_file("# a comment\n\n" + header + "key " + hex('a') + "  # id\n", "k");
  EXPECT_EQ(keys.keys().size(), 1u);
  EXPECT_EQ(parse(header + "key " + hex('a') + "x\n").find(hex('a')), std::string::npos);
}

TEST(KeyIds, NameKeysWithoutRevealingThemAndDifferPerKey) {
  const auto a = Key::from_hex(hex('a'));
  const auto b = Key::from_hex(hex('b'));
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->id(), Key::from_hex(hex('a'))->id());
  EXPECT_NE(a->id(), b->id());
  EXPECT_NE(a->id(), 0);
  EXPECT_EQ(key_name(0x12ab).size(), 18u);
  EXPECT_FALSE(Key::from_hex(hex('a').substr(1)));
}

}  // namespace
}  // namespace cvo::auth
