#include "sim/newton.hpp"

#include "core/cancellation.hpp"
#include "core/progress.hpp"
#include "sim/vertex_star_volumes.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/Eigenvalues>
#include <Eigen/Sparse>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace phantasm {
namespace {

/// The Hessian of a surface element's energy w/2 |F - P(F)|^2 in F (vec(F), 3 x columns
/// entries, column by column), w (I - dP/dF), with dP/dF by central differences of the
/// projection (the gradient w (F - P(F)) is exact; P is smooth away from the set's kinks), and
/// negative eigenvalues clamped to zero. Where a membrane is compressed or folded its rotational
/// modes have no stiffness (the energy is flat there), which the Gauss-Newton matrix w I does not
/// see: with it Newton crawled on a swinging sheet, one inertia-sized step per iteration.
/// Up to 6 x 6 (a triangle's F has 6 entries), without heap allocation.
using SurfaceHessian = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;

SurfaceHessian surface_hessian(const SurfaceElement& e, const SurfaceMatrix& F) {
  // F has at most SurfaceMatrix's 2 columns (the clamp also tells the compiler so).
  const int n = 3 * std::clamp(e.columns, 1, 2);
  // A flat rest state's bending target is e = 0: the energy is quadratic, its Hessian w I.
  if (e.kind == SurfaceConstraintKind::bending && e.rest.norm() == 0.0)
    return e.weight * SurfaceHessian::Identity(n, n);
  const double h = 1e-6 * std::max(1.0, F.leftCols(n / 3).norm());
  SurfaceHessian dP(n, n);
  for (int i = 0; i < n; ++i) {
    SurfaceMatrix plus = F, minus = F;
    plus(i % 3, i / 3) += h;
    minus(i % 3, i / 3) -= h;
    const SurfaceMatrix d = (project_surface(e, plus) - project_surface(e, minus)) / (2.0 * h);
    for (int j = 0; j < n; ++j)
      dP(j, i) = d(j % 3, j / 3);
  }
  const SurfaceHessian H = e.weight * (SurfaceHessian::Identity(n, n) - 0.5 * (dP + dP.transpose()));
  const Eigen::SelfAdjointEigenSolver<SurfaceHessian> eigen(H);
  return eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() *
         eigen.eigenvectors().transpose();
}

/// The PSD-projected Hessian over the free coordinates (3 per free vertex, lower triangle).
/// `entries` is the triplets' workspace, kept between iterations: its memory is reused rather
/// than faulted in anew each time (a swinging sheet's million entries cost more than the factor).
Eigen::SparseMatrix<double> assemble_hessian(const ElasticModel& model, const StepInertia& inertia,
                                             const Eigen::MatrixX3d& p, const std::vector<int>& free_index,
                                             Eigen::Index free_count,
                                             std::vector<Eigen::Triplet<double>>& entries) {
  entries.clear();
  auto add_block = [&](int a, int b, const Eigen::Matrix3d& block) {
    const int fa = free_index[static_cast<std::size_t>(a)];
    const int fb = free_index[static_cast<std::size_t>(b)];
    if (fa < 0 || fb < 0) return;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        if (3 * fb + c <= 3 * fa + r && block(r, c) != 0.0)
          entries.emplace_back(3 * fa + r, 3 * fb + c, block(r, c));
  };
  for (Eigen::Index v = 0; v < model.vertex_count(); ++v)
    add_block(static_cast<int>(v), static_cast<int>(v),
              (inertia.weight * model.masses_kg[v]) * Eigen::Matrix3d::Identity());
  for (const TetElement& e : model.tets) {
    Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
    const SignedSvd svd = signed_svd(deformation_gradient(e, p), rotation);
    const SingularValueEnergy strain =
        singular_value_energy(TetConstraintKind::strain, model.strain_range, e.strain_weight, svd.sigma);
    const SingularValueEnergy volume =
        singular_value_energy(TetConstraintKind::volume, model.volume_range, e.volume_weight, svd.sigma);
    const Eigen::Matrix<double, 9, 9> H_F = projected_hessian(svd, strain) + projected_hessian(svd, volume);
    // vec(F) = (Q^T kron I3) vec(X): H_X = (Q kron I3) H_F (Q^T kron I3).
    Eigen::Matrix<double, 12, 9> dF;
    dF.setZero();
    for (int k = 0; k < 4; ++k)
      for (int c = 0; c < 3; ++c)
        dF.block<3, 3>(3 * k, 3 * c) = e.Q(k, c) * Eigen::Matrix3d::Identity();
    const Eigen::Matrix<double, 12, 12> H = dF * H_F * dF.transpose();
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        add_block(e.vertices[static_cast<std::size_t>(a)], e.vertices[static_cast<std::size_t>(b)],
                  H.block<3, 3>(3 * a, 3 * b));
  }
  // Tet groups: as a tet's volume term, on the averaged F_g = X G.
  for (const TetGroup& g : model.tet_groups) {
    const Eigen::MatrixXd H = tet_group_hessian(model, g, p);
    for (std::size_t a = 0; a < g.vertices.size(); ++a)
      for (std::size_t b = 0; b < g.vertices.size(); ++b)
        add_block(g.vertices[a], g.vertices[b],
                  H.block<3, 3>(3 * static_cast<Eigen::Index>(a), 3 * static_cast<Eigen::Index>(b)));
  }
  // Surface elements: w (I - dP/dF) projected onto the PSD cone, through F = X Q.
  // Each element's Hessian on its own (the same bits for any number of threads).
  std::vector<SurfaceHessian> surface_hessians(model.surfaces.size());
  const auto surface_count = static_cast<std::ptrdiff_t>(model.surfaces.size());
#pragma omp parallel for schedule(static) if (surface_count > 256)
  for (std::ptrdiff_t i = 0; i < surface_count; ++i) {
    const SurfaceElement& e = model.surfaces[static_cast<std::size_t>(i)];
    surface_hessians[static_cast<std::size_t>(i)] = surface_hessian(e, surface_deformation(e, p));
  }
  for (std::size_t i = 0; i < model.surfaces.size(); ++i) {
    const SurfaceElement& e = model.surfaces[i];
    const SurfaceHessian& H_F = surface_hessians[i];
    for (int a = 0; a < e.count; ++a)
      for (int b = 0; b < e.count; ++b) {
        // vec(F) = (Q^T (x) I3) vec(X): the block of vertices a, b is sum_jk Q_aj Q_bk H_F(j, k).
        Eigen::Matrix3d block = Eigen::Matrix3d::Zero();
        for (int j = 0; j < e.columns; ++j)
          for (int k = 0; k < e.columns; ++k)
            block += (e.Q(a, j) * e.Q(b, k)) * H_F.block<3, 3>(3 * j, 3 * k);
        add_block(e.vertices[static_cast<std::size_t>(a)], e.vertices[static_cast<std::size_t>(b)], block);
      }
  }
  // Surface contacts: kc (c c^T) (x) (n n^T), c = (1, -b) over the vertex and the closest
  // point's triangle (Gauss-Newton: exact for a face contact, without the surface's curvature
  // at edges and corners).
  for (const SurfaceContact& contact : surface_contacts(model, p)) {
    const std::array<int, 4> vertices = {static_cast<int>(contact.vertex), contact.query.triangle[0],
                                         contact.query.triangle[1], contact.query.triangle[2]};
    Eigen::Vector4d c;
    c << 1.0, -contact.query.barycentric;
    const Eigen::Matrix3d nn =
        model.contact_stiffness_N_m * contact.query.normal * contact.query.normal.transpose();
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        if (c[a] != 0.0 && c[b] != 0.0)
          add_block(vertices[static_cast<std::size_t>(a)], vertices[static_cast<std::size_t>(b)],
                    c[a] * c[b] * nn);
  }
  // Enclosed volumes: w I on their vertices (Gauss-Newton, as for surface elements). A vertex
  // star's w is the bulk modulus's (huge as nu -> 1/2), where w I would make Newton crawl: its
  // block is w (I - dP/dX) without the set's curvature, w n n^T with n = grad V / |grad V|
  // (near the set w/2 dist^2 = K (V - V0)^2 / (2 V0), whose Gauss-Newton matrix this is), and
  // nothing while V / V0 lies strictly inside the range (the energy is 0 there).
  for (const EnclosedVolume& c : model.volumes) {
    if (!c.vertex_star) {
      for (int v : c.vertices)
        add_block(v, v, c.weight * Eigen::Matrix3d::Identity());
      continue;
    }
    const Eigen::MatrixX3d X = gather_vertices(c, p);
    const double ratio = enclosed_volume(c, X) / c.rest_volume_m3;
    if (ratio > c.range.min && ratio < c.range.max) continue;
    const Eigen::MatrixX3d G = enclosed_volume_gradient(c, X);
    const double norm2 = G.squaredNorm();
    if (!(norm2 > 0.0)) continue;
    const double scale = c.weight / norm2;
    for (std::size_t a = 0; a < c.vertices.size(); ++a)
      for (std::size_t b = 0; b < c.vertices.size(); ++b)
        add_block(c.vertices[a], c.vertices[b],
                  scale * G.row(static_cast<Eigen::Index>(a)).transpose() *
                      G.row(static_cast<Eigen::Index>(b)));
  }
  if (!model.obstacles.empty()) {
    for (Eigen::Index v = 0; v < model.vertex_count(); ++v)
      add_block(static_cast<int>(v), static_cast<int>(v),
                contact_hessian(model.obstacles, model.contact_stiffness_N_m, p.row(v).transpose()));
  }
  for (const PointConstraint& c : model.points) {
    for (int a = 0; a < c.count; ++a)
      for (int b = 0; b < c.count; ++b)
        add_block(c.vertices[static_cast<std::size_t>(a)], c.vertices[static_cast<std::size_t>(b)],
                  (c.stiffness_N_m * c.coefficients[a] * c.coefficients[b]) * Eigen::Matrix3d::Identity());
  }
  Eigen::SparseMatrix<double> H(3 * free_count, 3 * free_count);
  H.setFromTriplets(entries.begin(), entries.end());
  return H;
}

} // namespace

