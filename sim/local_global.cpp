#include "sim/local_global.hpp"

#include "sim/sparse_cholesky.hpp"
#include "sim/tet_projection_batch.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Sparse>
#include <omp.h>

#include <chrono>
#include <numeric>
#include <stdexcept>

namespace phantasm {

struct LocalGlobalSolver::Impl {
  const ElasticModel& model;
  double alpha = 0.0;
  int threads = 1;
  int anderson_history = 0;
  std::vector<int> free_index;            ///< per vertex: row in the free system, -1 for fixed vertices
  std::vector<int> free_vertex;           ///< per free row: the vertex
  Eigen::SparseMatrix<double> K_free;     ///< free x free
  Eigen::SparseMatrix<double> K_coupling; ///< free x all vertices, columns of fixed vertices only
  std::unique_ptr<SparseCholesky> factor; ///< of K_free plus the contacts' diagonal
  // Contacts with obstacles, per free row: obstacles the vertex is inside at the last local
  // step, the sum of its projections onto them, its contact energy; and the count the factor
  // holds (k per contact on the diagonal), brought up to date by rank updates.
  std::vector<int> contact_count, factored_count;
  Eigen::MatrixX3d contact_targets;
  std::vector<double> contact_energies;
  // Contacts with other bodies' surfaces: one slot per (free vertex, surface it may not enter),
  // and the surfaces' geometry at the last local step. A contact is the PD constraint
  // d = x_v - sum b_k x_k (the closest point of the surface's triangle, barycentric b), projected
  // onto the contact plane's allowed side; in the factor it is kc c c^T with
  // c = (1, -b_0, -b_1, -b_2) over (v, triangle), brought in by rank-one updates.
  struct SurfaceSlot {
    int vertex = 0, surface = 0;
    bool inside = false; ///< at the last local step, with:
    std::array<int, 3> triangle{};
    Eigen::Vector3d barycentric = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::Zero();
    double energy = 0.0;
    Eigen::Matrix<double, 3, 4> positions; ///< of v and the triangle's vertices
    bool factored = false;                 ///< the factor holds c c^T of:
    std::array<int, 3> factored_triangle{};
    Eigen::Vector3d factored_barycentric = Eigen::Vector3d::Zero();
  };
  std::vector<SurfaceSlot> slots;
  std::unique_ptr<ContactGeometry> geometry;

  /// Whether the factor's column of a slot is out of date (the barycentric coordinates are
  /// refreshed once they drift by 1e-6: for a face contact they only share out the reaction).
  static bool slot_changed(const SurfaceSlot& s) {
    if (s.inside != s.factored) return true;
    return s.inside && (s.triangle != s.factored_triangle ||
                        (s.barycentric - s.factored_barycentric).cwiseAbs().maxCoeff() > 1e-6);
  }

  /// sqrt(kc) c over the free rows of the factored contact: (row, value). (Fixed vertices'
  /// terms go to the right-hand side, in gather_rhs.)
  void slot_column(const SurfaceSlot& s, SparseCholesky::Column& column) const {
    const double root = std::sqrt(model.contact_stiffness_N_m);
    column.clear();
    auto put = [&](int vertex, double value) {
      const int f = free_index[static_cast<std::size_t>(vertex)];
      if (value != 0.0 && f >= 0) column.emplace_back(f, root * value);
    };
    put(s.vertex, 1.0);
    for (int k = 0; k < 3; ++k)
      put(s.factored_triangle[static_cast<std::size_t>(k)], -s.factored_barycentric[k]);
  }
  // Per tet: warm-started rotation and the projection term w_s T_s^T + w_v T_v^T.
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Matrix3d> eigenvectors;
  std::vector<Eigen::Matrix3d> projections;
  std::vector<double> tet_energies;
  // Per surface element: w P(F), and its energy.
  std::vector<SurfaceMatrix> surface_projections;
  std::vector<double> surface_energies;
  // Per enclosed volume: w P(X) (one row per surface vertex), and its energy.
  std::vector<Eigen::MatrixX3d> volume_projections;
  std::vector<double> volume_energies;
  // Per vertex (CSR): the tets, surface elements and point constraints (index, corner) using it.
  std::vector<int> tet_offsets, tet_entries, surface_offsets, surface_entries, point_offsets, point_entries,
      volume_offsets, volume_entries;
  Eigen::MatrixX3d rhs, coupling_rhs, solution;

  /// The residual (the gradient K x - b(x) of the free vertices, with b from the projections
  /// at the result, which the last local step computed, and the contacts found there) and the
  /// contact count into the report.
  void finish_report(const Eigen::MatrixX3d& x_free, const Eigen::MatrixX3d& target, SolveReport& report) {
    update_contacts();
    gather_rhs(target);
    const Eigen::MatrixX3d K_x = apply_matrix(x_free);
    report.residual_N = x_free.rows() > 0 ? (K_x - rhs).rowwise().norm().maxCoeff() : 0.0;
    report.contacts = 0;
    for (int c : contact_count)
      report.contacts += c > 0 ? 1 : 0;
    for (const SurfaceSlot& slot : slots)
      report.contacts += slot.factored ? 1 : 0;
    report.rank_updates = factor->rank_changes();
  }

