#include "libcvo/posegraph/cholmod_handles.hpp"

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <mutex>
#include <stdexcept>

#include <omp.h>

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
  common_.print = 0;                          // CHOLMOD prints nothing itself ...
  common_.error_handler = log_cholmod_error;  // ... real errors are logged here
}

SerialOpenMp::SerialOpenMp() : saved_levels_(omp_get_max_active_levels()) { omp_set_max_active_levels(0); }

SerialOpenMp::~SerialOpenMp() { omp_set_max_active_levels(saved_levels_); }

bool Cholmod::factorize() {
  const SerialOpenMp serial;
  cholmod_common* cc = common.get();
  factorized = cholmod_l_factorize(matrix.get(), factor.get(), cc) != 0 && cc->status != CHOLMOD_NOT_POSDEF;
  return factorized;
}

const double* Cholmod::solve(const double* b) {
  cholmod_common* cc = common.get();
  const std::size_t n = matrix->nrow;
  if (!rhs || rhs->nrow != n) {
    rhs = wrap(cholmod_l_allocate_dense(n, 1, n, CHOLMOD_REAL, cc));
    if (!rhs) throw std::runtime_error("pose graph: CHOLMOD could not allocate the right-hand side");
  }
  std::copy(b, b + n, static_cast<double*>(rhs->x));
  // solve2 reuses (or resizes) solution, Y and E instead of allocating them on every call.
  cholmod_dense* x = solution.release();
  cholmod_dense* y = solve_y.release();
  cholmod_dense* e = solve_e.release();
  const int ok = cholmod_l_solve2(CHOLMOD_A, factor.get(), rhs.get(), nullptr, &x, nullptr, &y, &e, cc);
  solution = wrap(x);
  solve_y = wrap(y);
  solve_e = wrap(e);
  if (!ok || !solution) throw std::runtime_error("pose graph: CHOLMOD solve failed");
  return static_cast<const double*>(solution->x);
}

}  // namespace detail
}  // namespace cvo::posegraph
