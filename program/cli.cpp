#include "program/cli.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "libcvo/io/input_error.hpp"

namespace cvo::program {
namespace {

constexpr const char* kExitStatuses = "exit status: 0 ok, 1 bad input or failure, 2 usage error";

// CLI11's formatter with the usage line first and in the project's words.
class Formatter : public CLI::Formatter {
 public:
  explicit Formatter(std::string synopsis) : synopsis_(std::move(synopsis)) {}

  std::string make_usage(const CLI::App*, std::string) const override { return "usage: " + synopsis_ + "\n"; }

  std::string make_help(const CLI::App* app, std::string name, CLI::AppFormatMode mode) const override {
    if (mode == CLI::AppFormatMode::Sub) return make_expanded(app);
    std::ostringstream out;
    std::string description = app->get_description();
    while (!description.empty() && description.back() == '\n') description.pop_back();
    out << make_usage(app, name) << "\n"
        << description << "\n"
        << make_positionals(app) << make_groups(app, mode) << make_subcommands(app, mode) << "\n"
        << make_footer(app);
    return out.str();
  }

  // An empty list (a repeatable option) is not a default worth showing.
  std::string make_option_opts(const CLI::Option* option) const override {
    std::string text = CLI::Formatter::make_option_opts(option);
    if (const auto at = text.find("=[]"); at != std::string::npos) text.erase(at, 3);
    return text;
  }

 private:
  std::string synopsis_;
};

// The usage line of the (sub)command the user was running.
std::string usage_line(const CLI::App& app) {
  const CLI::App* shown = &app;
  for (const CLI::App* sub = shown; sub != nullptr;) {
    shown = sub;
    const auto selected = sub->get_subcommands();
    sub = selected.empty() ? nullptr : selected.front();
  }
  const auto formatter = std::dynamic_pointer_cast<Formatter>(shown->get_formatter());
  return formatter ? formatter->make_usage(shown, shown->get_name()) : "usage: " + shown->get_name() + " [options]\n";
}

int usage_error(const CLI::App& app, const std::string& message) {
  std::cerr << app.get_name() << ": " << message << "\n"
            << usage_line(app) << "run '" << app.get_name() << " --help' for every option\n";
  return 2;
}

bool looks_like_number(const std::string& text) {
  double value = 0;
  return CLI::detail::lexical_cast(text, value);
}

// An option the program does not know, if the command line had one: the message to give first,
// even when a required argument is missing too (CLI11 reports that first).
// A word where a subcommand was required names the subcommand that does not exist.
std::optional<std::string> unknown_option(const CLI::App& app) {
  const auto remaining = app.remaining(true);
  for (const std::string& arg : remaining)
    if (arg.size() > 1 && arg.front() == '-' && !looks_like_number(arg)) return "unknown option '" + arg + "'";
  if (!remaining.empty() && app.get_require_subcommand_min() > 0 && app.get_subcommands().empty())
    return "unknown command '" + remaining.front() + "'";
  return std::nullopt;
}

}  // namespace

const CLI::Validator kPositive(
    [](const std::string& text) -> std::string {
      double value = 0;
      if (!CLI::detail::lexical_cast(text, value) || !std::isfinite(value) || value <= 0)
        return "needs a number greater than zero, not '" + text + "'";
      return {};
    },
    "> 0", "positive");

const CLI::Validator kDecimal(
    [](std::string& text) -> std::string {
      std::uint64_t value = 0;
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (error != std::errc() || end != text.data() + text.size())
        return "needs a whole number in decimal digits, not '" + text + "'";
      text = std::to_string(value);
      return {};
    },
    "", "decimal");

const CLI::Validator kAssignment(
    [](const std::string& text) -> std::string {
      const auto eq = text.find('=');
      if (eq == std::string::npos || text.find_first_not_of(" \t") == eq)
        return "needs KEY=VALUE, e.g. cvo.ell_init=0.15, not '" + text + "'";
      return {};
    },
    "", "assignment");

CLI::Option* add_set_option(CLI::App& app, std::vector<std::string>& assignments, const std::string& example) {
  return app
      .add_option("--set", assignments, "override one configuration key, e.g. --set " + example + " (repeatable)")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false)
      ->check(kAssignment);
}

void describe(CLI::App& app, const std::string& synopsis, const std::string& notes) {
  app.formatter(std::make_shared<Formatter>(synopsis));
  app.footer(notes.empty() ? std::string(kExitStatuses) : notes + "\n\n" + kExitStatuses);
  app.option_defaults()->always_capture_default();
  app.get_formatter()->column_width(28);
}

int cli_main(CLI::App& app, int argc, char** argv, const std::function<int()>& run) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::cout << app.help();
    return 0;
  } catch (const CLI::CallForAllHelp&) {
    std::cout << app.help("", CLI::AppFormatMode::All);
    return 0;
  } catch (const CLI::ParseError& e) {
    return usage_error(app, unknown_option(app).value_or(e.what()));
  }
  try {
    return run();
  } catch (const UsageError& e) {
    return usage_error(app, e.what());
  } catch (const io::InputError& e) {
    std::cerr << app.get_name() << ": " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {  // e.g. a filesystem error on an output
    std::cerr << app.get_name() << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace cvo::program