  Impl(const ElasticModel& m, double a, int t) : model(m), alpha(a), threads(t) {}

  /// The start of every solve: the fixed vertices' pull (constant during the solve), the first
  /// local step, and iteration 0 in the report and to the observer. Returns E(p).
  double begin_solve(const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& target, SolveReport& report,
                     bool record_energies, const IterationObserver& observer) {
    coupling_rhs = K_coupling * p;
    const auto start = std::chrono::steady_clock::now();
    const double energy = local_step(p, target);
    report.local_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    report.initial_energy_J = energy;
    if (record_energies) {
      report.energies_J.push_back(energy);
      report.seconds.push_back(report.local_seconds);
    }
    if (observer) observer(0, p, energy);
    report.stopped_by = "max_iterations";
    return energy;
  }

  void build_adjacency() {
    const auto n = static_cast<std::size_t>(model.vertex_count());
    auto build = [n](auto&& for_each_use, std::vector<int>& offsets, std::vector<int>& entries) {
      offsets.assign(n + 1, 0);
      for_each_use([&](int vertex, int, int) { ++offsets[static_cast<std::size_t>(vertex) + 1]; });
      for (std::size_t v = 0; v < n; ++v)
        offsets[v + 1] += offsets[v];
      entries.assign(2 * static_cast<std::size_t>(offsets[n]), 0);
      std::vector<int> cursor(offsets.begin(), offsets.end() - 1);
      for_each_use([&](int vertex, int element, int corner) {
        const auto at = 2 * static_cast<std::size_t>(cursor[static_cast<std::size_t>(vertex)]++);
        entries[at] = element;
        entries[at + 1] = corner;
      });
    };
    build(
        [&](auto&& use) {
          for (std::size_t t = 0; t < model.tets.size(); ++t)
            for (int k = 0; k < 4; ++k)
              use(model.tets[t].vertices[static_cast<std::size_t>(k)], static_cast<int>(t), k);
        },
        tet_offsets, tet_entries);
    build(
        [&](auto&& use) {
          for (std::size_t s = 0; s < model.surfaces.size(); ++s)
            for (int k = 0; k < model.surfaces[s].count; ++k)
              use(model.surfaces[s].vertices[static_cast<std::size_t>(k)], static_cast<int>(s), k);
        },
        surface_offsets, surface_entries);
    build(
        [&](auto&& use) {
          for (std::size_t c = 0; c < model.volumes.size(); ++c)
            for (std::size_t k = 0; k < model.volumes[c].vertices.size(); ++k)
              use(model.volumes[c].vertices[k], static_cast<int>(c), static_cast<int>(k));
        },
        volume_offsets, volume_entries);
    build(
        [&](auto&& use) {
          for (std::size_t c = 0; c < model.points.size(); ++c)
            for (int k = 0; k < model.points[c].count; ++k)
              use(model.points[c].vertices[static_cast<std::size_t>(k)], static_cast<int>(c), k);
        },
        point_offsets, point_entries);
  }

