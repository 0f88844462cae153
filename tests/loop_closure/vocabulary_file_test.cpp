// The vocabulary file: round trip, and refusal (io::InputError naming the file and why) of every
// kind of damage, without crashing or allocating from a corrupt count.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "libcvo/io/input_error.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::loop_closure {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kHeader = 28, kNode = 44;

std::vector<cv::Mat> random_images(int images, int per_image, std::uint64_t seed) {
  cv::RNG rng(seed);
  std::vector<cv::Mat> out;
  for (int i = 0; i < images; ++i) {
    cv::Mat m(per_image, 32, CV_8UC1);
    rng.fill(m, cv::RNG::UNIFORM, 0, 256);
    out.push_back(m);
  }
  return out;
}

Vocabulary small_vocabulary() { return Vocabulary::train(random_images(6, 200, 1), {.branching = 5, .levels = 2}); }

std::string read_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_bytes(const fs::path& file, const std::string& bytes) {
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
}

void put_u32(std::string& bytes, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) bytes[at + static_cast<std::size_t>(i)] = static_cast<char>((v >> (8 * i)) & 0xff);
}

// Replaces the trailing checksum by the right one for the edited bytes before it.
void reseal(std::string& bytes) {
  const std::uint64_t h = fnv1a64(std::string_view(bytes).substr(0, bytes.size() - 8));
  for (int i = 0; i < 8; ++i)
    bytes[bytes.size() - 8 + static_cast<std::size_t>(i)] = static_cast<char>((h >> (8 * i)) & 0xff);
}

// The message of the InputError that loading `bytes` (as a file) throws; "" when none is thrown.
std::string load_error(const test::TempDir& dir, const std::string& bytes) {
  const fs::path file = dir.path() / "damaged.voc";
  write_bytes(file, bytes);
  try {
    (void)Vocabulary::load(file);
  } catch (const io::InputError& e) {
    EXPECT_EQ(e.file(), file);
    return e.what();
  }
  return "";
}

TEST(VocabularyFile, RoundTripGivesTheSameVocabularyAndTransforms) {
  const test::TempDir dir;
  const Vocabulary voc = small_vocabulary();
  const fs::path file = dir.path() / "small.voc";
  voc.save(file);
  EXPECT_EQ(fs::file_size(file), kHeader + kNode * voc.nodes().size() + 8);
  EXPECT_EQ(read_bytes(file).substr(0, 6), "CVOVOC");
  EXPECT_FALSE(fs::exists(dir.path() / "small.voc.partial"));

  const Vocabulary back = Vocabulary::load(file);
  EXPECT_TRUE(back == voc);
  EXPECT_EQ(back.branching(), 5);
  EXPECT_EQ(back.levels(), 2);
  EXPECT_EQ(back.words(), voc.words());
  EXPECT_EQ(back.training_images(), 6u);
  EXPECT_EQ(back.checksum(), voc.checksum());
  for (const cv::Mat& image : random_images(5, 300, 99)) EXPECT_EQ(back.transform(image), voc.transform(image));
}

TEST(VocabularyFile, AnyFlippedByteIsRefused) {
  const test::TempDir dir;
  const std::string good = small_vocabulary().to_bytes();
  // A node's centre, a node's weight, a parent, and the checksum itself: the checksum catches them.
  for (const std::size_t at :
       {kHeader + kNode * 3 + 20, kHeader + kNode * 2 + 6, kHeader + kNode * 4, good.size() - 3}) {
    std::string bad = good;
    bad[at] = static_cast<char>(bad[at] ^ 0x10);
    EXPECT_NE(load_error(dir, bad).find("checksum mismatch"), std::string::npos) << "byte " << at;
  }
  // Header bytes are refused too (by what they break first).
  for (std::size_t at = 0; at < kHeader; ++at) {
    std::string bad = good;
    bad[at] = static_cast<char>(bad[at] ^ 0x01);
    EXPECT_NE(load_error(dir, bad), "") << "byte " << at;
  }
}

TEST(VocabularyFile, TruncatedFilesAreRefused) {
  const test::TempDir dir;
  const std::string good = small_vocabulary().to_bytes();
  for (const std::size_t length : {std::size_t{0}, std::size_t{3}, std::size_t{20}, kHeader + 8, kHeader + kNode + 1,
                                   good.size() / 2, good.size() - 1}) {
    const std::string message = load_error(dir, good.substr(0, length));
    EXPECT_NE(message.find("truncated"), std::string::npos) << length << " bytes: " << message;
    EXPECT_NE(message.find("damaged.voc"), std::string::npos) << message;
  }
  EXPECT_NE(load_error(dir, good + "x").find("unexpected bytes"), std::string::npos);
}

TEST(VocabularyFile, WrongMagicAndUnknownVersionAreRefused) {
  const test::TempDir dir;
  const std::string good = small_vocabulary().to_bytes();
  std::string bad = good;
  bad[2] = 'X';
  EXPECT_NE(load_error(dir, bad).find("magic"), std::string::npos);
  EXPECT_NE(load_error(dir, "P5\n640 480\n255\n" + std::string(100, '\0')).find("magic"), std::string::npos);
  bad = good;
  bad[6] = 2;
  reseal(bad);
  EXPECT_NE(load_error(dir, bad).find("unknown format version 2"), std::string::npos);
}

