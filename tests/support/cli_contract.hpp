#pragma once
// The command-line contract every program shares (program/cli.hpp), checked the same way for each:
// --help exits 0 and lists every option, an unknown option exits 2 with a message that names it, and
// so does a "--set" that is not KEY=VALUE.
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

/// `args` (a command line that would otherwise be accepted) plus "--set KEY" without "=": a usage
/// error, exit 2, naming --set and the form it needs, before anything runs.
inline void expect_set_needs_key_equals_value(const std::string& tool, const std::string& args,
                                              const std::filesystem::path& scratch) {
  const ToolRun r = run_tool(tool, args + " --set cvo.ell_init", scratch);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--set"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("KEY=VALUE"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("usage: " + tool), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

}  // namespace cvo::testing
