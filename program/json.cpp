#include "program/json.hpp"

namespace cvo::program {
namespace {

constexpr auto kReplace = Json::error_handler_t::replace;

// A value without line breaks, objects as {"key": value, ...}.
std::string one_line(const Json& value) {
  if (!value.is_object()) return value.dump(-1, ' ', false, kReplace);
  std::string out = "{";
  for (const auto& [key, item] : value.items())
    out.append(out.size() > 1 ? ", " : "")
        .append(Json(key).dump(-1, ' ', false, kReplace))
        .append(": ")
        .append(one_line(item));
  return out + "}";
}

}  // namespace

std::string to_text(const Json& json) {
  if (!json.is_object()) return one_line(json) + "\n";
  std::string out = "{\n";
  std::size_t k = 0;
  for (const auto& [key, value] : json.items()) {
    out.append("  ").append(one_line(Json(key))).append(": ");
    if (value.is_array() && !value.empty()) {
      out.append("[");
      for (std::size_t i = 0; i < value.size(); ++i) out.append(i ? ",\n    " : "\n    ").append(one_line(value[i]));
      out.append("\n  ]");
    } else {
      out.append(one_line(value));
    }
    out.append(++k < json.size() ? ",\n" : "\n");
  }
  return out + "}\n";
}

std::string to_line(const Json& json) { return json.dump(-1, ' ', false, kReplace) + "\n"; }

}  // namespace cvo::program
