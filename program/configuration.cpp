#include "program/configuration.hpp"

#include "program/cli.hpp"

namespace cvo::program {

config::Config configuration(const std::optional<std::filesystem::path>& file, const std::vector<std::string>& sets) {
  config::Config config = file ? config::load_config(*file) : config::Config{};
  for (const auto& assignment : sets) {
    try {
      config::apply_override(config, assignment);
    } catch (const config::ConfigError& e) {
      throw UsageError(e.what());
    }
  }
  return config;
}

}  // namespace cvo::program