  void assemble_and_factor() {
    const Eigen::Index n = model.vertex_count();
    free_index.assign(static_cast<std::size_t>(n), -1);
    free_vertex.clear();
    for (Eigen::Index v = 0; v < n; ++v) {
      if (model.fixed.empty() || !model.fixed[static_cast<std::size_t>(v)]) {
        free_index[static_cast<std::size_t>(v)] = static_cast<int>(free_vertex.size());
        free_vertex.push_back(static_cast<int>(v));
      }
    }
    const auto nf = static_cast<Eigen::Index>(free_vertex.size());
    std::vector<Eigen::Triplet<double>> inner, coupling;
    auto add = [&](int a, int b, double value) {
      const int fa = free_index[static_cast<std::size_t>(a)];
      if (fa < 0) return;
      const int fb = free_index[static_cast<std::size_t>(b)];
      if (fb >= 0) {
        if (fb <= fa) inner.emplace_back(fa, fb, value); // lower triangle
      } else {
        coupling.emplace_back(fa, b, value);
      }
    };
    for (Eigen::Index v = 0; v < n; ++v)
      add(static_cast<int>(v), static_cast<int>(v), alpha * model.masses_kg[v]);
    for (const TetElement& e : model.tets) {
      const Eigen::Matrix4d L = (e.strain_weight + e.volume_weight) * e.Q * e.Q.transpose();
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
          add(e.vertices[static_cast<std::size_t>(a)], e.vertices[static_cast<std::size_t>(b)], L(a, b));
    }
    for (const SurfaceElement& e : model.surfaces) {
      const Eigen::Matrix4d L = e.weight * e.Q * e.Q.transpose();
      for (int a = 0; a < e.count; ++a)
        for (int b = 0; b < e.count; ++b)
          add(e.vertices[static_cast<std::size_t>(a)], e.vertices[static_cast<std::size_t>(b)], L(a, b));
    }
    for (const PointConstraint& c : model.points) {
      for (int a = 0; a < c.count; ++a)
        for (int b = 0; b < c.count; ++b)
          add(c.vertices[static_cast<std::size_t>(a)], c.vertices[static_cast<std::size_t>(b)],
              c.stiffness_N_m * c.coefficients[a] * c.coefficients[b]);
    }
    for (const EnclosedVolume& c : model.volumes)
      for (int v : c.vertices)
        add(v, v, c.weight);
    K_free.resize(nf, nf);
    K_free.setFromTriplets(inner.begin(), inner.end());
    K_coupling.resize(nf, n);
    K_coupling.setFromTriplets(coupling.begin(), coupling.end());
    if (alpha == 0.0) check_held();
    try {
      factor = std::make_unique<SparseCholesky>(K_free);
    } catch (const std::runtime_error&) {
      throw std::runtime_error(
          "local/global: the global matrix is not positive definite (is anything holding "
          "the model? quasi-static solves need fixed vertices or attachments)");
    }
    contact_count.assign(static_cast<std::size_t>(nf), 0);
    factored_count.assign(static_cast<std::size_t>(nf), 0);
    contact_targets.setZero(nf, 3);
    contact_energies.assign(static_cast<std::size_t>(nf), 0.0);
    rhs.resize(nf, 3);
    coupling_rhs.setZero(nf, 3);
    solution.resize(nf, 3);
  }

  /// Quasi-static solves have no inertia: every connected piece of the model must touch a fixed
  /// vertex or a point constraint, else it can float and the matrix is singular (round-off can
  /// hide that from the factorization, so it is checked here).
  void check_held() const {
    std::vector<int> parent(static_cast<std::size_t>(model.vertex_count()));
    std::iota(parent.begin(), parent.end(), 0);
    auto find = [&](int v) {
      while (parent[static_cast<std::size_t>(v)] != v)
        v = parent[static_cast<std::size_t>(v)] =
            parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(v)])];
      return v;
    };
    for (const TetElement& e : model.tets)
      for (int k = 1; k < 4; ++k)
        parent[static_cast<std::size_t>(find(e.vertices[static_cast<std::size_t>(k)]))] = find(e.vertices[0]);
    for (const SurfaceElement& e : model.surfaces)
      for (int k = 1; k < e.count; ++k)
        parent[static_cast<std::size_t>(find(e.vertices[static_cast<std::size_t>(k)]))] = find(e.vertices[0]);
    std::vector<char> held(parent.size(), 0);
    for (std::size_t v = 0; v < parent.size(); ++v)
      if (!model.fixed.empty() && model.fixed[v])
        held[static_cast<std::size_t>(find(static_cast<int>(v)))] = 1;
    for (const PointConstraint& c : model.points)
      for (int k = 0; k < c.count; ++k)
        held[static_cast<std::size_t>(find(c.vertices[static_cast<std::size_t>(k)]))] = 1;
    for (int v : free_vertex) {
      if (!held[static_cast<std::size_t>(find(v))]) {
        throw std::runtime_error("local/global: the global matrix is not positive definite: vertex " +
                                 std::to_string(v) +
                                 " belongs to a piece that nothing holds (quasi-static solves need fixed "
                                 "vertices or attachments on every piece)");
      }
    }
  }

  /// The local step: projections of every tet at p; returns E(p).
  double local_step(const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& target) {
    const auto count = static_cast<std::ptrdiff_t>(model.tets.size());
    const std::ptrdiff_t batches = (count + tet_batch_size - 1) / tet_batch_size;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 32)
    for (std::ptrdiff_t b = 0; b < batches; ++b) {
      TetBatch batch;
      batch.count = static_cast<int>(std::min<std::ptrdiff_t>(tet_batch_size, count - b * tet_batch_size));
      for (int l = 0; l < batch.count; ++l) {
        const auto t = static_cast<std::size_t>(b * tet_batch_size + l);
        const auto i = static_cast<std::size_t>(l);
        const TetElement& e = model.tets[t];
        batch.F[i] = deformation_gradient(e, p);
        batch.strain_weight[i] = e.strain_weight;
        batch.volume_weight[i] = e.volume_weight;
        batch.rotation[i] = &rotations[t];
        batch.eigenvectors[i] = &eigenvectors[t];
        batch.projection[i] = &projections[t];
        batch.energy[i] = &tet_energies[t];
      }
      project_tet_batch(batch, model.strain_range, model.volume_range);
    }
    const auto surface_count = static_cast<std::ptrdiff_t>(model.surfaces.size());
