#pragma once
// The command-line contract every program shares (program/cli.hpp), checked the same way for each:
// --help exits 0 and lists every option, an unknown option exits 2 with a message that names it.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "tests/support/run_tool.hpp"

namespace cvo::testing {

/// `command` is the program and, for a subcommand, its name ("cvo-vocabulary train").
inline void expect_cli_contract(const std::string& tool, const std::string& subcommand,
                                const std::vector<std::string>& options, const std::filesystem::path& scratch) {
  const std::string prefix = subcommand.empty() ? "" : subcommand + " ";
  const ToolRun help = run_tool(tool, prefix + "--help", scratch);
  EXPECT_EQ(help.exit_code, 0) << help.err;
  EXPECT_NE(help.out.find("usage: " + tool), std::string::npos) << help.out;
  for (const std::string& option : options)
    EXPECT_NE(help.out.find(option), std::string::npos) << tool << " " << prefix << "--help does not list " << option;

  const ToolRun unknown = run_tool(tool, prefix + "--no-such-option 1", scratch);
  EXPECT_EQ(unknown.exit_code, 2) << unknown.err;
  EXPECT_NE(unknown.err.find("--no-such-option"), std::string::npos) << unknown.err;
  EXPECT_NE(unknown.err.find("usage: " + tool), std::string::npos) << unknown.err;
  EXPECT_TRUE(unknown.out.empty()) << unknown.out;
}

}  // namespace cvo::testing
