// cvo-keygen: the command-line contract; a new file of one key, mode 0600, never overwritten; a
// rotation through --add, --rotate, --retire, each step's file accepting the previous step's signer.
#include <sys/stat.h>

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "libcvo/auth/authenticator.hpp"
#include "libcvo/auth/key.hpp"
#include "tests/support/cli_contract.hpp"
#include "tests/support/run_tool.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::auth {
namespace {

using cvo::testing::run_tool;

TEST(CvoKeygen, KeepsTheCommandLineContract) {
  const cvo::test::TempDir dir("cvo_keygen");
  cvo::testing::expect_cli_contract("cvo-keygen", "", {"--add", "--rotate", "--retire", "FILE"}, dir.path());
}

TEST(CvoKeygen, WritesANewKeyFileMode0600AndNeverOverwritesOne) {
  const cvo::test::TempDir dir("cvo_keygen");
  const auto file = dir.path() / "cvo-slam.key";
  const auto made = run_tool("cvo-keygen", file.string(), dir.path());
  ASSERT_EQ(made.exit_code, 0) << made.err;
  struct stat st {};
  ASSERT_EQ(stat(file.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  const auto id = read_key_file(file).signing().id();
  EXPECT_NE(made.out.find(key_name(id)), std::string::npos) << made.out;
  const auto again = run_tool("cvo-keygen", file.string(), dir.path());
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_NE(again.err.find("exists already"), std::string::npos) << again.err;
  EXPECT_EQ(read_key_file(file).signing().id(), id);
  EXPECT_EQ(run_tool("cvo-keygen", "--add --retire " + file.string(), dir.path()).exit_code, 2);
}

// Each step's daemons accept the messages of the step before (and after): the fleet is rolled
// through them one daemon at a time.
TEST(CvoKeygen, RotatesThroughStepsWhoseNeighboursInteroperate) {
  const cvo::test::TempDir dir("cvo_keygen");
  const auto file = dir.path() / "cvo-slam.key";
  ASSERT_EQ(run_tool("cvo-keygen", file.string(), dir.path()).exit_code, 0);
  std::vector<std::shared_ptr<const KeyRing>> steps;
  steps.push_back(std::make_shared<const KeyRing>(read_key_file(file)));
  for (const char* step : {"--add", "--rotate", "--retire"}) {
    const auto r = run_tool("cvo-keygen", std::string(step) + " " + file.string(), dir.path());
    ASSERT_EQ(r.exit_code, 0) << step << ": " << r.err;
    steps.push_back(std::make_shared<const KeyRing>(read_key_file(file)));
  }
  ASSERT_EQ(steps[1]->keys().size(), 2u);
  EXPECT_EQ(steps[1]->signing().id(), steps[0]->signing().id()) << "--add: the old key still signs";
  EXPECT_EQ(steps[2]->signing().id(), steps[1]->keys()[1].id()) << "--rotate: the added key signs";
  EXPECT_EQ(steps[3]->keys().size(), 1u);
  EXPECT_EQ(steps[3]->signing().id(), steps[2]->signing().id()) << "--retire: the old key is gone";
  for (std::size_t i = 0; i + 1 < steps.size(); ++i) {
    for (const auto& [from, to] : {std::pair{steps[i], steps[i + 1]}, std::pair{steps[i + 1], steps[i]}}) {
      Signer signer(from, 1);
      std::vector<std::uint8_t> message(100, 0);
      signer.sign("CVO_MAP", message);
      Verifier verifier(to, 30'000'000);
      EXPECT_EQ(verifier.verify("CVO_MAP", message.data(), message.size()).verdict, Verdict::kOk) << "step " << i;
    }
  }
  Signer last(steps[3], 1);
  std::vector<std::uint8_t> message(100, 0);
  last.sign("CVO_MAP", message);
  Verifier first(steps[0], 30'000'000);
  EXPECT_EQ(first.verify("CVO_MAP", message.data(), message.size()).verdict, Verdict::kAuth)
      << "two steps apart do not interoperate: roll each step out before the next";
}

}  // namespace
}  // namespace cvo::auth
