#include "sim/sparse_cholesky.hpp"

#include "sim/single_threaded_blas.hpp"

#include <cholmod.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <string>

namespace phantasm {
namespace {

/// The last symbolic analysis (fill-reducing ordering, elimination tree, supernodes) with the
/// pattern and kind it was made for. A solve that recalibrates a load (growth: five solves of one
/// body) factors matrices of one pattern again and again; the analysis, over a tenth of a second
/// on a head's body (METIS), is then copied instead of made again. The copy is the analysis
/// itself, so the factor is the same, bit for bit.
class LastAnalysis {
public:
  LastAnalysis() { cholmod_start(&m_common); }
  ~LastAnalysis() {
    cholmod_free_factor(&m_symbolic, &m_common);
    cholmod_finish(&m_common);
  }
  LastAnalysis(const LastAnalysis&) = delete;
  LastAnalysis& operator=(const LastAnalysis&) = delete;

  /// A copy of the analysis of A's pattern made with `common`, or null when the last one is of
  /// another pattern or kind.
  cholmod_factor* copy(const Eigen::SparseMatrix<double>& A, bool supernodal, cholmod_common& common) {
    const std::lock_guard<std::mutex> lock(m_mutex);
    if (m_symbolic == nullptr || supernodal != m_supernodal || !same_pattern(A)) return nullptr;
    return cholmod_copy_factor(m_symbolic, &common);
  }

  /// Keeps a copy of `symbolic`, the analysis of A's pattern.
  void keep(const Eigen::SparseMatrix<double>& A, bool supernodal, cholmod_factor* symbolic) {
    const std::lock_guard<std::mutex> lock(m_mutex);
    cholmod_free_factor(&m_symbolic, &m_common);
    m_symbolic = cholmod_copy_factor(symbolic, &m_common);
    m_supernodal = supernodal;
    m_outer.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1);
    m_inner.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
  }

private:
  bool same_pattern(const Eigen::SparseMatrix<double>& A) const {
    return m_outer.size() == static_cast<std::size_t>(A.outerSize() + 1) &&
           m_inner.size() == static_cast<std::size_t>(A.nonZeros()) &&
           std::equal(m_outer.begin(), m_outer.end(), A.outerIndexPtr()) &&
           std::equal(m_inner.begin(), m_inner.end(), A.innerIndexPtr());
  }

  std::mutex m_mutex;
  cholmod_common m_common{};
  cholmod_factor* m_symbolic = nullptr;
  bool m_supernodal = false;
  std::vector<int> m_outer, m_inner;
};

std::atomic<long> g_analyses{0};

LastAnalysis& last_analysis() {
  static LastAnalysis analysis;
  return analysis;
}

} // namespace

/// cholmod_solve2's reusable workspaces of one solve, with the common block it runs with.
struct SolveWorkspace {
  cholmod_common common{};
  cholmod_dense* x = nullptr;
  cholmod_dense* y = nullptr;
  cholmod_dense* e = nullptr;
  SolveWorkspace() { cholmod_start(&common); }
  ~SolveWorkspace() {
    cholmod_free_dense(&x, &common);
    cholmod_free_dense(&y, &common);
    cholmod_free_dense(&e, &common);
    cholmod_finish(&common);
  }
  SolveWorkspace(const SolveWorkspace&) = delete;
  SolveWorkspace& operator=(const SolveWorkspace&) = delete;

  /// x = A^-1 b for `columns` columns of b (column-major, n rows) into out.
  void solve(cholmod_factor* factor, const double* b, std::size_t n, std::size_t columns, double* out) {
    cholmod_dense view{};
    view.nrow = n;
    view.ncol = columns;
    view.nzmax = n * columns;
    view.d = n;
    view.x = const_cast<double*>(b); // read only
    view.xtype = CHOLMOD_REAL;
    view.dtype = CHOLMOD_DOUBLE;
    if (!cholmod_solve2(CHOLMOD_A, factor, &view, nullptr, &x, nullptr, &y, &e, &common))
      throw std::runtime_error("sparse Cholesky: the solve failed");
    std::memcpy(out, x->x, sizeof(double) * view.nzmax);
  }
};

struct SparseCholesky::Impl {
  cholmod_common common{};
  cholmod_factor* factor = nullptr;
  SolveWorkspace first, second; ///< of the two halves of a solve split between threads
  std::vector<int> position;    ///< row of the permuted matrix for each row of A
  long rank_changes = 0;

