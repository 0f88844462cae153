#include "libcvo/io/numbers.hpp"

#include <charconv>
#include <cmath>

namespace cvo::io {
namespace {

// from_chars rejects a leading '+', which people write in config files.
std::string_view drop_plus(std::string_view s) {
  return (s.size() > 1 && s.front() == '+' && s[1] != '-' && s[1] != '+') ? s.substr(1) : s;
}

}  // namespace

std::optional<double> to_finite(std::string_view field) {
  const auto s = drop_plus(field);
  double value = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (s.empty() || ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::optional<long long> to_integer(std::string_view field) {
  const auto s = drop_plus(field);
  long long value = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (s.empty() || ec != std::errc() || ptr != s.data() + s.size()) return std::nullopt;
  return value;
}

std::optional<bool> to_bool(std::string_view field) {
  for (const std::string_view t : {"true", "True", "TRUE"})
    if (field == t) return true;
  for (const std::string_view f : {"false", "False", "FALSE"})
    if (field == f) return false;
  return std::nullopt;
}

}  // namespace cvo::io
