#include "libcvo/io/input_error.hpp"

namespace cvo::io {

std::string InputError::format(const std::filesystem::path& file, std::size_t line, const std::string& what) {
  // Built with append(): GCC 12 warns falsely (-Wrestrict) on chained operator+ here.
  std::string message = file.string();
  if (line != 0) message.append(":").append(std::to_string(line));
  message.append(": ").append(what);
  return message;
}

}  // namespace cvo::io
