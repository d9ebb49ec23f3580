#include "sim/position_based.hpp"

#include "core/cancellation.hpp"
#include "core/progress.hpp"
#include "sim/newton.hpp"
#include "sim/signed_svd.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>

namespace phantasm {
namespace {

/// One constraint's value and its gradient with respect to up to four vertices.
struct Linearized {
  double value = 0.0;
  int count = 0;
  std::array<int, 4> vertices{};
  std::array<Eigen::Vector3d, 4> gradients;
};

/// The same for a constraint over many vertices (an enclosed volume).
struct LinearizedMany {
  double value = 0.0;
  int count = 0;
  std::vector<int> vertices;
  std::vector<Eigen::Vector3d> gradients;
};

class Sweeper {
public:
  Sweeper(PositionBasedVariant variant, const ElasticModel& model, double inertia_weight)
      : m_variant(variant), m_model(model), m_alpha_scale(inertia_weight),
        m_rotations(2 * model.tets.size(), Eigen::Quaterniond::Identity()),
        m_eigenvectors(2 * model.tets.size(), Eigen::Quaterniond::Identity()),
        m_tet_lambda(2 * model.tets.size(), 0.0), m_surface_lambda(model.surfaces.size(), 0.0),
        m_point_lambda(model.points.size(), 0.0), m_volume_lambda(model.volumes.size(), 0.0),
        m_group_rotations(model.tet_groups.size(), Eigen::Quaterniond::Identity()),
        m_group_lambda(model.tet_groups.size(), 0.0),
        m_inverse_mass(static_cast<std::size_t>(model.vertex_count()), 0.0) {
    for (Eigen::Index v = 0; v < model.vertex_count(); ++v) {
      const bool fixed = !model.fixed.empty() && model.fixed[static_cast<std::size_t>(v)];
      if (!fixed && model.masses_kg[v] > 0.0)
        m_inverse_mass[static_cast<std::size_t>(v)] = 1.0 / model.masses_kg[v];
    }
    if (!model.obstacles.empty())
      m_contact_lambda.assign(static_cast<std::size_t>(model.vertex_count()) * model.obstacles.size(), 0.0);
    if (!model.contact_pairs.empty()) {
      m_opposing = opposing_surfaces(model.contact_surfaces, model.contact_pairs, model.vertex_count());
      m_geometry = std::make_unique<ContactGeometry>(model.contact_surfaces);
    }
  }