  Impl() { cholmod_start(&common); }
  ~Impl() {
    cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }

  /// An LDL^T factor exists for some indefinite matrices too: positive definite exactly when
  /// every entry of D (the first entry of each column of L) is positive.
  bool positive_pivots() const {
    const auto* column_start = static_cast<const int*>(factor->p);
    const auto* values = static_cast<const double*>(factor->x);
    for (std::size_t j = 0; j < factor->n; ++j)
      if (!(values[column_start[j]] > 0.0)) return false;
    return true;
  }

  void check_positive_definite(const char* what) const {
    if (common.status != CHOLMOD_OK || factor == nullptr || factor->minor < factor->n || !positive_pivots()) {
      throw std::runtime_error(std::string("sparse Cholesky: ") + what +
                               " is not positive definite (CHOLMOD status " + std::to_string(common.status) +
                               ")");
    }
  }

  /// One update (sign > 0) or downdate of A by the columns (rows of A, values).
  void apply(const std::vector<SparseCholesky::Column>& columns, int sign) {
    if (columns.empty()) return;
    const auto count = columns.size();
    std::size_t entries = 0;
    for (const auto& c : columns)
      entries += c.size();
    cholmod_sparse* C = cholmod_allocate_sparse(factor->n, count, entries, 1, 1, 0, CHOLMOD_REAL, &common);
    if (C == nullptr) throw std::runtime_error("sparse Cholesky: out of memory for a rank update");
    auto* p = static_cast<int*>(C->p);
    auto* i = static_cast<int*>(C->i);
    auto* v = static_cast<double*>(C->x);
    std::size_t at = 0;
    for (std::size_t k = 0; k < count; ++k) {
      p[k] = static_cast<int>(at);
      // In the factor's (permuted) row order, sorted as CHOLMOD expects.
      std::vector<std::pair<int, double>> permuted;
      for (const auto& [row, value] : columns[k])
        permuted.emplace_back(position[static_cast<std::size_t>(row)], value);
      std::sort(permuted.begin(), permuted.end());
      for (const auto& [row, value] : permuted) {
        i[at] = row;
        v[at] = value;
        ++at;
      }
    }
    p[count] = static_cast<int>(at);
    const int ok = cholmod_updown(sign > 0 ? 1 : 0, C, factor, &common);
    cholmod_free_sparse(&C, &common);
    if (!ok) throw std::runtime_error("sparse Cholesky: the rank update failed");
    check_positive_definite("the downdated matrix");
    rank_changes += static_cast<long>(count);
  }
};

SparseCholesky::SparseCholesky(const Eigen::SparseMatrix<double>& lower, Factorization factorization)
    : m(std::make_unique<Impl>()) {
  Eigen::SparseMatrix<double> A = lower;
  A.makeCompressed();
  cholmod_sparse view{};
  view.nrow = static_cast<std::size_t>(A.rows());
  view.ncol = static_cast<std::size_t>(A.cols());
  view.nzmax = static_cast<std::size_t>(A.nonZeros());
  view.p = A.outerIndexPtr();
  view.i = A.innerIndexPtr();
  view.x = A.valuePtr();
  view.stype = -1; // the lower triangle of a symmetric matrix
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = 1;
  view.packed = 1;
  const bool supernodal = factorization == Factorization::supernodal ||
                          (factorization == Factorization::automatic && A.rows() >= k_supernodal_rows);
  m->common.print = 0; // a matrix that is not positive definite is reported by the exception below
  m->common.supernodal = supernodal ? CHOLMOD_SUPERNODAL : CHOLMOD_SIMPLICIAL;
  m->common.final_ll = 0;                    // LDL^T: what cholmod_updown works on
  m->common.final_asis = supernodal ? 0 : 1; // a supernodal factor converted to simplicial LDL^T
  m->common.final_super = 0;
  m->common.final_pack = 1;
  m->common.final_monotonic = 1;
  // The analysis depends on the pattern and the settings above alone (the values are not read).
  m->factor = last_analysis().copy(A, supernodal, m->common);
  if (m->factor == nullptr) {
    m->factor = cholmod_analyze(&view, &m->common);
    if (m->factor == nullptr) throw std::runtime_error("sparse Cholesky: the analysis failed");
    ++g_analyses;
    last_analysis().keep(A, supernodal, m->factor);
  }
  if (supernodal) {
    const SingleThreadedBlas one_thread;
    cholmod_factorize(&view, m->factor, &m->common);
  } else {
    cholmod_factorize(&view, m->factor, &m->common);
  }
  // The supernodes are relaxed (they merge columns whose patterns nearly match, storing zeros to
  // make dense blocks): converted to simplicial those zeros stay in L and every solve reads them.
  // Dropped here, the solves read L's own pattern again.
  if (supernodal && m->common.status == CHOLMOD_OK)
    cholmod_resymbol(&view, nullptr, 0, 1, m->factor, &m->common);
  m->check_positive_definite("the matrix");
  m->position.assign(static_cast<std::size_t>(A.rows()), 0);
  const auto* permutation = static_cast<const int*>(m->factor->Perm);
  for (int k = 0; k < static_cast<int>(A.rows()); ++k)
    m->position[static_cast<std::size_t>(permutation[k])] = k;
}

