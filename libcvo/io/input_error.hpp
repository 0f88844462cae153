#pragma once
// The one exception type for bad input files: it always names the file, and the line when there
// is one, so a user can go straight to the problem.
#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace cvo::io {

class InputError : public std::runtime_error {
 public:
  InputError(const std::filesystem::path& file, std::size_t line, const std::string& what)
      : std::runtime_error(format(file, line, what)), file_(file), line_(line) {}
  InputError(const std::filesystem::path& file, const std::string& what) : InputError(file, 0, what) {}

  [[nodiscard]] const std::filesystem::path& file() const { return file_; }
  [[nodiscard]] std::size_t line() const { return line_; }  // 1-based; 0 when not about a line

 private:
  static std::string format(const std::filesystem::path& file, std::size_t line, const std::string& what);

  std::filesystem::path file_;
  std::size_t line_;
};

}  // namespace cvo::io
