#include "sim/elastic_model.hpp"

#include <cmath>
#include <map>
#include <stdexcept>
#include <vector>

namespace phantasm {

LameParameters lame_parameters(double E, double nu) {
  return {E / (2.0 * (1.0 + nu)), E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))};
}

int add_body(ElasticModel& model, const Eigen::MatrixX3d& rest_m, const Eigen::MatrixX4i& tets,
             const LameParameters& material, double density_kg_m3) {
  return add_body(
      model, rest_m, tets,
      std::vector<TetMaterial>(static_cast<std::size_t>(tets.rows()), TetMaterial{material, density_kg_m3}));
}

namespace {

/// Appends free vertices without mass; returns the index of the first.
int append_vertices(ElasticModel& model, const Eigen::MatrixX3d& rest_m) {
  const auto first_vertex = static_cast<int>(model.rest_positions_m.rows());
  const Eigen::Index total = first_vertex + rest_m.rows();
  model.rest_positions_m.conservativeResize(total, 3);
  model.rest_positions_m.bottomRows(rest_m.rows()) = rest_m;
  model.masses_kg.conservativeResize(total);
  model.masses_kg.tail(rest_m.rows()).setZero();
  model.fixed.resize(static_cast<std::size_t>(total), 0);
  return first_vertex;
}

} // namespace

int add_body(ElasticModel& model, const Eigen::MatrixX3d& rest_m, const Eigen::MatrixX4i& tets,
             const std::vector<TetMaterial>& materials) {
  if (materials.size() != static_cast<std::size_t>(tets.rows()))
    throw std::invalid_argument("add_body: expected one material per tet");
  const int first_vertex = append_vertices(model, rest_m);
  Eigen::Matrix<double, 4, 3> selector;
  selector << -1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    TetElement e;
    Eigen::Matrix3d Dm;
    for (int k = 0; k < 4; ++k)
      e.vertices[static_cast<std::size_t>(k)] = first_vertex + tets(t, k);
    for (int k = 0; k < 3; ++k)
      Dm.col(k) = (rest_m.row(tets(t, k + 1)) - rest_m.row(tets(t, 0))).transpose();
    e.rest_volume_m3 = Dm.determinant() / 6.0;
    if (!(e.rest_volume_m3 > 0.0)) {
      throw std::invalid_argument("tet " + std::to_string(t) + " has rest volume " +
                                  std::to_string(e.rest_volume_m3) + " m^3; expected a positive volume");
    }
    e.Q = selector * Dm.inverse();
    const TetMaterial& material = materials[static_cast<std::size_t>(t)];
    e.strain_weight = 2.0 * material.lame.mu * e.rest_volume_m3;
    e.volume_weight = 3.0 * material.lame.lambda * e.rest_volume_m3;
    for (int k = 0; k < 4; ++k)
      model.masses_kg[e.vertices[static_cast<std::size_t>(k)]] +=
          0.25 * material.density_kg_m3 * e.rest_volume_m3;
    model.tets.push_back(e);
  }
  return first_vertex;
}

Eigen::Matrix3d deformation_gradient(const TetElement& e, const Eigen::MatrixX3d& p) {
  Eigen::Matrix<double, 3, 4> X;
  for (int k = 0; k < 4; ++k)
    X.col(k) = p.row(e.vertices[static_cast<std::size_t>(k)]).transpose();
  return X * e.Q;
}

Eigen::Matrix3d group_deformation_gradient(const TetGroup& g, const Eigen::MatrixX3d& p) {
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < g.vertices.size(); ++k)
    F.noalias() += p.row(g.vertices[k]).transpose() * g.G.row(static_cast<Eigen::Index>(k));
  return F;
}