#pragma omp parallel for num_threads(threads) schedule(dynamic, 256) if (surface_count > 0)
    for (std::ptrdiff_t s = 0; s < surface_count; ++s) {
      const SurfaceElement& e = model.surfaces[static_cast<std::size_t>(s)];
      const SurfaceMatrix F = surface_deformation(e, p);
      const SurfaceMatrix T = project_surface(e, F);
      surface_projections[static_cast<std::size_t>(s)] = e.weight * T;
      surface_energies[static_cast<std::size_t>(s)] = 0.5 * e.weight * (F - T).squaredNorm();
    }
    // An enclosed volume's projection couples all its vertices: one task per volume.
    const auto volume_count = static_cast<std::ptrdiff_t>(model.volumes.size());
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1) if (volume_count > 1)
    for (std::ptrdiff_t c = 0; c < volume_count; ++c) {
      const EnclosedVolume& e = model.volumes[static_cast<std::size_t>(c)];
      const Eigen::MatrixX3d X = gather_vertices(e, p);
      const Eigen::MatrixX3d Y = project_enclosed_volume(e, X);
      volume_projections[static_cast<std::size_t>(c)] = e.weight * Y;
      volume_energies[static_cast<std::size_t>(c)] = 0.5 * e.weight * (X - Y).squaredNorm();
    }
    // Summed in element order, not by a parallel reduction: the energy, and so every stop
    // decision, is the same for any number of threads.
    double energy = 0.0;
    for (double e : volume_energies)
      energy += e;
    for (double e : tet_energies)
      energy += e;
    for (double e : surface_energies)
      energy += e;
    if (alpha > 0.0) { // over every vertex, as model_energy (fixed ones add a constant)
      for (Eigen::Index v = 0; v < p.rows(); ++v)
        energy += 0.5 * alpha * model.masses_kg[v] * (p.row(v) - target.row(v)).squaredNorm();
    }
    if (model.external_forces_N.rows() == p.rows()) energy -= model.external_forces_N.cwiseProduct(p).sum();
    for (const PointConstraint& c : model.points) {
      Eigen::RowVector3d x = Eigen::RowVector3d::Zero();
      for (int k = 0; k < c.count; ++k)
        x += c.coefficients[k] * p.row(c.vertices[static_cast<std::size_t>(k)]);
      energy += 0.5 * c.stiffness_N_m * (x - c.target_m.transpose()).squaredNorm();
    }
    if (!model.obstacles.empty() || !model.contact_pairs.empty()) energy += find_contacts(p);
    return energy;
  }

  /// The contact part of the local step: for each free vertex, the obstacles it is inside and
  /// its projections onto them. Returns the contact energy (summed in vertex order).
  double find_contacts(const Eigen::MatrixX3d& p) {
    if (geometry) geometry->update(p);
    const auto nf = static_cast<std::ptrdiff_t>(free_vertex.size());
    const double k = model.contact_stiffness_N_m;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (std::ptrdiff_t f = 0; f < nf; ++f) {
      const Eigen::Vector3d x = p.row(free_vertex[static_cast<std::size_t>(f)]).transpose();
      int count = 0;
      double energy = 0.0;
      Eigen::Vector3d targets = Eigen::Vector3d::Zero();
      for (const Obstacle& o : model.obstacles) {
        if (!(o.signed_distance(x) < 0.0)) continue;
        const Eigen::Vector3d projection = o.project(x);
        ++count;
        targets += projection;
        energy += 0.5 * k * (x - projection).squaredNorm();
      }
      contact_count[static_cast<std::size_t>(f)] = count;
      contact_targets.row(f) = targets.transpose();
      contact_energies[static_cast<std::size_t>(f)] = energy;
    }
    const auto slot_count = static_cast<std::ptrdiff_t>(slots.size());
#pragma omp parallel for num_threads(threads) schedule(static) if (slot_count > 0)
    for (std::ptrdiff_t i = 0; i < slot_count; ++i) {
      SurfaceSlot& slot = slots[static_cast<std::size_t>(i)];
      const SurfaceQuery q = geometry->query(slot.surface, p.row(slot.vertex).transpose());
      slot.inside = q.inside;
      slot.energy = q.inside ? 0.5 * k * q.distance * q.distance : 0.0;
      if (!q.inside) continue;
      slot.triangle = q.triangle;
      slot.barycentric = q.barycentric;
      slot.normal = q.normal;
      slot.positions.col(0) = p.row(slot.vertex).transpose();
      for (int c = 0; c < 3; ++c)
        slot.positions.col(c + 1) = p.row(q.triangle[static_cast<std::size_t>(c)]).transpose();
    }
    double energy = 0.0;
    for (double e : contact_energies)
      energy += e;
    for (const SurfaceSlot& slot : slots)
      energy += slot.energy;
    return energy;
  }

  /// Brings the factor's contacts up to those of the last local step by rank-one updates and
  /// downdates: k e_f e_f^T per obstacle contact, k c c^T per surface contact. Returns how many
  /// free vertices and surface-contact slots changed.
  int update_contacts() {
    if (model.obstacles.empty() && model.contact_pairs.empty()) return 0;
    std::vector<SparseCholesky::Column> add, remove;
    const double root = std::sqrt(model.contact_stiffness_N_m);
    int changes = 0;
    for (std::size_t f = 0; f < contact_count.size(); ++f) {
      if (contact_count[f] == factored_count[f]) continue;
      const int delta = contact_count[f] - factored_count[f];
      for (int k = 0; k < std::abs(delta); ++k)
        (delta > 0 ? add : remove).push_back({{static_cast<int>(f), root}});
      factored_count[f] = contact_count[f];
      ++changes;
    }
    SparseCholesky::Column column;
    for (SurfaceSlot& slot : slots) {
      if (!slot_changed(slot)) continue;
      if (slot.factored) {
        slot_column(slot, column);
        if (!column.empty()) remove.push_back(column);
      }
      slot.factored = slot.inside;
      slot.factored_triangle = slot.triangle;
      slot.factored_barycentric = slot.barycentric;
      if (slot.factored) {
        slot_column(slot, column);
        if (!column.empty()) add.push_back(column);
      }
      ++changes;
    }
    if (!add.empty() || !remove.empty()) factor->update_columns(add, remove);
    return changes;
  }

  /// Whether the last local step found contacts the factor does not hold yet.
  bool contacts_pending() const {
    if (contact_count != factored_count) return true;
    for (const SurfaceSlot& slot : slots)
      if (slot_changed(slot)) return true;
    return false;
  }

  /// K x over the free rows, with the contacts the factor holds.
  Eigen::MatrixX3d apply_matrix(const Eigen::MatrixX3d& x) const {
    Eigen::MatrixX3d Kx = K_free.selfadjointView<Eigen::Lower>() * x;
    for (std::size_t f = 0; f < factored_count.size(); ++f)
      if (factored_count[f] > 0)
        Kx.row(static_cast<Eigen::Index>(f)) +=
            (model.contact_stiffness_N_m * factored_count[f]) * x.row(static_cast<Eigen::Index>(f));
    SparseCholesky::Column column;
    for (const SurfaceSlot& slot : slots) {
      if (!slot.factored) continue;
      slot_column(slot, column);
      Eigen::RowVector3d cx = Eigen::RowVector3d::Zero();
      for (const auto& [row, value] : column)
        cx += value * x.row(row);
      for (const auto& [row, value] : column)
        Kx.row(row) += value * cx;
    }
    return Kx;
  }

  /// The diagonal of the matrix the factor holds.
  Eigen::VectorXd matrix_diagonal() const {
    Eigen::VectorXd d = K_free.diagonal();
    for (std::size_t f = 0; f < factored_count.size(); ++f)
      d[static_cast<Eigen::Index>(f)] += model.contact_stiffness_N_m * factored_count[f];
    SparseCholesky::Column column;
    for (const SurfaceSlot& slot : slots) {
      if (!slot.factored) continue;
      slot_column(slot, column);
      for (const auto& [row, value] : column)
        d[row] += value * value;
    }
    return d;
  }

  /// The right-hand side of the free vertices from the current projections.
  void gather_rhs(const Eigen::MatrixX3d& target) {
    const auto nf = static_cast<std::ptrdiff_t>(free_vertex.size());
    const bool forces = model.external_forces_N.rows() == model.vertex_count();
#pragma omp parallel for num_threads(threads) schedule(static)
    for (std::ptrdiff_t f = 0; f < nf; ++f) {
      const auto v = static_cast<std::size_t>(free_vertex[static_cast<std::size_t>(f)]);
      Eigen::RowVector3d r = Eigen::RowVector3d::Zero();
      if (alpha > 0.0)
        r += alpha * model.masses_kg[static_cast<Eigen::Index>(v)] * target.row(static_cast<Eigen::Index>(v));
      if (forces) r += model.external_forces_N.row(static_cast<Eigen::Index>(v));
      for (int i = tet_offsets[v]; i < tet_offsets[v + 1]; ++i) {
        const auto t = static_cast<std::size_t>(tet_entries[2 * static_cast<std::size_t>(i)]);
        const int corner = tet_entries[2 * static_cast<std::size_t>(i) + 1];
        r.noalias() += model.tets[t].Q.row(corner) * projections[t];
      }
      for (int i = surface_offsets[v]; i < surface_offsets[v + 1]; ++i) {
        const auto s = static_cast<std::size_t>(surface_entries[2 * static_cast<std::size_t>(i)]);
        const int corner = surface_entries[2 * static_cast<std::size_t>(i) + 1];
        r.noalias() += (surface_projections[s] * model.surfaces[s].Q.row(corner).transpose()).transpose();
      }
      for (int i = volume_offsets[v]; i < volume_offsets[v + 1]; ++i) {
        const auto c = static_cast<std::size_t>(volume_entries[2 * static_cast<std::size_t>(i)]);
        r += volume_projections[c].row(volume_entries[2 * static_cast<std::size_t>(i) + 1]);
      }
      for (int i = point_offsets[v]; i < point_offsets[v + 1]; ++i) {
        const PointConstraint& c =
            model.points[static_cast<std::size_t>(point_entries[2 * static_cast<std::size_t>(i)])];
        const int corner = point_entries[2 * static_cast<std::size_t>(i) + 1];
        r += c.stiffness_N_m * c.coefficients[corner] * c.target_m.transpose();
      }
      if (!contact_energies.empty() && contact_count[static_cast<std::size_t>(f)] > 0)
        r += model.contact_stiffness_N_m * contact_targets.row(f);
      rhs.row(f) = r - coupling_rhs.row(f);
    }
    // Contacts with other surfaces, as the factor holds them (update_contacts runs first):
    // kc c_j P(d) for the free vertices j of each, d = c . X at the last local step and P(d) its
    // part on the allowed side of the contact plane; fixed vertices' terms kc c_j c_k x_k move
    // to the right-hand side.
    const double k = model.contact_stiffness_N_m;
    for (const SurfaceSlot& slot : slots) {
      if (!slot.factored) continue;
      Eigen::Vector4d c;
      c << 1.0, -slot.factored_barycentric;
      const Eigen::Vector3d d = slot.positions * c;
      const Eigen::Vector3d projected = d - std::min(0.0, d.dot(slot.normal)) * slot.normal;
      const std::array<int, 4> vertices = {slot.vertex, slot.factored_triangle[0], slot.factored_triangle[1],
                                           slot.factored_triangle[2]};
      for (int j = 0; j < 4; ++j) {
        const int row = free_index[static_cast<std::size_t>(vertices[static_cast<std::size_t>(j)])];
        if (row < 0 || c[j] == 0.0) continue;
        Eigen::Vector3d r = k * c[j] * projected;
        for (int i = 0; i < 4; ++i)
          if (free_index[static_cast<std::size_t>(vertices[static_cast<std::size_t>(i)])] < 0)
            r -= k * c[j] * c[i] * slot.positions.col(i);
        rhs.row(row) += r.transpose();
      }
    }
  }
};

