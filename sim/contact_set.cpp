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
  const auto rows = static_cast<Eigen::Index>(nf);
  m_obstacle_count.assign(nf, 0);
  m_obstacle_positions.setZero(rows, 3);
  m_obstacle_gradients.setZero(rows, 3);
  m_obstacle_weights.setZero(rows, 3);
  m_factored_weights.setZero(rows, 3);
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
    Eigen::Vector3d gradient = Eigen::Vector3d::Zero(), weights = Eigen::Vector3d::Zero();
    for (const Obstacle& o : m_model.obstacles) {
      if (!(o.signed_distance(x) < 0.0)) continue;
      const Eigen::Vector3d offset = x - o.project(x);
      const Eigen::Vector3d n = o.outward_normal(x);
      ++count;
      gradient += k * offset;
      weights += k * n.lpNorm<1>() * n.cwiseAbs();
      energy += 0.5 * k * offset.squaredNorm();
    }
    m_obstacle_count[static_cast<std::size_t>(f)] = count;
    m_obstacle_positions.row(f) = x.transpose();
    m_obstacle_gradients.row(f) = gradient.transpose();
    m_obstacle_weights.row(f) = weights.transpose();
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

double ContactSet::factored_weight(double needed, double held) const {
  // Rounded up to a step of kc/64 and kept while it stays within two steps above what is
  // needed, so a contact on a curved obstacle does not change the factors at every iteration;
  // never below the need, so the global step's matrix stays above the contact's Hessian.
  const double step = m_model.contact_stiffness_N_m / 64.0;
  if (needed <= 0.0) return 0.0;
  if (held >= needed && held <= needed + 2.0 * step) return held;
  return std::ceil(needed / step) * step;
}

int ContactSet::update_factor(CoordinateFactors& factors) {
  if (m_model.obstacles.empty() && m_model.contact_pairs.empty()) return 0;
  std::array<std::vector<SparseCholesky::Column>, 3> add_obstacles, remove_obstacles;
  int changes = 0;
  for (std::size_t f = 0; f < m_obstacle_count.size(); ++f) {
    const auto row = static_cast<Eigen::Index>(f);
    Eigen::RowVector3d needed = m_obstacle_weights.row(row);
    if (!factors.per_coordinate()) needed.setConstant(needed.maxCoeff()); // one factor: the largest
    bool changed = false;
    for (int c = 0; c < 3; ++c) {
      const double held = m_factored_weights(row, c);
      const double weight = factored_weight(needed[c], held);
      if (weight == held) continue;
      const int coordinate = factors.per_coordinate() ? c : 0;
      if (factors.per_coordinate() || c == 0)
        (weight > held ? add_obstacles : remove_obstacles)[static_cast<std::size_t>(coordinate)].push_back(
            {{static_cast<int>(f), std::sqrt(std::abs(weight - held))}});
      m_factored_weights(row, c) = weight;
      changed = true;
    }
    changes += changed ? 1 : 0;
  }
  for (int c = 0; c < (factors.per_coordinate() ? 3 : 1); ++c) {
    const auto i = static_cast<std::size_t>(c);
    if (!add_obstacles[i].empty() || !remove_obstacles[i].empty())
      factors[c].update_columns(add_obstacles[i], remove_obstacles[i]);
  }
  std::vector<SparseCholesky::Column> add, remove;
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
  if (!add.empty() || !remove.empty()) factors.update_all(add, remove);
  return changes;
}

bool ContactSet::pending() const {
  for (Eigen::Index f = 0; f < m_factored_weights.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      if (factored_weight(m_obstacle_weights(f, c), m_factored_weights(f, c)) != m_factored_weights(f, c))
        return true;
  for (const SurfaceSlot& slot : m_slots)
    if (slot_changed(slot)) return true;
  return false;
}

void ContactSet::add_to_product(const Eigen::MatrixX3d& x, Eigen::MatrixX3d& Kx) const {
  if (!m_model.obstacles.empty()) Kx += m_factored_weights.cwiseProduct(x);
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

void ContactSet::add_to_diagonal(Eigen::MatrixX3d& d) const {
  if (!m_model.obstacles.empty()) d += m_factored_weights;
  SparseCholesky::Column column;
  for (const SurfaceSlot& slot : m_slots) {
    if (!slot.factored) continue;
    slot_column(slot, column);
    for (const auto& [row, value] : column)
      d.row(row).array() += value * value;
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
