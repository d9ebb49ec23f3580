// The local/global solver proper: the local step (projections, energy), the right-hand side of
// the global step, and the solve loop (Anderson acceleration, then L-BFGS with the global matrix
// as its initial Hessian).
#include "sim/local_global.hpp"

#include "core/cancellation.hpp"
#include "core/progress.hpp"
#include "sim/anderson_acceleration.hpp"
#include "sim/local_global_impl.hpp"
#include "sim/newton.hpp"
#include "sim/quasi_newton_history.hpp"
#include "sim/tet_projection_batch.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <optional>

namespace phantasm {

double LocalGlobalSolver::Impl::local_step(const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& target) {
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
  // Tet groups: the volume projection of the averaged F (a small 3x3 problem each).
  const auto group_count = static_cast<std::ptrdiff_t>(model.tet_groups.size());
#pragma omp parallel for num_threads(threads) schedule(dynamic, 64) if (group_count > 0)
  for (std::ptrdiff_t c = 0; c < group_count; ++c) {
    const auto i = static_cast<std::size_t>(c);
    const TetGroup& g = model.tet_groups[i];
    const SignedSvd svd =
        signed_svd(group_deformation_gradient(g, p), group_rotations[i], group_eigenvectors[i]);
    const Eigen::Vector3d closest = project_volume(svd.sigma, model.volume_range);
    group_projections[i] = g.weight * (svd.V * closest.asDiagonal() * svd.U.transpose());
    group_energies[i] = 0.5 * g.weight * (svd.sigma - closest).squaredNorm();
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
  for (double e : group_energies)
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
  if (!model.obstacles.empty() || !model.contact_pairs.empty()) energy += contacts->find(p, threads);
  return energy;
}

void LocalGlobalSolver::Impl::gather_rhs(const Eigen::MatrixX3d& target) {
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
    for (int i = group_offsets[v]; i < group_offsets[v + 1]; ++i) {
      const auto g = static_cast<std::size_t>(group_entries[2 * static_cast<std::size_t>(i)]);
      const int corner = group_entries[2 * static_cast<std::size_t>(i) + 1];
      r.noalias() += model.tet_groups[g].G.row(corner) * group_projections[g];
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
    contacts->add_obstacle_rhs(f, r);
    rhs.row(f) = r - coupling_rhs.row(f);
  }
  contacts->add_surface_rhs(rhs);
}

double LocalGlobalSolver::Impl::begin_solve(const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& target,
                                            SolveReport& report, bool record_energies,
                                            const IterationObserver& observer) {
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

void LocalGlobalSolver::Impl::finish_report(const Eigen::MatrixX3d& x_free, const Eigen::MatrixX3d& target,
                                            SolveReport& report) {
  contacts->update_factor(*factor);
  gather_rhs(target);
  const Eigen::MatrixX3d K_x = apply_matrix(x_free);
  report.residual_N = x_free.rows() > 0 ? (K_x - rhs).rowwise().norm().maxCoeff() : 0.0;
  report.contacts = contacts->count();
  report.rank_updates = factor->rank_changes();
}

LocalGlobalSolver::LocalGlobalSolver(const ElasticModel& model, double inertia_weight, int threads,
                                     int anderson_history, int history)
    : m(std::make_unique<Impl>(model, inertia_weight, threads > 0 ? threads : omp_get_max_threads())) {
  m->anderson_history = std::max(0, anderson_history);
  m->history = std::max(0, history);
  m->rotations.assign(model.tets.size(), Eigen::Quaterniond::Identity());
  m->eigenvectors.assign(model.tets.size(), Eigen::Matrix3d::Identity());
  m->projections.assign(model.tets.size(), Eigen::Matrix3d::Zero());
  m->tet_energies.assign(model.tets.size(), 0.0);
  m->group_rotations.assign(model.tet_groups.size(), Eigen::Quaterniond::Identity());
  m->group_eigenvectors.assign(model.tet_groups.size(), Eigen::Quaterniond::Identity());
  m->group_projections.assign(model.tet_groups.size(), Eigen::Matrix3d::Zero());
  m->group_energies.assign(model.tet_groups.size(), 0.0);
  m->surface_projections.assign(model.surfaces.size(), SurfaceMatrix::Zero());
  m->surface_energies.assign(model.surfaces.size(), 0.0);
  m->volume_projections.resize(model.volumes.size());
  m->volume_energies.assign(model.volumes.size(), 0.0);
  m->build_adjacency();
  m->assemble_and_factor();
}

LocalGlobalSolver::~LocalGlobalSolver() = default;

double LocalGlobalSolver::energy(const Eigen::MatrixX3d& p, const Eigen::MatrixX3d& inertial_target) {
  return m->local_step(p, inertial_target);
}

namespace {

/// The sum of the entrywise products of a and b (the dot product of the flattened points).
double dot(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  return a.cwiseProduct(b).sum();
}

/// Iterations of local/global with Anderson acceleration before L-BFGS takes over.
constexpr int k_anderson_iterations = 100;
/// Energies the line search evaluates before it falls back to the plain step.
constexpr int k_line_search_evaluations = 8;
/// The line search's sufficient decrease: E(x + t d) <= E(x) + k_armijo t grad . d.
constexpr double k_armijo = 1e-4;

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

} // namespace

bool LocalGlobalSolver::Impl::quasi_newton_step(sim_detail::QuasiNewtonHistory& pairs,
                                                const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& gradient,
                                                double previous, const Eigen::MatrixX3d& target,
                                                Eigen::MatrixX3d& p, Eigen::MatrixX3d& trial, double& energy,
                                                SolveReport& report) {
  // The direction: the two-loop recursion around gamma K^-1.
  auto start = Clock::now();
  direction = -gradient;
  pairs.first_loop(direction);
  factor->solve(pairs.newest_y(), scaled, threads);
  factor->solve(direction, solution, threads);
  report.global_seconds += seconds_since(start);
  start = Clock::now();
  direction = (pairs.newest_sy() / dot(pairs.newest_y(), scaled)) * solution;
  pairs.second_loop(direction);
  const double slope = dot(gradient, direction);
  double step = 1.0;
  bool accepted = false;
  for (int evaluation = 0; slope < 0.0 && evaluation < k_line_search_evaluations && !accepted; ++evaluation) {
    trial = x + step * direction;
    set_free_positions(trial, p);
    const double trial_energy = local_step(p, target);
    if (trial_energy <= previous + k_armijo * step * slope) {
      energy = trial_energy;
      accepted = true;
    } else {
      // The minimum of the parabola through E(x), the slope there and E(trial), within a
      // tenth and a half of the step.
      const double curvature = trial_energy - previous - step * slope;
      const double next = curvature > 0.0 ? -0.5 * slope * step * step / curvature : 0.5 * step;
      step = std::clamp(next, 0.1 * step, 0.5 * step);
    }
  }
  report.local_seconds += seconds_since(start);
  return accepted;
}

double LocalGlobalSolver::Impl::plain_step(sim_detail::AndersonAcceleration& anderson, bool accelerate,
                                           const Eigen::MatrixX3d& x, double previous,
                                           const Eigen::MatrixX3d& target, Eigen::MatrixX3d& p,
                                           Eigen::MatrixX3d& trial, SolveReport& report) {
  auto start = Clock::now();
  factor->solve(rhs, solution, threads);
  report.global_seconds += seconds_since(start);
  start = Clock::now();
  trial = solution;
  double energy = 0.0;
  bool accepted = false;
  // Anderson's proposal (phase 1), kept when it lowers the energy.
  const bool tried = accelerate && anderson.propose(solution, x, candidate);
  if (tried) {
    set_free_positions(candidate, p);
    const double candidate_energy = local_step(p, target);
    if (candidate_energy < previous) {
      trial = candidate;
      energy = candidate_energy;
      accepted = true;
    }
  }
  if (!accepted) {
    set_free_positions(trial, p);
    energy = local_step(p, target);
    if (tried) anderson.restart(); // rejected: restart the history from this point
  }
  report.local_seconds += seconds_since(start);
  return energy;
}

SolveReport LocalGlobalSolver::solve(Eigen::MatrixX3d& p, const Eigen::MatrixX3d& target,
                                     const StopCriteria& stop, bool record_energies,
                                     const IterationObserver& observer) {
  SolveReport report;
  report.solver = "local_global";
  double energy = m->begin_solve(p, target, report, record_energies, observer);
  const auto nf = static_cast<Eigen::Index>(m->free_vertex.size());
  // Two phases on the same energy, each step lowering it:
  // 1. Local/global with Anderson acceleration of the fixed-point map x -> G(x) (global step
  //    after local step), with Peng et al. (2018)'s energy safeguard: the accelerated point is
  //    kept only when its energy is below the current one; otherwise the plain step, which never
  //    raises the energy, is taken and the history restarts. Most solves converge here in tens
  //    of iterations.
  // 2. After k_anderson_iterations (never with contacts, whose factor and right-hand side change
  //    as contacts come and go), L-BFGS (Liu, Bouaziz and Kavan 2017) with the global matrix K as
  //    the initial Hessian: the gradient is K x - b(x) (b from the local step at x), the initial
  //    inverse Hessian gamma K^-1 with gamma = s.y / y.K^-1 y of the newest pair (Nocedal and
  //    Wright's scaling), and a backtracking line search (Armijo) on the energy that falls back
  //    to the plain step. K holds every constraint in all nine directions of its F with its
  //    weight, so the plain step crawls where the volume weight dwarfs the strain weight (nu ->
  //    1/2: docs/deformation.md); the pairs learn the curvature K gets wrong.
  const bool contacts_possible = !m->model.obstacles.empty() || !m->model.contact_pairs.empty();
  sim_detail::AndersonAcceleration anderson(nf, m->anderson_history);
  sim_detail::QuasiNewtonHistory history(m->history);
  Eigen::MatrixX3d x = m->free_positions(p);
  Eigen::MatrixX3d gradient, trial;
  std::optional<ResidualTest> test;
  for (int iteration = 1;; ++iteration) {
    throw_if_cancelled(); // an iteration takes milliseconds to a second: SIGINT stops here
    const auto start = Clock::now();
    const int contact_changes = m->contacts->update_factor(*m->factor); // (timed with the local step:
    report.contact_changes += contact_changes;                          // the right-hand side depends on it)
    m->gather_rhs(target);
    // The equilibrium residual at x (K x - b(x), b from the projections the last local step
    // made there): the energy's gradient, and the residual test before every step and after
    // the last.
    if (nf > 0)
      gradient = m->apply_matrix(x) - m->rhs;
    else
      gradient.resize(0, 3);
    const double residual = nf > 0 ? gradient.rowwise().norm().maxCoeff() : 0.0;
    report.residuals_N.push_back(residual);
    const bool quasi_newton = !contacts_possible && m->history > 0 && iteration > k_anderson_iterations;
    if (quasi_newton) history.add(x, gradient);
    report.local_seconds += seconds_since(start);
    if (!test) test.emplace(stop, residual);
    if (progress_detail_due()) progress_detail(solver_detail(iteration, residual));
    if (test->passes(residual)) {
      report.stopped_by = "residual";
      break;
    }
    if (iteration > stop.max_iterations) break;
    const double previous = energy;
    bool accepted = false;
    if (quasi_newton && history.size() > 0) {
      accepted = m->quasi_newton_step(history, x, gradient, previous, target, p, trial, energy, report);
      if (!accepted) history.clear(); // the plain step below, from a fresh history
    }
    if (!accepted) energy = m->plain_step(anderson, !quasi_newton, x, previous, target, p, trial, report);
    const double change = nf > 0 ? (trial - x).rowwise().norm().maxCoeff() : 0.0;
    x = trial;
    report.iterations = iteration;
    if (record_energies) {
      report.energies_J.push_back(energy);
      report.seconds.push_back(report.local_seconds + report.global_seconds);
    }
    if (observer) observer(iteration, p, energy);
    // A step that no longer moves anything: nothing more to gain (the residual test judges
    // whether that point is the equilibrium). The step criteria of the scene otherwise stop
    // nothing the residual test does not: a small step is not a small distance to equilibrium.
    if (change == 0.0) {
      report.stopped_by = "position";
      break;
    }
  }
  report.final_energy_J = energy;
  m->finish_report(m->free_positions(p), target, report);
  finish_solve(m->model, StepInertia{m->alpha, target}, p, stop, *test, true, report);
  return report;
}

} // namespace phantasm
