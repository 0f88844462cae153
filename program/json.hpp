#pragma once
// JSON the programs print (cvo-run --json, cvo-eval --json, ...) and read, through nlohmann-json.
// ordered_json keeps keys in the order they are set, so a report reads in the order it is built.
#include <nlohmann/json.hpp>

#include <optional>
#include <string>

namespace cvo::program {

using Json = nlohmann::ordered_json;

/// Two-space indented text and a final newline. NaN and infinity print as null (JSON has neither);
/// bytes that are not UTF-8 (a file name) print as U+FFFD rather than failing the report.
inline std::string to_text(const Json& json) {
  return json.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

/// One line, no spaces: for output that other programs read a line at a time.
inline std::string to_line(const Json& json) {
  return json.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

/// A value, or null when there is none.
template <class T>
Json or_null(const std::optional<T>& value) {
  return value ? Json(*value) : Json(nullptr);
}

}  // namespace cvo::program