LocalGlobalSolver::LocalGlobalSolver(const ElasticModel& model, double inertia_weight, int threads,
                                     int anderson_history)
    : m(std::make_unique<Impl>(model, inertia_weight, threads > 0 ? threads : omp_get_max_threads())) {
  m->anderson_history = std::max(0, anderson_history);
  m->rotations.assign(model.tets.size(), Eigen::Quaterniond::Identity());
  m->eigenvectors.assign(model.tets.size(), Eigen::Matrix3d::Identity());
  m->projections.assign(model.tets.size(), Eigen::Matrix3d::Zero());
  m->tet_energies.assign(model.tets.size(), 0.0);
  m->surface_projections.assign(model.surfaces.size(), SurfaceMatrix::Zero());
  m->surface_energies.assign(model.surfaces.size(), 0.0);
  m->volume_projections.resize(model.volumes.size());
  m->volume_energies.assign(model.volumes.size(), 0.0);
  m->build_adjacency();
  m->assemble_and_factor();
  if (!model.contact_pairs.empty()) {
    const auto opposing =
        opposing_surfaces(model.contact_surfaces, model.contact_pairs, model.vertex_count());
    for (int v : m->free_vertex) {
      for (int surface : opposing[static_cast<std::size_t>(v)]) {
        Impl::SurfaceSlot slot;
        slot.vertex = v;
        slot.surface = surface;
        m->slots.push_back(slot);
      }
    }
    m->geometry = std::make_unique<ContactGeometry>(model.contact_surfaces);
  }
}