int add_sheet(ElasticModel& model, const Eigen::MatrixX3d& rest_m, const Eigen::MatrixX3i& faces,
              double youngs_modulus_Pa, double poisson_ratio, double density_kg_m3, double thickness_m) {
  const int first_vertex = append_vertices(model, rest_m);
  const LameParameters lame = lame_parameters(youngs_modulus_Pa, poisson_ratio);
  const double bending_stiffness =
      youngs_modulus_Pa * std::pow(thickness_m, 3) / (12.0 * (1.0 - poisson_ratio * poisson_ratio));
  // Interior edges: the two triangles sharing each (sorted) edge, and their opposite vertices.
  std::map<std::pair<int, int>, std::vector<std::pair<Eigen::Index, int>>> edges;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const std::array<int, 3> v = {first_vertex + faces(f, 0), first_vertex + faces(f, 1),
                                  first_vertex + faces(f, 2)};
    SurfaceElement triangle = triangle_strain_element(v, model.rest_positions_m, lame.mu * thickness_m);
    const double area = triangle.weight / (2.0 * lame.mu * thickness_m);
    // Plane stress: lambda* = 2 lambda mu / (lambda + 2 mu); the distance of the singular values
    // to product 1 is |tr e| / sqrt 2, so weight 2 lambda* t A gives lambda*/2 (tr e)^2 t A.
    const double plane_lambda = 2.0 * lame.lambda * lame.mu / (lame.lambda + 2.0 * lame.mu);
    if (plane_lambda > 0.0)
      model.surfaces.push_back(
          triangle_area_element(v, model.rest_positions_m, 2.0 * plane_lambda * thickness_m * area));
    for (int k = 0; k < 3; ++k) {
      model.masses_kg[v[static_cast<std::size_t>(k)]] += density_kg_m3 * thickness_m * area / 3.0;
      const int a = v[static_cast<std::size_t>(k)], b = v[static_cast<std::size_t>((k + 1) % 3)];
      edges[{std::min(a, b), std::max(a, b)}].emplace_back(f, v[static_cast<std::size_t>((k + 2) % 3)]);
    }
    model.surfaces.push_back(triangle);
  }
  for (const auto& [edge, sides] : edges) {
    if (sides.size() != 2) continue; // a boundary (or non-manifold) edge does not bend
    model.surfaces.push_back(bending_element({edge.first, edge.second, sides[0].second, sides[1].second},
                                             model.rest_positions_m, bending_stiffness));
  }
  return first_vertex;
}

namespace {} // namespace

std::vector<SurfaceContact> surface_contacts(const ElasticModel& model, const Eigen::MatrixX3d& p) {
  std::vector<SurfaceContact> contacts;
  if (model.contact_pairs.empty()) return contacts;
  ContactGeometry geometry(model.contact_surfaces);
  geometry.update(p);
  const auto opposing = opposing_surfaces(model.contact_surfaces, model.contact_pairs, p.rows());
  for (Eigen::Index v = 0; v < p.rows(); ++v) {
    if (!model.fixed.empty() && model.fixed[static_cast<std::size_t>(v)]) continue;
    for (int s : opposing[static_cast<std::size_t>(v)]) {
      const SurfaceQuery q = geometry.query(s, p.row(v).transpose());
      if (q.inside) contacts.push_back({v, q});
    }
  }
  return contacts;
}

