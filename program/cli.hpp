#pragma once
// The command line every program of the project shares, tools and daemons alike, through CLI11.
//
// Exit status, a contract that scripts rely on:
//   0  success; also --help, which prints the help on stdout
//   1  bad input or a failure while running; the message on stderr names the file (io::InputError)
//   2  usage error: the message, which names the option, then the usage line, on stderr
//
// The help has one shape everywhere: "usage: SYNOPSIS", what the program does, every option with
// its default and allowed values, the program's notes, the exit statuses.
#include <CLI/CLI.hpp>

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace cvo::program {

/// A usage error found after parsing (options that only make sense together, a value's form);
/// cli_main turns it into exit status 2, like a parse error.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Gives `app` the project's help: `synopsis` is the usage line without "usage: ", `notes` (may be
/// empty) come after the options. Call before adding options: defaults are captured from then on.
void describe(CLI::App& app, const std::string& synopsis, const std::string& notes = {});

/// Parses argv into the variables bound to `app`'s options, then calls `run`; returns the exit
/// status above. No exception leaves it.
int cli_main(CLI::App& app, int argc, char** argv, const std::function<int()>& run);

/// A validator for option values that must be finite numbers greater than zero.
extern const CLI::Validator kPositive;

/// A transform for counts: decimal digits only. CLI11 alone would also read "-1" into an unsigned
/// (wrapped), "0x10" as hex and "010" as octal; the text is rewritten without leading zeros, so
/// "010" is ten.
extern const CLI::Validator kDecimal;

/// A validator of "--set KEY=VALUE" assignments: the form only (a key, "=", then the value, which
/// may be empty); the key and value are checked by config::apply_override when applied.
extern const CLI::Validator kAssignment;

/// The --set option every configurable program has, repeatable, each value KEY=VALUE (kAssignment:
/// one without "=" is a usage error, exit 2, before anything runs). `example` is one assignment.
CLI::Option* add_set_option(CLI::App& app, std::vector<std::string>& assignments, const std::string& example);

}  // namespace cvo::program