TEST(VocabularyFile, AHugeNodeCountIsRefusedWithoutAllocating) {
  const test::TempDir dir;
  std::string bad = small_vocabulary().to_bytes();
  put_u32(bad, 16, 0xffffffffu);  // ~190 GB of nodes announced
  reseal(bad);
  EXPECT_NE(load_error(dir, bad).find("truncated"), std::string::npos);
}

TEST(VocabularyFile, ImpossibleTreesWithAValidChecksumAreRefused) {
  const test::TempDir dir;
  const std::string good = small_vocabulary().to_bytes();
  std::string bad = good;
  put_u32(bad, kHeader + kNode * 2, 5);  // node 2's parent after it
  reseal(bad);
  EXPECT_NE(load_error(dir, bad).find("node 2: bad parent"), std::string::npos);

  bad = good;
  put_u32(bad, kHeader, 0);  // the root with a parent
  reseal(bad);
  EXPECT_NE(load_error(dir, bad).find("node 0: bad parent"), std::string::npos);

  bad = good;
  put_u32(bad, 20, 12345);  // word count
  reseal(bad);
  EXPECT_NE(load_error(dir, bad).find("words"), std::string::npos);

  bad = good;
  put_u32(bad, 8, 1);  // k = 1
  reseal(bad);
  EXPECT_NE(load_error(dir, bad).find("out of range"), std::string::npos);

  bad = good;
  put_u32(bad, 8, 2);  // k = 2, but the root has 5 children
  reseal(bad);
  EXPECT_NE(load_error(dir, bad).find("more than k children"), std::string::npos);

  bad = good;
  put_u32(bad, 12, 1);  // L = 1, but the tree has 2 levels
  reseal(bad);
  EXPECT_NE(load_error(dir, bad).find("deeper than the depth L = 1"), std::string::npos);

  bad = good;
  for (int i = 0; i < 8; ++i)
    bad[kHeader + kNode * 7 + 4 + static_cast<std::size_t>(i)] = static_cast<char>(0xff);  // NaN weight
  reseal(bad);
  EXPECT_NE(load_error(dir, bad).find("weight not in [0, 64]"), std::string::npos);
}

// Damage that a valid checksum hides (a buggy writer): loading either refuses it or gives a
// vocabulary whose transform() still keeps the BowVector invariants; it never crashes.
TEST(VocabularyFile, RandomDamageBehindAValidChecksumNeverCrashes) {
  const std::string good = small_vocabulary().to_bytes();
  const auto probe = random_images(1, 200, 5).front();
  cv::RNG rng(17);
  int refused = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string bad = good;
    for (int k = rng.uniform(1, 4); k > 0; --k) {
      const auto at =
          static_cast<std::size_t>(rng.uniform(8, static_cast<int>(good.size()) - 8));  // past the magic and version
      bad[at] = static_cast<char>(rng.uniform(0, 256));
    }
    reseal(bad);
    try {
      const Vocabulary v = Vocabulary::from_bytes(bad, "fuzz.voc");
      const BowVector b = v.transform(probe);
      double total = 0;
      for (std::size_t e = 0; e < b.size(); ++e) {
        ASSERT_TRUE(e == 0 || b[e - 1].word < b[e].word);
        ASSERT_LT(b[e].word, v.words());
        ASSERT_GT(b[e].weight, 0.0);
        total += b[e].weight;
      }
      if (!b.empty()) {
        EXPECT_NEAR(total, 1.0, 1e-9);
      }
    } catch (const io::InputError& e) {
      ++refused;
      EXPECT_NE(std::string(e.what()).find("fuzz.voc: vocabulary: "), std::string::npos) << e.what();
    }
  }
  EXPECT_GT(refused, 50);  // most damage to parents and counts is caught
}

TEST(VocabularyFile, MissingFileAndUnwritableOutputAreInputErrors) {
  const test::TempDir dir;
  EXPECT_THROW((void)Vocabulary::load(dir.path() / "absent.voc"), io::InputError);
  EXPECT_THROW(small_vocabulary().save(dir.path() / "no" / "such" / "folder.voc"), io::InputError);
}

TEST(VocabularyFile, TheCommittedDefaultVocabularyLoadsAndVerifies) {
  const fs::path file = CVO_DEFAULT_VOCABULARY;
  const Vocabulary voc = Vocabulary::load(file);  // checks format, checksum and tree
  EXPECT_EQ(voc.branching(), 10);
  EXPECT_EQ(voc.levels(), 4);
  EXPECT_GT(voc.words(), 5000u);
  EXPECT_LE(voc.words(), 10000u);
  EXPECT_GT(voc.training_images(), 100u);
  EXPECT_LE(fs::file_size(file), 1u << 20);     // small enough to version
  EXPECT_EQ(voc.to_bytes(), read_bytes(file));  // written by this format's writer, byte for byte
}

}  // namespace
}  // namespace cvo::loop_closure
