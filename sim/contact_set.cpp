// The contact set of the local/global solver: contacts found at each local step, their part of
// the matrix and right-hand side, and the factor's rank-one updates as they come and go.
#include "sim/contact_set.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>

namespace phantasm::sim_detail {

ContactSet::ContactSet(const ElasticModel& model, const std::vector<int>& free_index,
                       const std::vector<int>& free_vertex)
    : m_model(model), m_free_index(free_index), m_free_vertex(free_vertex) {
  const std::size_t nf = free_vertex.size();
  m_obstacle_count.assign(nf, 0);
  m_factored_count.assign(nf, 0);
  m_obstacle_targets.setZero(static_cast<Eigen::Index>(nf), 3);
  m_obstacle_energies.assign(nf, 0.0);
  if (!model.contact_pairs.empty()) {
    const auto opposing =
        opposing_surfaces(model.contact_surfaces, model.contact_pairs, model.vertex_count());
    for (int v : free_vertex) {
      for (int surface : opposing[static_cast<std::size_t>(v)]) {
        SurfaceSlot slot;
        slot.vertex = v;
        slot.surface = surface;
        m_slots.push_back(slot);
      }
    }
    m_geometry = std::make_unique<ContactGeometry>(model.contact_surfaces);
  }
}

bool ContactSet::slot_changed(const SurfaceSlot& s) {
  if (s.inside != s.factored) return true;
  return s.inside && (s.triangle != s.factored_triangle ||
                      (s.barycentric - s.factored_barycentric).cwiseAbs().maxCoeff() > 1e-6);
}

void ContactSet::slot_column(const SurfaceSlot& s, SparseCholesky::Column& column) const {
  const double root = std::sqrt(m_model.contact_stiffness_N_m);
  column.clear();
  auto put = [&](int vertex, double value) {
    const int f = m_free_index[static_cast<std::size_t>(vertex)];
    if (value != 0.0 && f >= 0) column.emplace_back(f, root * value);
  };
  put(s.vertex, 1.0);
  for (int k = 0; k < 3; ++k)
    put(s.factored_triangle[static_cast<std::size_t>(k)], -s.factored_barycentric[k]);
}

double ContactSet::find(const Eigen::MatrixX3d& p, int threads) {
  if (m_geometry) m_geometry->update(p);
  const auto nf = static_cast<std::ptrdiff_t>(m_free_vertex.size());
  const double k = m_model.contact_stiffness_N_m;
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::ptrdiff_t f = 0; f < nf; ++f) {
    const Eigen::Vector3d x = p.row(m_free_vertex[static_cast<std::size_t>(f)]).transpose();
    int count = 0;
    double energy = 0.0;
    Eigen::Vector3d targets = Eigen::Vector3d::Zero();
    for (const Obstacle& o : m_model.obstacles) {
      if (!(o.signed_distance(x) < 0.0)) continue;
      const Eigen::Vector3d projection = o.project(x);
      ++count;
      targets += projection;
      energy += 0.5 * k * (x - projection).squaredNorm();
    }
    m_obstacle_count[static_cast<std::size_t>(f)] = count;
    m_obstacle_targets.row(f) = targets.transpose();
    m_obstacle_energies[static_cast<std::size_t>(f)] = energy;
  }
  const auto slot_count = static_cast<std::ptrdiff_t>(m_slots.size());
#pragma omp parallel for num_threads(threads) schedule(static) if (slot_count > 0)
  for (std::ptrdiff_t i = 0; i < slot_count; ++i) {
    SurfaceSlot& slot = m_slots[static_cast<std::size_t>(i)];
    const SurfaceQuery q = m_geometry->query(slot.surface, p.row(slot.vertex).transpose());
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
  for (double e : m_obstacle_energies)
    energy += e;
  for (const SurfaceSlot& slot : m_slots)
    energy += slot.energy;
  return energy;
}

int ContactSet::update_factor(SparseCholesky& factor) {
  if (m_model.obstacles.empty() && m_model.contact_pairs.empty()) return 0;
  std::vector<SparseCholesky::Column> add, remove;
  const double root = std::sqrt(m_model.contact_stiffness_N_m);
  int changes = 0;
  for (std::size_t f = 0; f < m_obstacle_count.size(); ++f) {
    if (m_obstacle_count[f] == m_factored_count[f]) continue;
    const int delta = m_obstacle_count[f] - m_factored_count[f];
    for (int k = 0; k < std::abs(delta); ++k)
      (delta > 0 ? add : remove).push_back({{static_cast<int>(f), root}});
    m_factored_count[f] = m_obstacle_count[f];
    ++changes;
  }
  SparseCholesky::Column column;
  for (SurfaceSlot& slot : m_slots) {
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
  if (!add.empty() || !remove.empty()) factor.update_columns(add, remove);
  return changes;
}

bool ContactSet::pending() const {
  if (m_obstacle_count != m_factored_count) return true;
  for (const SurfaceSlot& slot : m_slots)
    if (slot_changed(slot)) return true;
  return false;
}

void ContactSet::add_to_product(const Eigen::MatrixX3d& x, Eigen::MatrixX3d& Kx) const {
  for (std::size_t f = 0; f < m_factored_count.size(); ++f)
    if (m_factored_count[f] > 0)
      Kx.row(static_cast<Eigen::Index>(f)) +=
          (m_model.contact_stiffness_N_m * m_factored_count[f]) * x.row(static_cast<Eigen::Index>(f));
  SparseCholesky::Column column;
  for (const SurfaceSlot& slot : m_slots) {
    if (!slot.factored) continue;
    slot_column(slot, column);
    Eigen::RowVector3d cx = Eigen::RowVector3d::Zero();
    for (const auto& [row, value] : column)
      cx += value * x.row(row);
    for (const auto& [row, value] : column)
      Kx.row(row) += value * cx;
  }
}

void ContactSet::add_to_diagonal(Eigen::VectorXd& d) const {
  for (std::size_t f = 0; f < m_factored_count.size(); ++f)
    d[static_cast<Eigen::Index>(f)] += m_model.contact_stiffness_N_m * m_factored_count[f];
  SparseCholesky::Column column;
  for (const SurfaceSlot& slot : m_slots) {
    if (!slot.factored) continue;
    slot_column(slot, column);
    for (const auto& [row, value] : column)
      d[row] += value * value;
  }
}

void ContactSet::add_surface_rhs(Eigen::MatrixX3d& rhs) const {
  const double k = m_model.contact_stiffness_N_m;
  for (const SurfaceSlot& slot : m_slots) {
    if (!slot.factored) continue;
    Eigen::Vector4d c;
    c << 1.0, -slot.factored_barycentric;
    const Eigen::Vector3d d = slot.positions * c;
    const Eigen::Vector3d projected = d - std::min(0.0, d.dot(slot.normal)) * slot.normal;
    const std::array<int, 4> vertices = {slot.vertex, slot.factored_triangle[0], slot.factored_triangle[1],
                                         slot.factored_triangle[2]};
    for (int j = 0; j < 4; ++j) {
      const int row = m_free_index[static_cast<std::size_t>(vertices[static_cast<std::size_t>(j)])];
      if (row < 0 || c[j] == 0.0) continue;
      Eigen::Vector3d r = k * c[j] * projected;
      for (int i = 0; i < 4; ++i)
        if (m_free_index[static_cast<std::size_t>(vertices[static_cast<std::size_t>(i)])] < 0)
          r -= k * c[j] * c[i] * slot.positions.col(i);
      rhs.row(row) += r.transpose();
    }
  }
}

int ContactSet::count() const {
  int contacts = 0;
  for (int c : m_obstacle_count)
    contacts += c > 0 ? 1 : 0;
  for (const SurfaceSlot& slot : m_slots)
    contacts += slot.factored ? 1 : 0;
  return contacts;
}

} // namespace phantasm::sim_detail
