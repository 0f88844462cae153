// Runs the built cvo-vocabulary on a few images: the command-line contract (exit status 0 ok,
// 1 bad input naming the file, 2 usage error) and a trained file that loads.
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/loop_closure/vocabulary.hpp"
#include "loop_closure/test_images.hpp"
#include "tests/support/cli_contract.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::loop_closure {
namespace {

namespace fs = std::filesystem;
using cvo::testing::quoted;
using cvo::testing::ToolRun;

ToolRun run(const test::TempDir& dir, const std::string& args) {
  return cvo::testing::run_tool("cvo-vocabulary", args, dir.path());
}

TEST(CvoVocabularyCli, TrainsOnATumFolderAndInfoVerifiesTheFile) {
  const test::TempDir dir;
  const fs::path out = dir.path() / "small.voc";
  // Frames 0, 10, ..., 40 of the sample.
  const ToolRun train = run(dir, "train " + quoted(out) + " " + quoted(testing::sample_dir()) +
                                     " --every 10 --k 6 --levels 2 --features 300 --seed 4");
  ASSERT_EQ(train.exit_code, 0) << train.err;
  EXPECT_NE(train.out.find("images          5\n"), std::string::npos) << train.out;
  EXPECT_NE(train.out.find("k 6, L 2"), std::string::npos) << train.out;

  const Vocabulary voc = Vocabulary::load(out);
  EXPECT_EQ(voc.branching(), 6);
  EXPECT_EQ(voc.levels(), 2);
  EXPECT_EQ(voc.training_images(), 5u);
  EXPECT_GT(voc.words(), 6u);
  EXPECT_LE(voc.words(), 36u);

  const ToolRun info = run(dir, "info " + quoted(out));
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("branching k      6\n"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("depth L          2\n"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("words            " + std::to_string(voc.words()) + "\n"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("training images  5\n"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find(" OK\n"), std::string::npos) << info.out;

  // The same command gives the same file.
  const fs::path again = dir.path() / "again.voc";
  ASSERT_EQ(run(dir, "train " + quoted(again) + " " + quoted(testing::sample_dir()) +
                         " --every 10 --k 6 --levels 2 --features 300 --seed 4")
                .exit_code,
            0);
  EXPECT_TRUE(Vocabulary::load(again) == voc);
}

TEST(CvoVocabularyCli, TrainsOnImageFilesAndFoldersOfImages) {
  const test::TempDir dir;
  const fs::path images = dir.path() / "images";
  fs::create_directories(images);
  cv::imwrite((images / "a.png").string(), testing::sample_frame(0));
  cv::imwrite((images / "b.jpg").string(), testing::sample_frame(25));
  dir.write("images/notes.txt", "not an image, skipped by extension\n");
  const fs::path single = dir.path() / "c.png";
  cv::imwrite(single.string(), testing::sample_frame(49));
  const fs::path out = dir.path() / "v.voc";
  const ToolRun r =
      run(dir, "train " + quoted(out) + " " + quoted(images) + " " + quoted(single) + " --k 4 --levels 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Vocabulary::load(out).training_images(), 3u);
}

TEST(CvoVocabularyCli, BadInputExitsWithOneAndNamesTheFile) {
  const test::TempDir dir;
  const fs::path out = dir.path() / "v.voc";
  ToolRun r = run(dir, "train " + quoted(out) + " " + quoted(dir.path() / "missing"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("missing"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));

  const fs::path not_image = dir.write("fake.png", "not a png");
  r = run(dir, "train " + quoted(out) + " " + quoted(not_image));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("fake.png"), std::string::npos) << r.err;

  fs::create_directories(dir.path() / "empty");
  r = run(dir, "train " + quoted(out) + " " + quoted(dir.path() / "empty"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no image files"), std::string::npos) << r.err;

  // A damaged vocabulary: info refuses it with the reason.
  std::string bytes = Vocabulary::load(CVO_DEFAULT_VOCABULARY).to_bytes();
  bytes[1000] = static_cast<char>(bytes[1000] ^ 0x40);
  const fs::path damaged = dir.path() / "damaged.voc";
  std::ofstream(damaged, std::ios::binary) << bytes;
  r = run(dir, "info " + quoted(damaged));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("damaged.voc"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("checksum mismatch"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");

  r = run(dir, "info " + quoted(dir.path() / "absent.voc"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("absent.voc"), std::string::npos) << r.err;
}

TEST(CvoVocabularyCli, UsageErrorsExitWithTwoAndHelpWithZero) {
  const test::TempDir dir;
  const std::string sample = quoted(testing::sample_dir());
  for (const std::string& args :
       std::vector<std::string>{"", "fly", "train", "train out.voc", "info", "info a.voc b.voc",
                                "train out.voc " + sample + " --k 1", "train out.voc " + sample + " --k ten",
                                "train out.voc " + sample + " --levels 17", "train out.voc " + sample + " --every 0",
                                "train out.voc " + sample + " --features", "train out.voc " + sample + " --wat"}) {
    const ToolRun r = run(dir, args);
    EXPECT_EQ(r.exit_code, 2) << "'" << args << "': " << r.err;
    EXPECT_NE(r.err.find("usage: cvo-vocabulary"), std::string::npos) << args;
  }
  const ToolRun help = run(dir, "--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("usage: cvo-vocabulary train"), std::string::npos);
}

TEST(CvoVocabularyCli, HelpListsEveryOptionAndAnUnknownOneExitsTwoNamingIt) {
  const test::TempDir dir;
  cvo::testing::expect_cli_contract("cvo-vocabulary", "", {"train", "info"}, dir.path());
  cvo::testing::expect_cli_contract("cvo-vocabulary", "train",
                                    {"OUT.voc", "INPUT", "--k", "--levels", "--every", "--features", "--seed"},
                                    dir.path());
  cvo::testing::expect_cli_contract("cvo-vocabulary", "info", {"FILE.voc"}, dir.path());
}

// Counts are decimal: a negative seed is refused rather than wrapped, hexadecimal and octal too.
TEST(CvoVocabularyCli, CountsTakeOnlyDecimalDigits) {
  const test::TempDir dir;
  const std::string train = "train out.voc " + quoted(testing::sample_dir());
  for (const std::string option : {"--seed -1", "--seed 18446744073709551616", "--k 0x10", "--every 1.5"}) {
    const ToolRun r = run(dir, train + " " + option);
    EXPECT_EQ(r.exit_code, 2) << option << ": " << r.err;
    EXPECT_NE(r.err.find(option.substr(0, option.find(' '))), std::string::npos) << option << ": " << r.err;
  }
  const fs::path out = dir.path() / "k10.voc";
  const ToolRun r = run(dir, "train " + quoted(out) + " " + quoted(testing::sample_dir()) +
                                 " --k 010 --levels 01 --every 25 --features 200 --seed 007");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Vocabulary::load(out).branching(), 10) << "010 is ten, not octal eight";
  EXPECT_NE(r.out.find("seed 7\n"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace cvo::loop_closure