SolveReport newton_solve(const ElasticModel& model, const StepInertia& inertia, Eigen::MatrixX3d& p,
                         const StopCriteria& stop, bool record_energies, const IterationObserver& observer) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  double observer_seconds = 0.0;
  auto elapsed = [&] {
    return std::chrono::duration<double>(Clock::now() - start).count() - observer_seconds;
  };
  SolveReport report;
  report.solver = "newton";
  std::vector<int> free_index(static_cast<std::size_t>(model.vertex_count()), -1);
  std::vector<int> free_vertex;
  for (Eigen::Index v = 0; v < model.vertex_count(); ++v) {
    if (model.fixed.empty() || !model.fixed[static_cast<std::size_t>(v)]) {
      free_index[static_cast<std::size_t>(v)] = static_cast<int>(free_vertex.size());
      free_vertex.push_back(static_cast<int>(v));
    }
  }
  const auto nf = static_cast<Eigen::Index>(free_vertex.size());
  double energy = model_energy(model, inertia, p);
  report.initial_energy_J = energy;
  if (record_energies) {
    report.energies_J.push_back(energy);
    report.seconds.push_back(elapsed());
  }
  if (observer) {
    const auto before = Clock::now();
    observer(0, p, energy);
    observer_seconds += std::chrono::duration<double>(Clock::now() - before).count();
  }
  report.stopped_by = "max_iterations";
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> factor;
  // Simplicial: the supernodal factor's many small BLAS calls cost more than they save at the
  // sizes Newton is the reference for (the bar: 35 vs 57 ms per iteration, bench_sim).
  factor.setMode(Eigen::CholmodSimplicialLLt);
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixX3d gradient = model_gradient(model, inertia, p);
  const ResidualTest test(stop, free_gradient_norm(model, gradient));
  for (int iteration = 1; iteration <= stop.max_iterations; ++iteration) {
    throw_if_cancelled(); // an iteration takes milliseconds to a second: SIGINT stops here
    const double residual = free_gradient_norm(model, gradient);
    if (progress_detail_due()) progress_detail(solver_detail(iteration, residual));
    if (residual <= stop.gradient_norm_N) {
      report.stopped_by = "gradient";
      break;
    }
    if (stop.gradient_norm_N <= 0.0 && test.passes(residual)) {
      report.stopped_by = "residual";
      break;
    }
    Eigen::VectorXd g(3 * nf);
    for (Eigen::Index f = 0; f < nf; ++f)
      g.segment<3>(3 * f) = gradient.row(free_vertex[static_cast<std::size_t>(f)]).transpose();
    Eigen::SparseMatrix<double> H = assemble_hessian(model, inertia, p, free_index, nf, entries);
    // A PSD Hessian can be singular (a quasi-static model held only in part): shift until it factors.
    double shift = 0.0;
    Eigen::VectorXd direction;
    for (int attempt = 0; attempt < 30; ++attempt) {
      factor.setShift(shift);
      factor.compute(H);
      if (factor.info() == Eigen::Success) {
        direction = -factor.solve(g);
        if (direction.allFinite()) break;
      }
      shift = shift == 0.0 ? 1e-8 * H.diagonal().cwiseAbs().maxCoeff() : 10.0 * shift;
    }
    if (direction.size() != g.size()) throw std::runtime_error("newton: the Hessian could not be factored");
    const double slope = g.dot(direction);
    double step = 1.0;
    Eigen::MatrixX3d trial = p;
    double trial_energy = energy;
    bool accepted = false;
    Eigen::MatrixX3d trial_gradient;
    // Near the minimizer the decrease a step promises falls below the round-off of E itself and
    // Armijo's test becomes a coin toss: there, the full Newton step is taken when it lowers the
    // gradient norm instead (the merit function of Newton's method for the equation grad E = 0).
    const bool below_roundoff = -slope <= 1e-13 * std::abs(energy);
    if (below_roundoff) {
      for (Eigen::Index f = 0; f < nf; ++f)
        trial.row(free_vertex[static_cast<std::size_t>(f)]) =
            p.row(free_vertex[static_cast<std::size_t>(f)]) + direction.segment<3>(3 * f).transpose();
      trial_gradient = model_gradient(model, inertia, trial);
      if (free_gradient_norm(model, trial_gradient) < free_gradient_norm(model, gradient)) {
        trial_energy = model_energy(model, inertia, trial);
        accepted = true;
      } else {
        trial_gradient.resize(0, 3);
      }
    }
    for (int backtrack = 0; backtrack < 60 && !accepted; ++backtrack) {
      for (Eigen::Index f = 0; f < nf; ++f)
        trial.row(free_vertex[static_cast<std::size_t>(f)]) =
            p.row(free_vertex[static_cast<std::size_t>(f)]) + step * direction.segment<3>(3 * f).transpose();
      trial_energy = model_energy(model, inertia, trial);
      if (trial_energy <= energy + 1e-4 * step * slope) {
        accepted = true;
        break;
      }
      step *= 0.5;
    }
    report.iterations = iteration;
    if (!accepted) { // no decrease representable in double precision: converged
      report.stopped_by = "energy";
      break;
    }
    const double previous = energy;
    p = trial;
    energy = trial_energy;
    gradient = trial_gradient.rows() == p.rows() ? trial_gradient : model_gradient(model, inertia, p);
    if (record_energies) {
      report.energies_J.push_back(energy);
      report.seconds.push_back(elapsed());
    }
    if (observer) {
      const auto before = Clock::now();
      observer(iteration, p, energy);
      observer_seconds += std::chrono::duration<double>(Clock::now() - before).count();
    }
    // The energy criterion stops only a solve whose residual test passes too.
    if (stop.gradient_norm_N <= 0.0 &&
        previous - energy <= stop.relative_energy_decrease * std::abs(energy) &&
        test.passes(free_gradient_norm(model, gradient))) {
      report.stopped_by = "energy";
      break;
    }
  }
  report.final_energy_J = energy;
  report.residual_N = free_gradient_norm(model, gradient);
  judge_convergence(test, report);
  return report;
}

} // namespace phantasm