namespace {

Eigen::Vector3d point_of(const PointConstraint& c, const Eigen::MatrixX3d& p) {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  for (int k = 0; k < c.count; ++k)
    x += c.coefficients[k] * p.row(c.vertices[static_cast<std::size_t>(k)]).transpose();
  return x;
}

/// dE/dF of both tet constraints at F: U diag(psi_strain + psi_volume) V^T, and their energy.
Eigen::Matrix3d tet_stress(const ElasticModel& model, const TetElement& e, const Eigen::Matrix3d& F,
                           double* energy) {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  const SignedSvd svd = signed_svd(F, rotation);
  const SingularValueEnergy strain =
      singular_value_energy(TetConstraintKind::strain, model.strain_range, e.strain_weight, svd.sigma, false);
  const SingularValueEnergy volume =
      singular_value_energy(TetConstraintKind::volume, model.volume_range, e.volume_weight, svd.sigma, false);
  *energy = strain.value + volume.value;
  return svd.U * (strain.gradient + volume.gradient).asDiagonal() * svd.V.transpose();
}

/// dE/dF_g of a tet group's volume term at F: U diag(psi) V^T, and its energy.
Eigen::Matrix3d group_stress(const ElasticModel& model, const TetGroup& g, const Eigen::Matrix3d& F,
                             double* energy) {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  const SignedSvd svd = signed_svd(F, rotation);
  const SingularValueEnergy volume =
      singular_value_energy(TetConstraintKind::volume, model.volume_range, g.weight, svd.sigma, false);
  *energy = volume.value;
  return svd.U * volume.gradient.asDiagonal() * svd.V.transpose();
}

/// Every tet's and tet group's stress and energy at p. Each element's own SVD and projections
/// (most of an energy or gradient evaluation) in parallel, each into its slot: the callers sum
/// and scatter them in element order, so their results do not depend on the number of threads.
struct ElementStresses {
  std::vector<Eigen::Matrix3d> tets, groups;
  std::vector<double> tet_energies, group_energies;
};

ElementStresses element_stresses(const ElasticModel& model, const Eigen::MatrixX3d& p) {
  ElementStresses s;
  const auto tets = static_cast<std::ptrdiff_t>(model.tets.size());
  const auto groups = static_cast<std::ptrdiff_t>(model.tet_groups.size());
  s.tets.resize(model.tets.size());
  s.tet_energies.resize(model.tets.size());
  s.groups.resize(model.tet_groups.size());
  s.group_energies.resize(model.tet_groups.size());
#pragma omp parallel if (tets + groups > 1024)
  {
#pragma omp for schedule(static) nowait
    for (std::ptrdiff_t t = 0; t < tets; ++t) {
      const auto i = static_cast<std::size_t>(t);
      const TetElement& e = model.tets[i];
      s.tets[i] = tet_stress(model, e, deformation_gradient(e, p), &s.tet_energies[i]);
    }
#pragma omp for schedule(static)
    for (std::ptrdiff_t c = 0; c < groups; ++c) {
      const auto i = static_cast<std::size_t>(c);
      const TetGroup& g = model.tet_groups[i];
      s.groups[i] = group_stress(model, g, group_deformation_gradient(g, p), &s.group_energies[i]);
    }
  }
  return s;
}

} // namespace

double model_energy(const ElasticModel& model, const StepInertia& inertia, const Eigen::MatrixX3d& p) {
  double energy = 0.0;
  if (inertia.weight > 0.0) {
    energy += 0.5 * inertia.weight *
              (model.masses_kg.asDiagonal() * (p - inertia.target_m).rowwise().squaredNorm()).sum();
  }
  if (model.external_forces_N.rows() == p.rows()) energy -= model.external_forces_N.cwiseProduct(p).sum();
  const ElementStresses stresses = element_stresses(model, p);
  for (double tet : stresses.tet_energies)
    energy += tet;
  for (double group : stresses.group_energies)
    energy += group;
  for (const SurfaceElement& e : model.surfaces) {
    const SurfaceMatrix F = surface_deformation(e, p);
    energy += 0.5 * e.weight * (F - project_surface(e, F)).squaredNorm(); // unused columns are 0
  }
  for (const EnclosedVolume& c : model.volumes) {
    const Eigen::MatrixX3d X = gather_vertices(c, p);
    energy += 0.5 * c.weight * (X - project_enclosed_volume(c, X)).squaredNorm();
  }
  for (const PointConstraint& c : model.points)
    energy += 0.5 * c.stiffness_N_m * (point_of(c, p) - c.target_m).squaredNorm();
  if (!model.obstacles.empty()) {
    for (Eigen::Index v = 0; v < p.rows(); ++v)
      if (model.fixed.empty() || !model.fixed[static_cast<std::size_t>(v)])
        energy += contact_energy(model.obstacles, model.contact_stiffness_N_m, p.row(v).transpose());
  }
  for (const SurfaceContact& c : surface_contacts(model, p))
    energy += 0.5 * model.contact_stiffness_N_m * c.query.distance * c.query.distance;
  return energy;
}

