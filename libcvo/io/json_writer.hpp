#pragma once
// The two pieces of hand-written JSON output the tools need: a quoted string and a number. The
// tools write their (flat) objects themselves; this keeps the escaping and the number format in
// one place so every tool's JSON reads the same.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

namespace cvo::io {

/// A JSON string literal: quotes, backslashes and control characters escaped; UTF-8 passes through.
inline std::string json_string(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

/// The shortest text that reads back to the same double; JSON has no NaN or infinity, so null.
inline std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc() ? std::string(buf, end) : "null";
}

/// null when there is no value.
inline std::string json_number(std::optional<double> v) { return v ? json_number(*v) : "null"; }

}  // namespace cvo::io
