#pragma once
// Line-oriented text files as the TUM benchmark writes them: whitespace- (or comma-) separated
// fields, '#' starts a comment, blank lines are skipped.
#include <cstddef>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>
#include <string_view>
#include <vector>

namespace cvo::io {

/// Calls fn(line_number, fields) for every non-empty, non-comment line (1-based numbers).
void for_each_data_line(std::istream& in, const std::filesystem::path& name,
                        const std::function<void(std::size_t, const std::vector<std::string>&)>& fn);

/// Parses a whole field as a finite double; throws InputError naming file and line otherwise.
double parse_finite(std::string_view field, const std::filesystem::path& name, std::size_t line);

}  // namespace cvo::io
