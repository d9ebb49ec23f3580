// The state the local/global solvers share: the global matrix and its factor, the per-tet
// projections, the contact set, and the steps both solve loops are made of. Internal to sim.
#pragma once

#include "sim/contact_set.hpp"
#include "sim/local_global.hpp"
#include "sim/sparse_cholesky.hpp"
#include "sim/surface_constraints.hpp"

#include <Eigen/Geometry>
#include <Eigen/Sparse>

#include <memory>
#include <vector>

namespace phantasm {

namespace sim_detail {
class AndersonAcceleration;
class QuasiNewtonHistory;
} // namespace sim_detail

struct LocalGlobalSolver::Impl {
  const ElasticModel& model;
  double alpha = 0.0;
  int threads = 1;
  int anderson_history = 0;               ///< iterations Anderson acceleration remembers (0: off)
  int history = 0;                        ///< L-BFGS pairs remembered (0: no L-BFGS phase)
  std::vector<int> free_index;            ///< per vertex: row in the free system, -1 for fixed vertices
  std::vector<int> free_vertex;           ///< per free row: the vertex
  Eigen::SparseMatrix<double> K_free;     ///< free x free
  Eigen::SparseMatrix<double> K_coupling; ///< free x all vertices, columns of fixed vertices only
  std::unique_ptr<CoordinateFactors>
      factor; ///< of K_free plus the contacts' part (per coordinate with obstacles)
  std::unique_ptr<sim_detail::ContactSet> contacts;
  // Per tet: warm-started rotation and the projection term w_s T_s^T + w_v T_v^T.
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Matrix3d> eigenvectors;
  std::vector<Eigen::Matrix3d> projections;
  std::vector<double> tet_energies;
  // Per surface element: w P(F), and its energy.
  std::vector<SurfaceMatrix> surface_projections;
  std::vector<double> surface_energies;
  // Per tet group: warm-started rotation and w T^T (T the closest point of the volume set to
  // the averaged F), and its energy.
  std::vector<Eigen::Quaterniond> group_rotations, group_eigenvectors;
  std::vector<Eigen::Matrix3d> group_projections;
  std::vector<double> group_energies;
  // Per enclosed volume: w P(X) (one row per surface vertex), and its energy.
  std::vector<Eigen::MatrixX3d> volume_projections;
  std::vector<double> volume_energies;
  // Per vertex (CSR): the tets, surface elements and point constraints (index, corner) using it.
  std::vector<int> tet_offsets, tet_entries, surface_offsets, surface_entries, point_offsets, point_entries,
      volume_offsets, volume_entries, group_offsets, group_entries;
  Eigen::MatrixX3d rhs, coupling_rhs, solution;
  // solve()'s buffers: its quasi-Newton direction, K^-1 y of the newest pair, Anderson's proposal.
  Eigen::MatrixX3d direction, scaled, candidate;

  Impl(const ElasticModel& m, double a, int t) : model(m), alpha(a), threads(t) {}

  // The global system (global_matrix.cpp).

  /// Per vertex, the elements and point constraints using it (CSR, for gather_rhs).
  void build_adjacency();
  /// The free rows, K_free and K_coupling, the factor, and an empty contact set.
  /// @throws std::runtime_error when the matrix cannot be factored
  void assemble_and_factor();
  /// Quasi-static solves have no inertia: every connected piece of the model must touch a fixed
  /// vertex or a point constraint, else it can float and the matrix is singular (round-off can
  /// hide that from the factorization, so it is checked here).
  /// @throws std::runtime_error naming a vertex of a piece nothing holds
  void check_held() const;
  /// K x over the free rows, with the contacts the factor holds.
  Eigen::MatrixX3d apply_matrix(const Eigen::MatrixX3d& x) const;
  /// The diagonal of the matrix the factors hold, per coordinate.
  Eigen::MatrixX3d matrix_diagonal() const;

  // The steps (local_global.cpp).

  /// The local step: projections of every element at p and the contacts there; returns E(p).
  double local_step(const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& target);
  /// The right-hand side of the free vertices from the current projections.
  void gather_rhs(const Eigen::MatrixX3d& target);
  /// The start of every solve: the fixed vertices' pull (constant during the solve), the first
  /// local step, and iteration 0 in the report and to the observer. Returns E(p).
  double begin_solve(const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& target, SolveReport& report,
                     bool record_energies, const IterationObserver& observer);
  /// The residual (the gradient K x - b(x) of the free vertices, with b from the projections
  /// at the result, which the last local step computed, and the contacts found there) and the
  /// contact count into the report.
  void finish_report(const Eigen::MatrixX3d& x_free, const Eigen::MatrixX3d& target, SolveReport& report);
  /// An iteration of solve()'s second phase (L-BFGS around the global matrix): the two-loop
  /// direction from x (its gradient, its energy `previous`; `pairs` the L-BFGS history) and a
  /// backtracking line search on the energy. True when the search accepts a point: the point in
  /// `trial`, p and `energy`.
  bool quasi_newton_step(sim_detail::QuasiNewtonHistory& pairs, const Eigen::MatrixX3d& x,
                         const Eigen::MatrixX3d& gradient, double previous, const Eigen::MatrixX3d& target,
                         Eigen::MatrixX3d& p, Eigen::MatrixX3d& trial, double& energy, SolveReport& report);
  /// A plain iteration of solve() (the global step after the local step), with Anderson's
  /// proposal kept where it lowers the energy when `accelerate` (the first phase): the point in
  /// `trial` and p; returns its energy.
  double plain_step(sim_detail::AndersonAcceleration& anderson, bool accelerate, const Eigen::MatrixX3d& x,
                    double previous, const Eigen::MatrixX3d& target, Eigen::MatrixX3d& p,
                    Eigen::MatrixX3d& trial, SolveReport& report);

  /// The free rows of p.
  Eigen::MatrixX3d free_positions(const Eigen::MatrixX3d& p) const {
    Eigen::MatrixX3d x(static_cast<Eigen::Index>(free_vertex.size()), 3);
    for (std::size_t f = 0; f < free_vertex.size(); ++f)
      x.row(static_cast<Eigen::Index>(f)) = p.row(free_vertex[f]);
    return x;
  }
  /// p's free rows set to x.
  void set_free_positions(const Eigen::MatrixX3d& x, Eigen::MatrixX3d& p) const {
    for (std::size_t f = 0; f < free_vertex.size(); ++f)
      p.row(free_vertex[f]) = x.row(static_cast<Eigen::Index>(f));
  }
};

} // namespace phantasm
