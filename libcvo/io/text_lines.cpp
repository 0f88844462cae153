#include "libcvo/io/text_lines.hpp"

#include <charconv>
#include <cmath>
#include <istream>
#include <sstream>

#include "libcvo/io/input_error.hpp"

namespace cvo::io {

void for_each_data_line(std::istream& in, const std::filesystem::path& name,
                        const std::function<void(std::size_t, const std::vector<std::string>&)>& fn) {
  std::string line;
  std::vector<std::string> fields;
  for (std::size_t line_no = 1; std::getline(in, line); ++line_no) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    for (char& c : line)
      if (c == ',' || c == '\t' || c == '\r') c = ' ';
    fields.clear();
    std::istringstream ss(line);
    for (std::string f; ss >> f;) fields.push_back(f);
    if (!fields.empty()) fn(line_no, fields);
  }
  if (in.bad()) throw InputError(name, "read error");
}

double parse_finite(std::string_view field, const std::filesystem::path& name, std::size_t line) {
  double value = 0;
  const auto [ptr, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (ec != std::errc() || ptr != field.data() + field.size())
    throw InputError(name, line, "not a number: '" + std::string(field) + "'");
  if (!std::isfinite(value)) throw InputError(name, line, "not a finite number: '" + std::string(field) + "'");
  return value;
}

}  // namespace cvo::io