  /// One sweep over every constraint; returns the largest distance a vertex moved.
  double sweep(Eigen::MatrixX3d& p) {
    const Eigen::MatrixX3d before = p;
    for (std::size_t t = 0; t < m_model.tets.size(); ++t) {
      const TetElement& e = m_model.tets[t];
      if (e.strain_weight > 0.0)
        apply(tet_constraint(e, t, TetConstraintKind::strain, p), e.strain_weight, m_tet_lambda[2 * t], p);
      if (e.volume_weight > 0.0)
        apply(tet_constraint(e, t, TetConstraintKind::volume, p), e.volume_weight, m_tet_lambda[2 * t + 1],
              p);
    }
    for (std::size_t c = 0; c < m_model.tet_groups.size(); ++c) {
      // C = |sigma - P(sigma)| of the averaged F_g = X G: dC/dx_k = U diag(d / C) V^T G_k.
      const TetGroup& group = m_model.tet_groups[c];
      const SignedSvd svd = signed_svd(group_deformation_gradient(group, p), m_group_rotations[c]);
      const Eigen::Vector3d d = svd.sigma - project_volume(svd.sigma, m_model.volume_range);
      LinearizedMany l;
      l.value = d.norm();
      if (l.value > 0.0) {
        const Eigen::Matrix3d dC = svd.U * (d / l.value).asDiagonal() * svd.V.transpose();
        l.count = static_cast<int>(group.vertices.size());
        l.vertices = group.vertices;
        for (Eigen::Index k = 0; k < group.G.rows(); ++k)
          l.gradients.push_back(dC * group.G.row(k).transpose());
      }
      apply(l, group.weight, m_group_lambda[c], p);
    }
    for (std::size_t s = 0; s < m_model.surfaces.size(); ++s) {
      const SurfaceElement& e = m_model.surfaces[s];
      const SurfaceMatrix F = surface_deformation(e, p);
      const SurfaceMatrix d = F - project_surface(e, F);
      Linearized l;
      l.value = d.norm();
      if (l.value > 0.0) {
        l.count = e.count;
        for (int k = 0; k < e.count; ++k) {
          l.vertices[static_cast<std::size_t>(k)] = e.vertices[static_cast<std::size_t>(k)];
          l.gradients[static_cast<std::size_t>(k)] = d * e.Q.row(k).transpose() / l.value;
        }
      }
      apply(l, e.weight, m_surface_lambda[s], p);
    }
    for (std::size_t c = 0; c < m_model.volumes.size(); ++c) {
      // C = |X - P(X)|, dC/dX = (X - P(X)) / C, as for the element constraints.
      const EnclosedVolume& volume = m_model.volumes[c];
      const Eigen::MatrixX3d X = gather_vertices(volume, p);
      const Eigen::MatrixX3d d = X - project_enclosed_volume(volume, X);
      LinearizedMany l;
      l.value = d.norm();
      if (l.value > 0.0) {
        l.count = static_cast<int>(volume.vertices.size());
        l.vertices = volume.vertices;
        for (Eigen::Index k = 0; k < d.rows(); ++k)
          l.gradients.push_back(d.row(k).transpose() / l.value);
      }
      apply(l, volume.weight, m_volume_lambda[c], p);
    }
    for (std::size_t c = 0; c < m_model.points.size(); ++c) {
      const PointConstraint& point = m_model.points[c];
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (int k = 0; k < point.count; ++k)
        x += point.coefficients[k] * p.row(point.vertices[static_cast<std::size_t>(k)]).transpose();
      const Eigen::Vector3d r = x - point.target_m;
      Linearized l;
      l.value = r.norm();
      if (l.value > 0.0) {
        l.count = point.count;
        for (int k = 0; k < point.count; ++k) {
          l.vertices[static_cast<std::size_t>(k)] = point.vertices[static_cast<std::size_t>(k)];
          l.gradients[static_cast<std::size_t>(k)] = point.coefficients[k] * r / l.value;
        }
      }
      apply(l, point.stiffness_N_m, m_point_lambda[c], p);
    }
    for (std::size_t o = 0; o < m_model.obstacles.size(); ++o) {
      const Obstacle& obstacle = m_model.obstacles[o];
      for (Eigen::Index v = 0; v < p.rows(); ++v) {
        double& lambda = m_contact_lambda[static_cast<std::size_t>(v) * m_model.obstacles.size() + o];
        if (m_inverse_mass[static_cast<std::size_t>(v)] == 0.0) continue;
        const Eigen::Vector3d x = p.row(v).transpose();
        const double depth = -obstacle.signed_distance(x);
        if (!(depth > 0.0)) {
          lambda = 0.0; // not in contact: the constraint is inactive
          continue;
        }
        Linearized l;
        l.value = depth;
        l.count = 1;
        l.vertices[0] = static_cast<int>(v);
        l.gradients[0] = -obstacle.outward_normal(x);
        apply(l, m_model.contact_stiffness_N_m, lambda, p);
      }
    }
    if (m_geometry) {
      // Other bodies' surfaces as they are at this point of the sweep.
      m_geometry->update(p);
      for (Eigen::Index v = 0; v < p.rows(); ++v) {
        if (m_inverse_mass[static_cast<std::size_t>(v)] == 0.0) continue;
        for (int s : m_opposing[static_cast<std::size_t>(v)]) {
          const SurfaceQuery q = m_geometry->query(s, p.row(v).transpose());
          double lambda = 0.0; // contacts change from sweep to sweep: no multiplier carried over
          if (!q.inside) continue;
          // C = depth: the vertex moves out along n, the triangle's vertices (by b) back.
          Linearized l;
          l.value = q.distance;
          l.count = 4;
          l.vertices[0] = static_cast<int>(v);
          l.gradients[0] = -q.normal;
          for (int k = 0; k < 3; ++k) {
            l.vertices[static_cast<std::size_t>(k + 1)] = q.triangle[static_cast<std::size_t>(k)];
            l.gradients[static_cast<std::size_t>(k + 1)] = q.barycentric[k] * q.normal;
          }
          apply(l, m_model.contact_stiffness_N_m, lambda, p);
        }
      }
    }
    return (p - before).rowwise().norm().maxCoeff();
  }

private:
  Linearized tet_constraint(const TetElement& e, std::size_t t, TetConstraintKind kind,
                            const Eigen::MatrixX3d& p) {
    const std::size_t slot = 2 * t + (kind == TetConstraintKind::volume ? 1 : 0);
    const SignedSvd svd = signed_svd(deformation_gradient(e, p), m_rotations[slot], m_eigenvectors[slot]);
    const Eigen::Vector3d target = kind == TetConstraintKind::strain
                                       ? project_strain(svd.sigma, m_model.strain_range)
                                       : project_volume(svd.sigma, m_model.volume_range);
    const Eigen::Vector3d d = svd.sigma - target;
    Linearized l;
    l.value = d.norm();
    if (!(l.value > 0.0)) return l;
    // dC/dF = U diag(d / C) V^T (the distance to a set: the unit vector away from its projection).
    const Eigen::Matrix3d G = svd.U * (d / l.value).asDiagonal() * svd.V.transpose();
    l.count = 4;
    for (int k = 0; k < 4; ++k) {
      l.vertices[static_cast<std::size_t>(k)] = e.vertices[static_cast<std::size_t>(k)];
      l.gradients[static_cast<std::size_t>(k)] = G * e.Q.row(k).transpose();
    }
    return l;
  }

