#pragma once
// RAII ownership of CHOLMOD's objects (the 64-bit-index "cholmod_l_" interface). Internal to the
// posegraph library: only .cpp files include this, so users never see cholmod.h.
//
// Every cholmod object is freed through the cholmod_common that made it, so a Cholmod bundle owns
// the common and the objects together, declared in that order: members are destroyed in reverse,
// the objects before the common. The bundle is neither copyable nor movable (the deleters hold the
// common's address); own it through a std::unique_ptr to move it.
#include <memory>

#include <cholmod.h>

namespace cvo::posegraph::detail {

class CholmodCommon {
 public:
  /// Started with CHOLMOD's output sent to standard error (send_cholmod_messages_to_stderr) and
  /// only real errors logged: a warning (status > 0: not positive definite) is the caller's to
  /// handle, and CHOLMOD's print level 1 would print it as an error anyway.
  CholmodCommon();
  ~CholmodCommon() { cholmod_l_finish(&common_); }
  CholmodCommon(const CholmodCommon&) = delete;
  CholmodCommon& operator=(const CholmodCommon&) = delete;
  CholmodCommon(CholmodCommon&&) = delete;
  CholmodCommon& operator=(CholmodCommon&&) = delete;

  cholmod_common* get() { return &common_; }

 private:
  cholmod_common common_{};
};

struct SparseDeleter {
  cholmod_common* common = nullptr;
  void operator()(cholmod_sparse* p) const { cholmod_l_free_sparse(&p, common); }
};
struct FactorDeleter {
  cholmod_common* common = nullptr;
  void operator()(cholmod_factor* p) const { cholmod_l_free_factor(&p, common); }
};
struct DenseDeleter {
  cholmod_common* common = nullptr;
  void operator()(cholmod_dense* p) const { cholmod_l_free_dense(&p, common); }
};

using SparsePtr = std::unique_ptr<cholmod_sparse, SparseDeleter>;
using FactorPtr = std::unique_ptr<cholmod_factor, FactorDeleter>;
using DensePtr = std::unique_ptr<cholmod_dense, DenseDeleter>;

/// While alive, the OpenMP parallel regions this thread starts run on this thread alone: OpenMP's
/// max-active-levels, a per-thread setting, is 0 (no region is active), and the previous value
/// comes back at the end of the scope. Other threads, and this one afterwards, are unaffected.
class SerialOpenMp {
 public:
  SerialOpenMp();
  ~SerialOpenMp();
  SerialOpenMp(const SerialOpenMp&) = delete;
  SerialOpenMp& operator=(const SerialOpenMp&) = delete;
  SerialOpenMp(SerialOpenMp&&) = delete;
  SerialOpenMp& operator=(SerialOpenMp&&) = delete;

 private:
  int saved_levels_;
};

/// A common with the matrix, its factor and the dense workspaces of its solves, all belonging to
/// it. The workspaces (right-hand side, solution, and cholmod_l_solve2's Y and E) are kept between
/// solves, so a solve allocates nothing once their size is set.
struct Cholmod {
  CholmodCommon common;
  SparsePtr matrix{nullptr, SparseDeleter{common.get()}};
  FactorPtr factor{nullptr, FactorDeleter{common.get()}};
  DensePtr rhs{nullptr, DenseDeleter{common.get()}};
  DensePtr solution{nullptr, DenseDeleter{common.get()}};
  DensePtr solve_y{nullptr, DenseDeleter{common.get()}};
  DensePtr solve_e{nullptr, DenseDeleter{common.get()}};
  double factor_flops = 0;     // of one numeric factorisation, from the symbolic analysis
  double factor_nonzeros = 0;  // nnz(L), likewise
  bool factorized = false;     // factor holds the numeric factorisation of a positive definite matrix

  DensePtr wrap(cholmod_dense* p) { return DensePtr(p, DenseDeleter{common.get()}); }
  SparsePtr wrap(cholmod_sparse* p) { return SparsePtr(p, SparseDeleter{common.get()}); }
  FactorPtr wrap(cholmod_factor* p) { return FactorPtr(p, FactorDeleter{common.get()}); }

  /// Numeric factorisation of matrix into factor (whose symbolic analysis it must hold); false
  /// when the matrix is not positive definite. Sets `factorized` to the result.
  ///
  /// It runs serially (SerialOpenMp). CHOLMOD's supernodal factorisation does its dense work in
  /// the BLAS (serial here) and wraps a few memory-bound loops (scattering H into a supernode,
  /// adding an update into its ancestor) in OpenMP regions of a compiled-in 4 threads. A pose
  /// graph's supernodes are small (tens of columns), so those loops are short and each region's
  /// fork and join costs more than the loop; with fewer cores than threads the team also
  /// competes with the thread that waits for it.
  bool factorize();
  /// x = A^-1 b with the factor of the last successful factorize(); b and the result have
  /// matrix->nrow entries. The result points into `solution`, valid until the next solve. Throws
  /// std::runtime_error when CHOLMOD fails (out of memory).
  const double* solve(const double* b);
};

}  // namespace cvo::posegraph::detail