LocalGlobalSolver::~LocalGlobalSolver() = default;

double LocalGlobalSolver::energy(const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& inertial_target) {
  return m->local_step(p, inertial_target);
}

SolveReport LocalGlobalSolver::solve(Eigen::MatrixX3d& p, const Eigen::MatrixX3d& target,
                                     const StopCriteria& stop, bool record_energies,
                                     const IterationObserver& observer) {
  using Clock = std::chrono::steady_clock;
  auto seconds_since = [](Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
  };
  SolveReport report;
  report.solver = "local_global";
  double energy = m->begin_solve(p, target, report, record_energies, observer);
  auto start = Clock::now();
  const auto nf = static_cast<Eigen::Index>(m->free_vertex.size());
  auto free_positions = [&] {
    Eigen::MatrixX3d x(nf, 3);
    for (Eigen::Index f = 0; f < nf; ++f)
      x.row(f) = p.row(m->free_vertex[static_cast<std::size_t>(f)]);
    return x;
  };
  auto set_free_positions = [&](const Eigen::MatrixX3d& x) {
    for (Eigen::Index f = 0; f < nf; ++f)
      p.row(m->free_vertex[static_cast<std::size_t>(f)]) = x.row(f);
  };
  // Anderson acceleration of the fixed-point map x -> G(x) (global step after local step), with
  // Peng et al. (2018)'s energy safeguard: the accelerated point is kept only when its energy is
  // below the current one; otherwise the plain step, which never raises the energy, is taken and
  // the history restarts. Either way the energy never increases.
  const int history = m->anderson_history;
  Eigen::MatrixXd dG(3 * nf, std::max(history, 1)), dF(3 * nf, std::max(history, 1));
  Eigen::VectorXd g_previous, f_previous;
  int stored = 0, next_column = 0;
  Eigen::MatrixX3d x = free_positions();
  for (int iteration = 1; iteration <= stop.max_iterations; ++iteration) {
    start = Clock::now();
    const int contact_changes = m->update_contacts(); // (timed with the local step: the
    report.contact_changes += contact_changes;        // right-hand side depends on it)
    m->gather_rhs(target);
    report.local_seconds += seconds_since(start);
    start = Clock::now();
    m->factor->solve(m->rhs, m->solution, m->threads);
    report.global_seconds += seconds_since(start);
    start = Clock::now();
    const double previous = energy;
    const Eigen::MatrixX3d g_matrix = m->solution;
    Eigen::MatrixX3d accepted = g_matrix;
    bool accelerated = false, tried = false;
    if (history > 0) {
      const Eigen::Map<const Eigen::VectorXd> g(g_matrix.data(), 3 * nf);
      const Eigen::Map<const Eigen::VectorXd> xv(x.data(), 3 * nf);
      const Eigen::VectorXd f = g - xv;
      if (g_previous.size() == g.size()) {
        dG.col(next_column) = g - g_previous;
        dF.col(next_column) = f - f_previous;
        next_column = (next_column + 1) % history;
        stored = std::min(stored + 1, history);
      }
      g_previous = g;
      f_previous = f;
      if (stored > 0) {
        const Eigen::MatrixXd F = dF.leftCols(stored);
        Eigen::MatrixXd normal = F.transpose() * F;
        normal.diagonal().array() += 1e-10 * normal.diagonal().maxCoeff() + 1e-300;
        const Eigen::VectorXd theta = normal.ldlt().solve(F.transpose() * f);
        if (theta.allFinite()) {
          tried = true;
          Eigen::MatrixX3d candidate(nf, 3);
          Eigen::Map<Eigen::VectorXd>(candidate.data(), 3 * nf) = g - dG.leftCols(stored) * theta;
          set_free_positions(candidate);
          const double candidate_energy = m->local_step(p, target);
          if (candidate_energy < previous) {
            accepted = candidate;
            energy = candidate_energy;
            accelerated = true;
          }
        }
      }
    }
    if (!accelerated) {
      set_free_positions(g_matrix);
      energy = m->local_step(p, target);
      if (tried) { // rejected: restart the history from this point
        stored = 0;
        next_column = 0;
        g_previous.resize(0);
      }
    }
    report.local_seconds += seconds_since(start);
    const double change = nf > 0 ? (accepted - x).rowwise().norm().maxCoeff() : 0.0;
    x = accepted;
    report.iterations = iteration;
    if (record_energies) {
      report.energies_J.push_back(energy);
      report.seconds.push_back(report.local_seconds + report.global_seconds);
    }
    if (observer) observer(iteration, p, energy);
    if (change <= stop.position_change_m) {
      report.stopped_by = "position";
      break;
    }
    // Contacts that came or went (in this step, or found at its result) make the energy of the
    // step another function: no stop on its change then.
    if (contact_changes == 0 && !m->contacts_pending() &&
        (previous - energy) <= stop.relative_energy_decrease * std::abs(energy)) {
      report.stopped_by = "energy";
      break;
    }
  }
  report.final_energy_J = energy;
  Eigen::MatrixX3d p_free(static_cast<Eigen::Index>(m->free_vertex.size()), 3);
  for (std::size_t f = 0; f < m->free_vertex.size(); ++f)
    p_free.row(static_cast<Eigen::Index>(f)) = p.row(m->free_vertex[f]);
  m->finish_report(p_free, target, report);
  return report;
}

