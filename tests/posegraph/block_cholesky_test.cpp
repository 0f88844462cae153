// The 6x6-block Cholesky factorisation of small graphs (block_cholesky.hpp), and the serial
// OpenMP scope of CHOLMOD's factorisation (cholmod_handles.hpp).
#include "libcvo/posegraph/block_cholesky.hpp"

#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <omp.h>

#include "libcvo/posegraph/cholmod_handles.hpp"

namespace cvo::posegraph::detail {
namespace {

// A CHOLMOD upper triangle laid out as the optimiser's (optimizer.cpp, allocate_matrix): column
// 6C + c holds, for each block row R of column C in order, rows 6R.. 6R + 5 (R < C) or
// 6C .. 6C + c (the diagonal block, last). The vectors own the storage.
struct UpperTriangle {
  std::vector<SuiteSparse_long> p, i;
  std::vector<double> x;
  cholmod_sparse matrix{};

  UpperTriangle(const Eigen::MatrixXd& H, const std::vector<std::vector<int>>& column_blocks) {
    const auto n = static_cast<int>(column_blocks.size());
    for (int C = 0; C < n; ++C)
      for (int c = 0; c < 6; ++c) {
        p.push_back(static_cast<SuiteSparse_long>(i.size()));
        for (const int R : column_blocks[C])
          for (int r = 0; r < (R < C ? 6 : c + 1); ++r) {
            i.push_back(6 * R + r);
            x.push_back(H(6 * R + r, 6 * C + c));
          }
      }
    p.push_back(static_cast<SuiteSparse_long>(i.size()));
    matrix.nrow = matrix.ncol = 6 * n;
    matrix.p = p.data();
    matrix.i = i.data();
    matrix.x = x.data();
  }
};

// Blocks 0-1-2-3-4 in a chain with a loop 0-4 and a chord 1-3: eliminating in the order below
// makes fill (blocks of L that H lacks).
const std::vector<std::vector<int>> kPattern = {{0}, {0, 1}, {1, 2}, {1, 2, 3}, {0, 3, 4}};
const std::vector<int> kOrder = {2, 0, 4, 1, 3};

// A symmetric positive definite H with the pattern's blocks (random values, diagonally dominant).
Eigen::MatrixXd random_spd(const std::vector<std::vector<int>>& pattern) {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto n = static_cast<int>(pattern.size());
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(6 * n, 6 * n);
  for (int C = 0; C < n; ++C)
    for (const int R : pattern[C]) {
      const Eigen::MatrixXd block = Eigen::MatrixXd::NullaryExpr(6, 6, [&] { return unit(random); });
      H.block<6, 6>(6 * R, 6 * C) = block;
      H.block<6, 6>(6 * C, 6 * R) = block.transpose();
    }
  H = 0.5 * (H + H.transpose()).eval();
  H.diagonal().array() += 6.0 * n;
  return H;
}

TEST(BlockCholesky, SolvesLikeADenseCholeskyWhateverTheOrder) {
  const Eigen::MatrixXd H = random_spd(kPattern);
  UpperTriangle upper(H, kPattern);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(H.rows(), -1.0, 2.0);
  const Eigen::VectorXd expected = H.llt().solve(b);
  for (const auto& order : {kOrder, std::vector<int>{0, 1, 2, 3, 4}, std::vector<int>{4, 3, 2, 1, 0}}) {
    BlockCholesky factor(kPattern, order);
    EXPECT_FALSE(factor.factorized());
    ASSERT_TRUE(factor.factorize(upper.matrix));
    EXPECT_TRUE(factor.factorized());
    const Eigen::Map<const Eigen::VectorXd> x(factor.solve(b.data()), b.size());
    EXPECT_LT((x - expected).norm(), 1e-12 * expected.norm()) << order[0];
  }
}

TEST(BlockCholesky, RefactorisesNewValuesOnTheSameStructure) {
  BlockCholesky factor(kPattern, kOrder);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(30);
  for (const double shift : {0.0, 100.0}) {
    Eigen::MatrixXd H = random_spd(kPattern);
    H.diagonal().array() += shift;
    UpperTriangle upper(H, kPattern);
    ASSERT_TRUE(factor.factorize(upper.matrix));
    const Eigen::Map<const Eigen::VectorXd> x(factor.solve(b.data()), b.size());
    EXPECT_LT((H * x - b).norm(), 1e-12 * b.norm()) << shift;
  }
}

TEST(BlockCholesky, RefusesAMatrixThatIsNotPositiveDefinite) {
  for (const double pivot : {-1.0, std::nan("")}) {
    Eigen::MatrixXd H = random_spd(kPattern);
    H(6 * 3 + 2, 6 * 3 + 2) = pivot;  // block 3 is eliminated last: its pivot fails after the updates
    UpperTriangle upper(H, kPattern);
    BlockCholesky factor(kPattern, kOrder);
    EXPECT_FALSE(factor.factorize(upper.matrix)) << pivot;
    EXPECT_FALSE(factor.factorized());
  }
}

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
    const SerialOpenMp serial;
    EXPECT_EQ(team(), 1);
  }
  EXPECT_EQ(omp_get_max_active_levels(), before);
  if (before >= 1) {
    EXPECT_EQ(team(), 4);
  }
}

}  // namespace
}  // namespace cvo::posegraph::detail
