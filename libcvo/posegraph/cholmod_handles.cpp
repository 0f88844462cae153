#include "libcvo/posegraph/cholmod_handles.hpp"

#include <cstdarg>
#include <cstdio>
#include <mutex>

#include "libcvo/posegraph/optimizer.hpp"

namespace cvo::posegraph {
namespace {

// CHOLMOD's printf (SuiteSparse_config.printf_func) with standard error as its stream.
__attribute__((format(printf, 1, 2))) int print_to_stderr(const char* format, ...) {
  va_list arguments;
  va_start(arguments, format);
  const int written = std::vfprintf(stderr, format, arguments);
  va_end(arguments);
  return written;
}

// Common->error_handler: errors (status < 0: out of memory, invalid input) go to the log.
void log_cholmod_error(int status, const char* file, int line, const char* message) {
  if (status < 0)
    std::fprintf(stderr, "CHOLMOD error %d: %s (%s:%d)\n", status, message != nullptr ? message : "",
                 file != nullptr ? file : "?", line);
}

}  // namespace

void send_cholmod_messages_to_stderr() {
  static std::once_flag once;
  std::call_once(once, [] { SuiteSparse_config.printf_func = print_to_stderr; });
}

namespace detail {

CholmodCommon::CholmodCommon() {
  send_cholmod_messages_to_stderr();
  cholmod_l_start(&common_);
  common_.print = 0;  // CHOLMOD prints nothing itself ...
  common_.error_handler = log_cholmod_error;  // ... real errors are logged here
}

}  // namespace detail
}  // namespace cvo::posegraph