SparseCholesky::~SparseCholesky() = default;

void SparseCholesky::solve(const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x, int threads) {
  const auto n = static_cast<std::size_t>(b.rows());
  x.resize(b.rows(), 3);
  if (threads < 2 || n < k_split_rows) {
    m->first.solve(m->factor, b.data(), n, 3, x.data());
    return;
  }
  // Two columns on one thread, the third on another: each pass over the factor is shared by
  // fewer columns, but the two run at once (the factor is only read).
  std::exception_ptr failure;
#pragma omp parallel num_threads(2)
  {
    try {
#pragma omp single nowait
      m->first.solve(m->factor, b.data(), n, 2, x.data());
#pragma omp single nowait
      m->second.solve(m->factor, b.data() + 2 * n, n, 1, x.data() + 2 * n);
    } catch (...) {
#pragma omp critical
      failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
}

void SparseCholesky::solve_column(const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x, int column) {
  const auto n = static_cast<std::size_t>(b.rows());
  m->first.solve(m->factor, b.col(column).data(), n, 1, x.col(column).data());
}

void SparseCholesky::update_diagonal(const std::vector<std::pair<int, double>>& changes) {
  std::vector<Column> add, remove;
  for (const auto& [row, delta] : changes) {
    if (delta == 0.0) continue;
    (delta > 0.0 ? add : remove).push_back({{row, std::sqrt(std::abs(delta))}});
  }
  update_columns(add, remove);
}

void SparseCholesky::update_columns(const std::vector<Column>& add, const std::vector<Column>& remove) {
  m->apply(add, +1); // updates first: the matrix stays positive definite in between
  m->apply(remove, -1);
}

long SparseCholesky::analyses() {
  return g_analyses.load();
}

long SparseCholesky::rank_changes() const {
  return m->rank_changes;
}

CoordinateFactors::CoordinateFactors(const Eigen::SparseMatrix<double>& lower, bool per_coordinate) {
  for (int c = 0; c < (per_coordinate ? 3 : 1); ++c)
    m_factors.push_back(std::make_unique<SparseCholesky>(lower));
}

void CoordinateFactors::solve(const Eigen::MatrixX3d& b, Eigen::MatrixX3d& x, int threads) {
  if (!per_coordinate()) {
    m_factors[0]->solve(b, x, threads);
    return;
  }
  x.resize(b.rows(), 3);
  const bool parallel = threads >= 2 && static_cast<std::size_t>(b.rows()) >= SparseCholesky::k_split_rows;
  std::exception_ptr failure;
#pragma omp parallel for num_threads(std::min(threads, 3)) schedule(static, 1) if (parallel)
  for (int c = 0; c < 3; ++c) {
    try { // each factor has its own workspace: the columns are independent
      m_factors[static_cast<std::size_t>(c)]->solve_column(b, x, c);
    } catch (...) {
#pragma omp critical
      failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
}

void CoordinateFactors::update_all(const std::vector<SparseCholesky::Column>& add,
                                   const std::vector<SparseCholesky::Column>& remove) {
  for (auto& factor : m_factors)
    factor->update_columns(add, remove);
}

long CoordinateFactors::rank_changes() const {
  long changes = 0;
  for (const auto& factor : m_factors)
    changes += factor->rank_changes();
  return changes;
}

} // namespace phantasm
