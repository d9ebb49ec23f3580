// The contacts of a local/global solve (obstacles, other bodies' surfaces) and the factor's rank
// updates that bring them in and out of the global matrix. Internal to the sim target.
#pragma once

#include "sim/elastic_model.hpp"
#include "sim/sparse_cholesky.hpp"

#include <Eigen/Core>

#include <array>
#include <memory>
#include <vector>

namespace phantasm::sim_detail {

/// The contacts the local step finds and the part of the global matrix the factors hold for
/// them. A vertex inside an obstacle costs kc/2 |x - P(x)|^2, whose Hessian is at most kc n n^T
/// (n the obstacle's normal there): the global step holds it as the diagonal per coordinate
/// kc |n_c| |n|_1 (above kc n n^T: their difference is diagonally dominant; n = e_z gives kc
/// on z alone), with right-hand side D x - kc (x - P(x)), so the vertex may slide along the
/// obstacle within one step (the same fixed point as kc I with target P(x), which pins it in
/// every direction: frictionless contacts then slid by about force / kc per iteration). A vertex
/// inside another body's surface is the PD constraint d = x_v - sum b_k x_k (the closest point of
/// the surface's triangle, barycentric b), projected onto the contact plane's allowed side; in
/// the matrix it is kc c c^T with c = (1, -b_0, -b_1, -b_2) over (v, triangle). Both come and go
/// by rank-one updates and downdates of the factor (update_factor), not by a new factorization.
class ContactSet {
public:
  /// @param free_index per model vertex: its row in the free system, -1 for fixed vertices
  /// @param free_vertex per free row: its vertex
  /// The model and both vectors must outlive the set.
  ContactSet(const ElasticModel& model, const std::vector<int>& free_index,
             const std::vector<int>& free_vertex);

  /// The contact part of the local step at p (metres, one row per model vertex): for each free
  /// vertex, the obstacles it is inside and its projections onto them, and the surfaces it has
  /// entered. Returns the contact energy (summed in vertex order), J.
  double find(const Eigen::MatrixX3d& p, int threads);

  /// Brings the factors' contacts up to those of the last find() by rank-one updates and
  /// downdates: per obstacle contact its diagonal weight in each coordinate's factor (rounded up
  /// to kc/64 and renewed when it must grow, falls by kc/32 or the contact ends), kc c c^T per
  /// surface contact in every factor. Returns how many free vertices and surface-contact slots
  /// changed.
  int update_factor(CoordinateFactors& factors);

  /// Whether the last find() found contacts the factor does not hold yet.
  bool pending() const;

  /// Kx += the contacts' part of the matrix (as the factor holds it) times x, over the free rows.
  void add_to_product(const Eigen::MatrixX3d& x, Eigen::MatrixX3d& Kx) const;

  /// d += the diagonal of the contacts' part of the matrix the factors hold, per coordinate.
  void add_to_diagonal(Eigen::MatrixX3d& d) const;

  /// r += D x - kc sum (x - P(x)) of free row f (right-hand side, N): D the diagonal the factors
  /// hold for its obstacle contacts, x and P(x) of the last find() (update_factor runs first).
  void add_obstacle_rhs(Eigen::Index f, Eigen::RowVector3d& r) const {
    if (m_obstacle_energies.empty()) return;
    r += m_factored_weights.row(f).cwiseProduct(m_obstacle_positions.row(f)) - m_obstacle_gradients.row(f);
  }

  /// rhs += the surface contacts' part of the right-hand side, as the factor holds them
  /// (update_factor runs first): kc c_j P(d) for the free vertices j of each, d = c . X at the last
  /// find() and P(d) its part on the allowed side of the contact plane; fixed vertices' terms
  /// kc c_j c_k x_k move to the right-hand side.
  void add_surface_rhs(Eigen::MatrixX3d& rhs) const;

  /// Free vertices inside an obstacle plus surface contacts, as the factor holds them.
  int count() const;

private:
  /// One (free vertex, surface it may not enter) pair.
  struct SurfaceSlot {
    int vertex = 0, surface = 0;
    bool inside = false; ///< at the last find(), with:
    std::array<int, 3> triangle{};
    Eigen::Vector3d barycentric = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::Zero();
    double energy = 0.0;
    Eigen::Matrix<double, 3, 4> positions =
        Eigen::Matrix<double, 3, 4>::Zero(); ///< of v and the triangle's vertices
    bool factored = false;                   ///< the factor holds c c^T of:
    std::array<int, 3> factored_triangle{};
    Eigen::Vector3d factored_barycentric = Eigen::Vector3d::Zero();
  };

  /// Whether the factor's column of a slot is out of date (the barycentric coordinates are
  /// refreshed once they drift by 1e-6: for a face contact they only share out the reaction).
  static bool slot_changed(const SurfaceSlot& s);

  /// sqrt(kc) c over the free rows of the factored contact: (row, value). (Fixed vertices'
  /// terms go to the right-hand side, in add_surface_rhs.)
  void slot_column(const SurfaceSlot& s, SparseCholesky::Column& column) const;

  const ElasticModel& m_model;
  const std::vector<int>& m_free_index;
  const std::vector<int>& m_free_vertex;
  /// The diagonal weight the factors should hold for a needed one (0 when the contact ended),
  /// given the one they hold.
  double factored_weight(double needed, double held) const;

  // Per free row: obstacles the vertex is inside at the last find(), its position then, its
  // contact gradient kc sum (x - P(x)), its contact energy, the diagonal weights per coordinate
  // its contacts need (kc |n_c| |n|_1 summed over them), and those the factors hold.
  std::vector<int> m_obstacle_count;
  Eigen::MatrixX3d m_obstacle_positions, m_obstacle_gradients, m_obstacle_weights, m_factored_weights;
  std::vector<double> m_obstacle_energies;
  // Contacts with other bodies' surfaces: one slot per (free vertex, surface it may not enter),
  // and the surfaces' geometry at the last find().
  std::vector<SurfaceSlot> m_slots;
  std::unique_ptr<ContactGeometry> m_geometry;
};

} // namespace phantasm::sim_detail