double LocalGlobalSolver::jacobi_spectral_radius() {
  const Eigen::Index nf = m->K_free.rows();
  if (nf == 0) return 0.0;
  const Eigen::VectorXd inverse_diagonal = m->K_free.diagonal().cwiseInverse();
  Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(nf, 1.0, 2.0); // deterministic start
  v.normalize();
  double rho = 0.0;
  for (int k = 0; k < 300; ++k) {
    const Eigen::VectorXd Kv = m->K_free.selfadjointView<Eigen::Lower>() * v;
    Eigen::VectorXd w = v - inverse_diagonal.cwiseProduct(Kv);
    const double norm = w.norm();
    if (norm == 0.0) return 0.0;
    rho = norm; // |J v| with |v| = 1 converges to the spectral radius for the dominant mode
    v = w / norm;
  }
  return std::min(rho, 1.0 - 1e-12);
}

SolveReport LocalGlobalSolver::solve_jacobi_chebyshev(Eigen::MatrixX3d& p, const Eigen::MatrixX3d& target,
                                                      const StopCriteria& stop, bool record_energies,
                                                      const IterationObserver& observer,
                                                      double under_relaxation, double rho_scale) {
  using Clock = std::chrono::steady_clock;
  auto seconds_since = [](Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
  };
  SolveReport report;
  report.solver = "jacobi_chebyshev";
  const double rho = rho_scale * jacobi_spectral_radius();
  double energy = m->begin_solve(p, target, report, record_energies, observer);
  auto start = Clock::now();
  const auto nf = static_cast<Eigen::Index>(m->free_vertex.size());
  Eigen::MatrixX3d x(nf, 3);
  for (Eigen::Index f = 0; f < nf; ++f)
    x.row(f) = p.row(m->free_vertex[static_cast<std::size_t>(f)]);
  Eigen::MatrixX3d x_previous = x, best = x;
  double best_energy = energy;
  Eigen::VectorXd inverse_diagonal = m->K_free.diagonal().cwiseInverse();
  double omega = 1.0;
  int step = 0; // iterations since the acceleration (re)started
  for (int iteration = 1; iteration <= stop.max_iterations; ++iteration) {
    start = Clock::now();
    const bool contacts_changed = m->update_contacts() > 0;
    m->gather_rhs(target);
    report.local_seconds += seconds_since(start);
    start = Clock::now();
    if (contacts_changed) inverse_diagonal = m->matrix_diagonal().cwiseInverse();
    const Eigen::MatrixX3d Kx = m->apply_matrix(x);
    const Eigen::MatrixX3d jacobi = x + inverse_diagonal.asDiagonal() * (m->rhs - Kx);
    ++step;
    omega = step == 1 ? 1.0 : step == 2 ? 2.0 / (2.0 - rho * rho) : 4.0 / (4.0 - rho * rho * omega);
    const Eigen::MatrixX3d next = omega * (under_relaxation * (jacobi - x) + x - x_previous) + x_previous;
    report.global_seconds += seconds_since(start);
    start = Clock::now();
    const double previous = energy;
    for (Eigen::Index f = 0; f < nf; ++f)
      p.row(m->free_vertex[static_cast<std::size_t>(f)]) = next.row(f);
    energy = m->local_step(p, target);
    const double change = nf > 0 ? (next - x).rowwise().norm().maxCoeff() : 0.0;
    x_previous = x;
    x = next;
    if (std::isfinite(energy) && m->contacts_pending()) {
      // New or released contacts: the energy is another function from here; restart the
      // acceleration at this point rather than returning to one with the old contacts.
      best = x;
      best_energy = energy;
      x_previous = x;
      step = 0;
    } else if (!std::isfinite(energy) || energy > best_energy) {
      // Restart the acceleration from the best point so far.
      x = best;
      x_previous = best;
      step = 0;
      for (Eigen::Index f = 0; f < nf; ++f)
        p.row(m->free_vertex[static_cast<std::size_t>(f)]) = best.row(f);
      energy = m->local_step(p, target);
    } else {
      best = x;
      best_energy = energy;
    }
    report.local_seconds += seconds_since(start);
    report.iterations = iteration;
    if (record_energies) {
      report.energies_J.push_back(energy);
      report.seconds.push_back(report.local_seconds + report.global_seconds);
    }
    if (observer) observer(iteration, p, energy);
    if (step > 0 && change <= stop.position_change_m) {
      report.stopped_by = "position";
      break;
    }
    if (step > 2 && !m->contacts_pending() &&
        std::abs(previous - energy) <= stop.relative_energy_decrease * std::abs(energy)) {
      report.stopped_by = "energy";
      break;
    }
  }
  report.final_energy_J = energy;
  m->finish_report(x, target, report);
  return report;
}

} // namespace phantasm
