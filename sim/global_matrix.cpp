// The global system of the local/global solvers: the per-vertex adjacency, the assembly of
// a M + sum w A^T A over the free vertices, its factor, and products with the matrix it holds.
#include "sim/local_global_impl.hpp"

#include <numeric>
#include <stdexcept>
#include <string>

namespace phantasm {

void LocalGlobalSolver::Impl::build_adjacency() {
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
        for (std::size_t g = 0; g < model.tet_groups.size(); ++g)
          for (std::size_t k = 0; k < model.tet_groups[g].vertices.size(); ++k)
            use(model.tet_groups[g].vertices[k], static_cast<int>(g), static_cast<int>(k));
      },
      group_offsets, group_entries);
  build(
      [&](auto&& use) {
        for (std::size_t c = 0; c < model.points.size(); ++c)
          for (int k = 0; k < model.points[c].count; ++k)
            use(model.points[c].vertices[static_cast<std::size_t>(k)], static_cast<int>(c), k);
      },
      point_offsets, point_entries);
}

void LocalGlobalSolver::Impl::assemble_and_factor() {
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
  for (const TetGroup& g : model.tet_groups) {
    const Eigen::MatrixXd L = g.weight * g.G * g.G.transpose();
    for (std::size_t a = 0; a < g.vertices.size(); ++a)
      for (std::size_t b = 0; b < g.vertices.size(); ++b)
        add(g.vertices[a], g.vertices[b], L(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)));
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
    // Obstacle contacts stiffen a vertex along the obstacle's normal only: a factor per
    // coordinate (sim/contact_set.hpp).
    factor = std::make_unique<CoordinateFactors>(K_free, !model.obstacles.empty());
  } catch (const std::runtime_error&) {
    throw std::runtime_error("local/global: the global matrix is not positive definite (is anything holding "
                             "the model? quasi-static solves need fixed vertices or attachments)");
  }
  contacts = std::make_unique<sim_detail::ContactSet>(model, free_index, free_vertex);
  rhs.resize(nf, 3);
  coupling_rhs.setZero(nf, 3);
  solution.resize(nf, 3);
}

void LocalGlobalSolver::Impl::check_held() const {
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
    if (!model.fixed.empty() && model.fixed[v]) held[static_cast<std::size_t>(find(static_cast<int>(v)))] = 1;
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

Eigen::MatrixX3d LocalGlobalSolver::Impl::apply_matrix(const Eigen::MatrixX3d& x) const {
  Eigen::MatrixX3d Kx = K_free.selfadjointView<Eigen::Lower>() * x;
  contacts->add_to_product(x, Kx);
  return Kx;
}

Eigen::MatrixX3d LocalGlobalSolver::Impl::matrix_diagonal() const {
  Eigen::MatrixX3d d = K_free.diagonal().replicate(1, 3);
  contacts->add_to_diagonal(d);
  return d;
}

} // namespace phantasm
