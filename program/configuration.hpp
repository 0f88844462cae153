#pragma once
// The configuration a tool runs with: its --config file (a bad file is bad input, exit 1), then
// its --set overrides in order (a bad one is a usage error, exit 2: it was typed on the command
// line).
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "libcvo/config/config.hpp"

namespace cvo::program {

/// Throws config::ConfigError for the file, UsageError for an override.
config::Config configuration(const std::optional<std::filesystem::path>& file, const std::vector<std::string>& sets);

}  // namespace cvo::program
