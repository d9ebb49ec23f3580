// The Newton check's factor (sim/hessian_factor.hpp): supernodal and simplicial give the same
// solves, both refuse a matrix that is not positive definite (Newton then shifts it), the
// analysis kept for a pattern serves new values, and `automatic` chooses by size.

#include "sim/hessian_factor.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace phantasm {
namespace {

/// A matrix with a Newton Hessian's pattern on an n^3 grid of vertices: a 3 x 3 block per pair of
/// neighbours (the grid graph's Laplacian plus `diagonal` - 6 times the identity, times an SPD
/// block), lower triangle stored. Positive definite for diagonal > 0.
Eigen::SparseMatrix<double> block_grid(int n, double diagonal) {
  Eigen::Matrix3d block;
  block << 1.0, 0.2, 0.1, 0.2, 1.0, 0.2, 0.1, 0.2, 1.0;
  std::vector<Eigen::Triplet<double>> entries;
  const auto add = [&](int i, int j, double weight) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        if (3 * i + r >= 3 * j + c) entries.emplace_back(3 * i + r, 3 * j + c, weight * block(r, c));
  };
  const auto vertex = [n](int i, int j, int k) { return (k * n + j) * n + i; };
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        add(vertex(i, j, k), vertex(i, j, k), 6.0 + diagonal);
        if (i > 0) add(vertex(i, j, k), vertex(i - 1, j, k), -1.0);
        if (j > 0) add(vertex(i, j, k), vertex(i, j - 1, k), -1.0);
        if (k > 0) add(vertex(i, j, k), vertex(i, j, k - 1), -1.0);
      }
  Eigen::SparseMatrix<double> H(3 * n * n * n, 3 * n * n * n);
  H.setFromTriplets(entries.begin(), entries.end());
  return H;
}

/// The full symmetric matrix of a stored lower triangle.
Eigen::SparseMatrix<double> symmetric(const Eigen::SparseMatrix<double>& lower) {
  return lower.selfadjointView<Eigen::Lower>();
}

TEST(HessianFactor, AutomaticIsSupernodalFromItsThresholdOn) {
  EXPECT_FALSE(HessianFactor(HessianFactor::k_supernodal_rows - 1).supernodal());
  EXPECT_TRUE(HessianFactor(HessianFactor::k_supernodal_rows).supernodal());
  EXPECT_FALSE(HessianFactor(100000, HessianFactor::Factorization::simplicial).supernodal());
  EXPECT_TRUE(HessianFactor(3, HessianFactor::Factorization::supernodal).supernodal());
}

TEST(HessianFactor, SupernodalSolvesAsSimplicialAndBothRefuseAnIndefiniteMatrix) {
  // 13^3 vertices, 6591 rows: supernodal under `automatic`.
  const Eigen::SparseMatrix<double> H = block_grid(13, 0.05);
  ASSERT_GE(H.rows(), HessianFactor::k_supernodal_rows);
  const Eigen::VectorXd b = Eigen::VectorXd::Random(H.rows());
  HessianFactor simplicial(H.rows(), HessianFactor::Factorization::simplicial), supernodal(H.rows());
  ASSERT_TRUE(supernodal.supernodal());
  ASSERT_TRUE(simplicial.factorize(H, 0.0));
  ASSERT_TRUE(supernodal.factorize(H, 0.0));
  const Eigen::VectorXd reference = simplicial.solve(b), x = supernodal.solve(b);
  EXPECT_LT((x - reference).norm(), 1e-10 * reference.norm());
  EXPECT_LT((symmetric(H) * x - b).norm(), 1e-10 * b.norm());

  // Shifted below its smallest eigenvalue (about 0.05 x the block's smallest, 0.8) the matrix is
  // indefinite: both refuse it, as Newton's shift loop needs; a shift up makes it definite again.
  for (HessianFactor* factor : {&simplicial, &supernodal}) {
    EXPECT_FALSE(factor->factorize(H, -0.5));
    ASSERT_TRUE(factor->factorize(H, 1.0));
    const Eigen::VectorXd shifted = factor->solve(b);
    Eigen::SparseMatrix<double> I(H.rows(), H.rows());
    I.setIdentity();
    EXPECT_LT(((symmetric(H) + I) * shifted - b).norm(), 1e-10 * b.norm());
  }
}

TEST(HessianFactor, TheKeptAnalysisServesNewValuesOfThePattern) {
  const Eigen::SparseMatrix<double> first = block_grid(12, 0.05);
  Eigen::SparseMatrix<double> second = block_grid(12, 2.0); // same pattern, other values
  const Eigen::VectorXd b = Eigen::VectorXd::Random(first.rows());
  HessianFactor factor(first.rows(), HessianFactor::Factorization::supernodal);
  ASSERT_TRUE(factor.factorize(first, 0.0));
  ASSERT_TRUE(factor.factorize(second, 0.0));
  EXPECT_LT((symmetric(second) * factor.solve(b) - b).norm(), 1e-10 * b.norm());
}

} // namespace
} // namespace phantasm