  /// The XPBD or PBD update of one linearized constraint with stiffness w.
  template <typename Constraint>
  void apply(const Constraint& l, double stiffness, double& lambda, Eigen::MatrixX3d& p) const {
    if (l.count == 0 && m_variant == PositionBasedVariant::xpbd) {
      // At C = 0 the gradient is undefined; the multiplier's own relaxation still applies
      // (dlambda = -lambda alpha~ / alpha~), which needs no position update.
      lambda = 0.0;
      return;
    }
    double denominator = 0.0;
    for (int k = 0; k < l.count; ++k)
      denominator += m_inverse_mass[static_cast<std::size_t>(l.vertices[static_cast<std::size_t>(k)])] *
                     l.gradients[static_cast<std::size_t>(k)].squaredNorm();
    double dlambda = 0.0;
    if (m_variant == PositionBasedVariant::xpbd) {
      const double alpha = m_alpha_scale / stiffness; // alpha~ = (1 / w) / h^2
      if (!(denominator + alpha > 0.0)) return;
      dlambda = (-l.value - alpha * lambda) / (denominator + alpha);
      lambda += dlambda;
    } else {
      if (!(denominator > 1e-300)) return;
      dlambda = -l.value / denominator;
    }
    for (int k = 0; k < l.count; ++k) {
      const auto v = static_cast<Eigen::Index>(l.vertices[static_cast<std::size_t>(k)]);
      p.row(v) += (m_inverse_mass[static_cast<std::size_t>(v)] * dlambda) *
                  l.gradients[static_cast<std::size_t>(k)].transpose();
    }
  }

