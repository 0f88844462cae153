#pragma once
// The main() every command-line tool shares: its exit status is a contract scripts rely on.
//   0  success
//   1  bad input or a failure while running; the message on stderr names the file (io::InputError)
//   2  usage error: the message, then the usage text, on stderr
// --help (Arguments::help) prints the usage text on stdout and exits 0.
#include <exception>
#include <iostream>
#include <stdexcept>
#include <string_view>

#include "libcvo/io/input_error.hpp"

namespace cvo::tools {

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// parse(argc, argv) -> Arguments (throws UsageError); run(const Arguments&) -> exit status.
template <class Parse, class Run>
int cli_main(std::string_view name, std::string_view usage, int argc, char** argv, Parse parse, Run run) {
  const auto usage_error = [&](const UsageError& e) {
    std::cerr << name << ": " << e.what() << "\n\n" << usage;
    return 2;
  };
  decltype(parse(argc, argv)) args;
  try {
    args = parse(argc, argv);
  } catch (const UsageError& e) {
    return usage_error(e);
  }
  if (args.help) {
    std::cout << usage;
    return 0;
  }
  try {
    return run(args);
  } catch (const UsageError& e) {
    return usage_error(e);
  } catch (const io::InputError& e) {
    std::cerr << name << ": " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {  // e.g. a filesystem error on an output
    std::cerr << name << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace cvo::tools
