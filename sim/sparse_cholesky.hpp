// SparseCholesky: CHOLMOD's simplicial LDL^T factor behind a small interface, with multi-column
// solves and rank-one updates of the diagonal for contacts that come and go.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <memory>
#include <utility>
#include <vector>

namespace phantasm {

/// The sparse Cholesky factor of a symmetric positive definite matrix (CHOLMOD behind a small
/// interface): solves with several right-hand sides in one pass over the factor, and changes of
/// the matrix's diagonal applied by rank-one updates and downdates of the factor instead of a
/// new factorization (contacts that come and go). The factor is simplicial LDL^T, what
/// cholmod_updown works on; its solves are also faster here than the supernodal factor's, whose
/// many small BLAS calls cost more than they save at these sizes (the bar's three-column solve
/// 0.045 vs 0.13 ms, the 43k-tet solid's 1.4 vs 2.0 ms: bench_sim). From k_supernodal_rows rows
/// up the factorization itself is supernodal (BLAS on one thread: the same bits on any machine),
/// then converted to that simplicial LDL^T with the relaxed supernodes' stored zeros dropped, so
/// the solves read the same pattern: a compact body of 10 648 vertices factors in 163 ms
/// against 380 ms simplicial, the twisting bar's 1421 in 7.9 ms against 2.1 ms (bench_sim,
/// sparse_cholesky_factor). Rank-one changes may fill in the factor's pattern (cholmod_updown
/// handles it).
class SparseCholesky {
public:
  /// How the factor is computed (the result is a simplicial LDL^T either way).
  enum class Factorization { automatic, simplicial, supernodal };

  /// Rows from which `automatic` factors supernodally.
  static constexpr long k_supernodal_rows = 5000;

  /// Factors A, given by its lower triangle (fill-reducing ordering by CHOLMOD, or the last
  /// analysis when it was of A's pattern: analyses()).
  /// @throws std::runtime_error when A is not positive definite
  explicit SparseCholesky(const Eigen::SparseMatrix<double>& lower,
                          Factorization factorization = Factorization::automatic);
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  /// Systems from this many rows up are solved on two threads when asked.
  static constexpr std::size_t k_split_rows = 4000;

  /// x = A^-1 b for the columns of b (no allocation once the sizes repeat). With threads >= 2
  /// and at least k_split_rows rows, two columns are solved on one thread and the third on
  /// another (the same results: each column's solve is independent).
  void solve(const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x, int threads = 1);

  /// x.col(column) = A^-1 b.col(column) (x already sized as b).
  void solve_column(const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x, int column);

  /// A <- A + sum of delta e_row e_row^T over `changes` (row, delta): positive deltas by a
  /// rank update, negative ones by a downdate, both in one call each.
  /// @throws std::runtime_error when a downdate leaves A not positive definite
  void update_diagonal(const std::vector<std::pair<int, double>>& changes);

  /// A column of a rank-one change c c^T: (row, value) entries.
  using Column = std::vector<std::pair<int, double>>;

  /// A <- A + sum over `add` of c c^T - sum over `remove` of c c^T (updates first, so the
  /// matrix stays positive definite in between; the factor's pattern grows where c c^T fills
  /// in, e.g. a contact between two bodies).
  /// @throws std::runtime_error when a downdate leaves A not positive definite
  void update_columns(const std::vector<Column>& add, const std::vector<Column>& remove);

  /// Rank-one changes applied so far.
  long rank_changes() const;

  /// Analyses (fill-reducing ordering and symbolic factor) made by this process. A factor of the
  /// pattern and kind (simplicial or supernodal) of the last analysis copies it instead: the
  /// same analysis, so the same factor bit for bit (a growth load's recalibrating solves factor
  /// one body's matrix five times).
  static long analyses();

private:
  struct Impl;
  std::unique_ptr<Impl> m;
};

/// The global matrix of the three coordinates of every vertex (K (x) I_3): one factor for all
/// three, or one per coordinate when rank-one changes differ between coordinates (a contact
/// with an obstacle stiffens its vertex along the obstacle's normal only).
class CoordinateFactors {
public:
  /// Factors A (its lower triangle) once, or three times when per_coordinate.
  /// @throws std::runtime_error when A is not positive definite
  CoordinateFactors(const Eigen::SparseMatrix<double>& lower, bool per_coordinate);

  /// Whether each coordinate has a factor of its own.
  bool per_coordinate() const { return m_factors.size() == 3; }
  /// The factor coordinate c (0..2) is solved with.
  SparseCholesky& operator[](int c) { return *m_factors[per_coordinate() ? static_cast<std::size_t>(c) : 0]; }

  /// x = A_c^-1 b_c per coordinate c (the same results for any number of threads).
  void solve(const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x, int threads);

  /// The same update_columns on every coordinate's factor.
  void update_all(const std::vector<SparseCholesky::Column>& add,
                  const std::vector<SparseCholesky::Column>& remove);

  /// Rank-one changes applied so far, over all factors.
  long rank_changes() const;

private:
  std::vector<std::unique_ptr<SparseCholesky>> m_factors;
};

} // namespace phantasm
