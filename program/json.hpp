#pragma once
// JSON the programs print (cvo-run --json, cvo-eval --json, ...) and read, through nlohmann-json.
// ordered_json keeps keys in the order they are set, so a report reads in the order it is built.
#include <nlohmann/json.hpp>

#include <optional>
#include <string>

namespace cvo::program {

using Json = nlohmann::ordered_json;

/// The project's layout of a report: one key a line, each element of a list on a line of its own
/// (a failed frame, a loop, a session), anything deeper on that line as {"key": value, ...}, so
/// that scripts can grep a row. NaN and infinity print as null (JSON has neither); bytes that are
/// not UTF-8 (a file name) print as U+FFFD rather than failing the report.
std::string to_text(const Json& json);

/// One line, no spaces: for output that other programs read a line at a time.
std::string to_line(const Json& json);

/// A value, or null when there is none.
template <class T>
Json or_null(const std::optional<T>& value) {
  return value ? Json(*value) : Json(nullptr);
}

}  // namespace cvo::program
