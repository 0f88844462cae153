// CHOLMOD's messages go to standard error, never into a program's standard output; its
// factorisations run serially (SerialOpenMp).
#include <string>

#include <cholmod.h>
#include <gtest/gtest.h>
#include <omp.h>

#include "libcvo/posegraph/cholmod_handles.hpp"
#include "libcvo/posegraph/optimizer.hpp"

namespace cvo::posegraph {
namespace {

// Another library's CHOLMOD (Ceres') starts with the default print level, 3, which prints
// warnings; the supernodal factorisation of an indefinite matrix gives one ("not positive
// definite"). By default it would be printed on standard output.
TEST(CholmodMessages, GoToStandardErrorNotStandardOutput) {
  send_cholmod_messages_to_stderr();
  cholmod_common common;
  cholmod_l_start(&common);
  common.supernodal = CHOLMOD_SUPERNODAL;  // the simplicial LDL' would factorise it without a word
  cholmod_sparse* A =
      cholmod_l_allocate_sparse(2, 2, 3, /*sorted=*/1, /*packed=*/1, /*stype=upper*/ 1, CHOLMOD_REAL, &common);
  ASSERT_NE(A, nullptr);
  auto* p = static_cast<SuiteSparse_long*>(A->p);
  auto* i = static_cast<SuiteSparse_long*>(A->i);
  auto* x = static_cast<double*>(A->x);
  p[0] = 0, p[1] = 1, p[2] = 3;
  i[0] = 0, i[1] = 0, i[2] = 1;
  x[0] = 1, x[1] = 2, x[2] = 1;  // [[1, 2], [2, 1]]: eigenvalues 3 and -1
  cholmod_factor* L = cholmod_l_analyze(A, &common);

  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  cholmod_l_factorize(A, L, &common);
  const std::string out = ::testing::internal::GetCapturedStdout();
  const std::string err = ::testing::internal::GetCapturedStderr();

  EXPECT_EQ(common.status, CHOLMOD_NOT_POSDEF);
  EXPECT_EQ(out, "");
  EXPECT_NE(err.find("not positive definite"), std::string::npos) << err;
  cholmod_l_free_factor(&L, &common);
  cholmod_l_free_sparse(&A, &common);
  cholmod_l_finish(&common);
}

// A scope that runs this thread's OpenMP regions alone, and gives the setting back after.
TEST(SerialOpenMp, RunsThisThreadsRegionsAloneAndRestoresTheSetting) {
  const int before = omp_get_max_active_levels();
  const auto team = [] {
    int size = 0;
#pragma omp parallel num_threads(4)
    {
#pragma omp single
      size = omp_get_num_threads();
    }
    return size;
  };
  {
    const detail::SerialOpenMp serial;
    EXPECT_EQ(team(), 1);
  }
  EXPECT_EQ(omp_get_max_active_levels(), before);
  if (before >= 1) {
    EXPECT_EQ(team(), 4);
  }
}

}  // namespace
}  // namespace cvo::posegraph