Eigen::MatrixX3d model_gradient(const ElasticModel& model, const StepInertia& inertia,
                                const Eigen::MatrixX3d& p) {
  Eigen::MatrixX3d g = Eigen::MatrixX3d::Zero(p.rows(), 3);
  if (inertia.weight > 0.0) g += inertia.weight * (model.masses_kg.asDiagonal() * (p - inertia.target_m));
  if (model.external_forces_N.rows() == p.rows()) g -= model.external_forces_N;
  const ElementStresses stresses = element_stresses(model, p);
  for (std::size_t t = 0; t < model.tets.size(); ++t) {
    const TetElement& e = model.tets[t];
    // dE/dX = P Q^T: column k is the force on vertex k.
    const Eigen::Matrix<double, 3, 4> forces = stresses.tets[t] * e.Q.transpose();
    for (int k = 0; k < 4; ++k)
      g.row(e.vertices[static_cast<std::size_t>(k)]) += forces.col(k).transpose();
  }
  for (std::size_t i = 0; i < model.tet_groups.size(); ++i) {
    const TetGroup& group = model.tet_groups[i];
    const Eigen::Matrix3d& P = stresses.groups[i];
    for (std::size_t k = 0; k < group.vertices.size(); ++k) // dE/dX = P G^T
      g.row(group.vertices[k]) += (P * group.G.row(static_cast<Eigen::Index>(k)).transpose()).transpose();
  }
  for (const SurfaceElement& e : model.surfaces) {
    // d/dX w/2 |F - P(F)|^2 = w (F - P(F)) Q^T (the distance to a set: envelope theorem).
    const SurfaceMatrix F = surface_deformation(e, p);
    const SurfaceMatrix stress = e.weight * (F - project_surface(e, F));
    for (int k = 0; k < e.count; ++k)
      g.row(e.vertices[static_cast<std::size_t>(k)]) += (stress * e.Q.row(k).transpose()).transpose();
  }
  for (const EnclosedVolume& c : model.volumes) {
    // w (X - P(X)), by the envelope theorem as for the other constraints.
    const Eigen::MatrixX3d X = gather_vertices(c, p);
    const Eigen::MatrixX3d stress = c.weight * (X - project_enclosed_volume(c, X));
    for (std::size_t i = 0; i < c.vertices.size(); ++i)
      g.row(c.vertices[i]) += stress.row(static_cast<Eigen::Index>(i));
  }
  for (const PointConstraint& c : model.points) {
    const Eigen::Vector3d r = c.stiffness_N_m * (point_of(c, p) - c.target_m);
    for (int k = 0; k < c.count; ++k)
      g.row(c.vertices[static_cast<std::size_t>(k)]) += c.coefficients[k] * r.transpose();
  }
  if (!model.obstacles.empty()) {
    for (Eigen::Index v = 0; v < p.rows(); ++v)
      if (model.fixed.empty() || !model.fixed[static_cast<std::size_t>(v)])
        g.row(v) +=
            contact_gradient(model.obstacles, model.contact_stiffness_N_m, p.row(v).transpose()).transpose();
  }
  // kc/2 |x_v - y|^2 with y = sum b_k x_k the closest point (fixed b: the envelope theorem).
  for (const SurfaceContact& c : surface_contacts(model, p)) {
    const Eigen::RowVector3d force =
        model.contact_stiffness_N_m * (p.row(c.vertex) - c.query.closest.transpose());
    g.row(c.vertex) += force;
    for (int k = 0; k < 3; ++k)
      g.row(c.query.triangle[static_cast<std::size_t>(k)]) -= c.query.barycentric[k] * force;
  }
  return g;
}

double free_gradient_norm(const ElasticModel& model, const Eigen::MatrixX3d& gradient) {
  double largest = 0.0;
  for (Eigen::Index v = 0; v < gradient.rows(); ++v) {
    if (!model.fixed.empty() && model.fixed[static_cast<std::size_t>(v)]) continue;
    largest = std::max(largest, gradient.row(v).norm());
  }
  return largest;
}

} // namespace phantasm