  PositionBasedVariant m_variant;
  const ElasticModel& m_model;
  double m_alpha_scale; ///< 1/h^2
  std::vector<Eigen::Quaterniond> m_rotations, m_eigenvectors;
  std::vector<double> m_tet_lambda, m_surface_lambda, m_point_lambda, m_volume_lambda, m_contact_lambda;
  std::vector<Eigen::Quaterniond> m_group_rotations;
  std::vector<double> m_group_lambda;
  std::vector<double> m_inverse_mass;
  std::vector<std::vector<int>> m_opposing;
  std::unique_ptr<ContactGeometry> m_geometry;
};

} // namespace

SolveReport position_based_solve(PositionBasedVariant variant, const ElasticModel& model,
                                 const StepInertia& inertia, Eigen::MatrixX3d& p, const StopCriteria& stop,
                                 bool record_energies, const IterationObserver& observer) {
  using Clock = std::chrono::steady_clock;
  const char* name = variant == PositionBasedVariant::xpbd ? "xpbd" : "gauss_seidel_pbd";
  if (!(inertia.weight > 0.0)) {
    throw std::invalid_argument(
        std::string(name) +
        " steps in time: it needs a dynamic step (a time step), not a quasi-static solve");
  }
  SolveReport report;
  report.solver = name;
  // External forces move the prediction: M/h^2 (x - s) - f = M/h^2 (x - s - h^2 M^-1 f).
  if (model.external_forces_N.rows() == p.rows()) {
    for (Eigen::Index v = 0; v < p.rows(); ++v) {
      const bool fixed = !model.fixed.empty() && model.fixed[static_cast<std::size_t>(v)];
      if (!fixed && model.masses_kg[v] > 0.0)
        p.row(v) += model.external_forces_N.row(v) / (inertia.weight * model.masses_kg[v]);
    }
  }
  Sweeper sweeper(variant, model, inertia.weight);
  double energy = model_energy(model, inertia, p);
  report.initial_energy_J = energy;
  if (record_energies) {
    report.energies_J.push_back(energy);
    report.seconds.push_back(0.0);
  }
  if (observer) observer(0, p, energy);
  report.stopped_by = "max_iterations";
  double solver_seconds = 0.0;
  // The residual is evaluated after every sweep, like E, outside the solver's time.
  double residual = free_gradient_norm(model, model_gradient(model, inertia, p));
  const ResidualTest test(stop, residual);
  // The sweeps start from p, as the other solvers do (the prediction: s with the prescribed
  // vertices placed). XPBD takes M (x - s) = sum grad C lambda as given rather than solving for
  // it, so where gradients turn during the step its fixed point is near, not at, the minimizer.
  for (int iteration = 1; iteration <= stop.max_iterations; ++iteration) {
    throw_if_cancelled(); // an iteration takes milliseconds to a second: SIGINT stops here
    const auto start_time = Clock::now();
    sweeper.sweep(p);
    solver_seconds += std::chrono::duration<double>(Clock::now() - start_time).count();
    energy = model_energy(model, inertia, p);
    report.iterations = iteration;
    if (record_energies) {
      report.energies_J.push_back(energy);
      report.seconds.push_back(solver_seconds);
    }
    if (observer) observer(iteration, p, energy);
    if (!p.allFinite()) throw std::runtime_error(std::string(name) + ": non-finite positions");
    residual = free_gradient_norm(model, model_gradient(model, inertia, p));
    if (progress_detail_due()) progress_detail(solver_detail(iteration, residual));
    // The step criteria measure a sweep, not the distance to equilibrium: they stop only a
    // solve whose residual test passes, which stops it by itself. Gauss-Seidel PBD's fixed point
    // is not the energy's minimizer (and XPBD's only near it): they may run to the limit and
    // say they did not converge.
    if (test.passes(residual)) {
      report.stopped_by = "residual";
      break;
    }
  }
  report.final_energy_J = energy;
  report.local_seconds = solver_seconds;
  report.residual_N = residual;
  finish_solve(model, inertia, p, stop, test, false, report);
  return report;
}

} // namespace phantasm
