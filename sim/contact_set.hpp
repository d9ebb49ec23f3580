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

/// The contacts the local step finds and the part of the global matrix the factor holds for
/// them. A vertex inside an obstacle adds kc e_f e_f^T per obstacle to the matrix. A vertex
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

  /// Brings the factor's contacts up to those of the last find() by rank-one updates and
  /// downdates: kc e_f e_f^T per obstacle contact, kc c c^T per surface contact. Returns how many
  /// free vertices and surface-contact slots changed.
  int update_factor(SparseCholesky& factor);

  /// Whether the last find() found contacts the factor does not hold yet.
  bool pending() const;

  /// Kx += the contacts' part of the matrix (as the factor holds it) times x, over the free rows.
  void add_to_product(const Eigen::MatrixX3d& x, Eigen::MatrixX3d& Kx) const;

  /// d += the diagonal of the contacts' part of the matrix the factor holds.
  void add_to_diagonal(Eigen::VectorXd& d) const;

  /// r += kc times the sum of free row f's projections onto the obstacles it is inside (right-hand
  /// side, N), when the factor holds its obstacle contacts.
  void add_obstacle_rhs(Eigen::Index f, Eigen::RowVector3d& r) const {
    if (!m_obstacle_energies.empty() && m_obstacle_count[static_cast<std::size_t>(f)] > 0)
      r += m_model.contact_stiffness_N_m * m_obstacle_targets.row(f);
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
  // Per free row: obstacles the vertex is inside at the last find(), the sum of its projections
  // onto them, its contact energy; and the count the factor holds (kc per contact on the
  // diagonal).
  std::vector<int> m_obstacle_count, m_factored_count;
  Eigen::MatrixX3d m_obstacle_targets;
  std::vector<double> m_obstacle_energies;
  // Contacts with other bodies' surfaces: one slot per (free vertex, surface it may not enter),
  // and the surfaces' geometry at the last find().
  std::vector<SurfaceSlot> m_slots;
  std::unique_ptr<ContactGeometry> m_geometry;
};

} // namespace phantasm::sim_detail
