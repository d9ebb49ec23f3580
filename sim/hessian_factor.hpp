// HessianFactor: CHOLMOD's LL^T factor of the Newton check's projected Hessian, simplicial or
// supernodal by size (sim/newton.cpp). Its own file so that the benchmark and the tests reach the
// factor Newton uses; CHOLMOD stays behind it.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <memory>

namespace phantasm {

class HessianFactor {
public:
  enum class Factorization {
    automatic,  ///< supernodal from k_supernodal_rows rows, simplicial below
    simplicial, ///< column by column
    supernodal  ///< dense blocks through BLAS, on one thread (SingleThreadedBlas)
  };
  /// Rows from which `automatic` factors supernodally: the supernodal factor's many small BLAS
  /// calls cost more than they save on small bodies (the twisting bar, 3969 rows: 16 against 34
  /// ms a factorization); above, its dense blocks win, more the larger and more compact the body
  /// (bench_sim's newton_hessian_factor on cubes: 6591 rows 107 against 51 ms, 14 739 rows 387
  /// against 123 ms; the tests' coarse Colin head, 17 130 rows, 2.3-2.9 s against 0.25 s; the
  /// main job's body, 27 000 rows, 9.4 against 1.5 s; docs/performance.md, Deformation).
  static constexpr Eigen::Index k_supernodal_rows = 5000;

  /// A factor for matrices of `rows` rows (free coordinates).
  explicit HessianFactor(Eigen::Index rows, Factorization kind = Factorization::automatic);
  ~HessianFactor();
  HessianFactor(const HessianFactor&) = delete;
  HessianFactor& operator=(const HessianFactor&) = delete;

  /// Factors H + shift I (H's lower triangle is read); false when it is not positive definite.
  /// The symbolic analysis (fill-reducing ordering, elimination tree) is kept while H's pattern
  /// stays the same, as it does between Newton iterations unless contacts come or go.
  bool factorize(const Eigen::SparseMatrix<double>& H, double shift);
  /// (H + shift I)^-1 b with the last factor.
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  bool supernodal() const { return m_supernodal; }

private:
  struct Impl;
  std::unique_ptr<Impl> m;
  bool m_supernodal = false;
};

} // namespace phantasm
