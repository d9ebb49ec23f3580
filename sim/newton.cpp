#include "sim/newton.hpp"

#include "core/cancellation.hpp"
#include "core/progress.hpp"
#include "sim/hessian_factor.hpp"
#include "sim/vertex_star_volumes.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Sparse>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>

#ifdef _OPENMP
#include <omp.h>
#endif

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

/// Adds a 3 x 3 block of vertices a, b to the Hessian's triplets over the free coordinates
/// (lower triangle, nonzero entries; nothing for a fixed vertex).
struct BlockAdder {
  const std::vector<int>& free_index;
  std::vector<Eigen::Triplet<double>>& entries;

  void operator()(int a, int b, const Eigen::Matrix3d& block) const {
    const int fa = free_index[static_cast<std::size_t>(a)];
    const int fb = free_index[static_cast<std::size_t>(b)];
    if (fa < 0 || fb < 0) return;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        if (3 * fb + c <= 3 * fa + r && block(r, c) != 0.0)
          entries.emplace_back(3 * fa + r, 3 * fb + c, block(r, c));
  }
};

/// The tets' blocks (strain and volume terms, projected onto the PSD cone) and the tet groups'.
void add_tet_blocks(const ElasticModel& model, const Eigen::MatrixX3d& p, const BlockAdder& add_block) {
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
}

/// Surface elements: w (I - dP/dF) projected onto the PSD cone, through F = X Q.
void add_surface_blocks(const ElasticModel& model, const Eigen::MatrixX3d& p, const BlockAdder& add_block) {
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
}

/// Surface contacts: kc (c c^T) (x) (n n^T), c = (1, -b) over the vertex and the closest point's
/// triangle (Gauss-Newton: exact for a face contact, without the surface's curvature at edges and
/// corners).
void add_contact_blocks(const ElasticModel& model, const Eigen::MatrixX3d& p, const BlockAdder& add_block) {
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
}

/// Enclosed volumes: w I on their vertices (Gauss-Newton, as for surface elements). A vertex
/// star's w is the bulk modulus's (huge as nu -> 1/2), where w I would make Newton crawl: its
/// block is w (I - dP/dX) without the set's curvature, w n n^T with n = grad V / |grad V| (near
/// the set w/2 dist^2 = K (V - V0)^2 / (2 V0), whose Gauss-Newton matrix this is), and nothing
/// while V / V0 lies strictly inside the range (the energy is 0 there).
void add_volume_blocks(const ElasticModel& model, const Eigen::MatrixX3d& p, const BlockAdder& add_block) {
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
}

/// The PSD-projected Hessian over the free coordinates (3 per free vertex, lower triangle).
/// `entries` is the triplets' workspace, kept between iterations: its memory is reused rather
/// than faulted in anew each time (a swinging sheet's million entries cost more than the factor).
Eigen::SparseMatrix<double> assemble_hessian(const ElasticModel& model, const StepInertia& inertia,
                                             const Eigen::MatrixX3d& p, const std::vector<int>& free_index,
                                             Eigen::Index free_count,
                                             std::vector<Eigen::Triplet<double>>& entries) {
  entries.clear();
  const BlockAdder add_block{free_index, entries};
  for (Eigen::Index v = 0; v < model.vertex_count(); ++v)
    add_block(static_cast<int>(v), static_cast<int>(v),
              (inertia.weight * model.masses_kg[v]) * Eigen::Matrix3d::Identity());
  add_tet_blocks(model, p, add_block);
  add_surface_blocks(model, p, add_block);
  add_contact_blocks(model, p, add_block);
  add_volume_blocks(model, p, add_block);
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

/// The free rows: per vertex its row (-1 for fixed vertices), and per row its vertex.
struct FreeRows {
  std::vector<int> index, vertex;
  explicit FreeRows(const ElasticModel& model) : index(static_cast<std::size_t>(model.vertex_count()), -1) {
    for (Eigen::Index v = 0; v < model.vertex_count(); ++v) {
      if (model.fixed.empty() || !model.fixed[static_cast<std::size_t>(v)]) {
        index[static_cast<std::size_t>(v)] = static_cast<int>(vertex.size());
        vertex.push_back(static_cast<int>(v));
      }
    }
  }
  Eigen::Index count() const { return static_cast<Eigen::Index>(vertex.size()); }
  /// The free rows of a per-vertex gradient, flattened.
  Eigen::VectorXd gather(const Eigen::MatrixX3d& gradient) const {
    Eigen::VectorXd g(3 * count());
    for (Eigen::Index f = 0; f < count(); ++f)
      g.segment<3>(3 * f) = gradient.row(vertex[static_cast<std::size_t>(f)]).transpose();
    return g;
  }
};

/// The largest row of a flattened direction (m).
double largest_step(const Eigen::VectorXd& direction) {
  double largest = 0.0;
  for (Eigen::Index f = 0; 3 * f < direction.size(); ++f)
    largest = std::max(largest, direction.segment<3>(3 * f).norm());
  return largest;
}

/// The Newton direction -H^-1 g for an assembled H, factored into `factor` (shifted until it
/// factors where H is singular).
/// @throws std::runtime_error when no shift makes it factor
Eigen::VectorXd factored_direction(const Eigen::SparseMatrix<double>& H, const Eigen::VectorXd& g,
                                   HessianFactor& factor) {
  // A PSD Hessian can be singular (a quasi-static model held only in part): shift until it factors.
  double shift = 0.0;
  for (int attempt = 0; attempt < 30; ++attempt) {
    if (factor.factorize(H, shift)) {
      Eigen::VectorXd direction = -factor.solve(g);
      if (direction.allFinite()) return direction;
    }
    shift = shift == 0.0 ? 1e-8 * H.diagonal().cwiseAbs().maxCoeff() : 10.0 * shift;
  }
  throw std::runtime_error("newton: the Hessian could not be factored");
}

/// The Newton direction -H^-1 g at p (H the PSD-projected Hessian, into `H`, shifted until it
/// factors where it is singular).
/// @throws std::runtime_error when no shift makes it factor
Eigen::VectorXd newton_direction(const ElasticModel& model, const StepInertia& inertia,
                                 const Eigen::MatrixX3d& p, const FreeRows& free, const Eigen::VectorXd& g,
                                 HessianFactor& factor, std::vector<Eigen::Triplet<double>>& entries,
                                 Eigen::SparseMatrix<double>& H) {
  H = assemble_hessian(model, inertia, p, free.index, free.count(), entries);
  return factored_direction(H, g, factor);
}

/// Conjugate-gradient steps of the direction from the previous iterate's factor.
constexpr int k_preconditioned_steps = 20;

/// The Newton direction -H^-1 g by conjugate gradients preconditioned by `factor`, the factor of
/// the previous iterate's Hessian, or none when they do not reach a residual of 1e-10 |g| within
/// k_preconditioned_steps (H not positive definite along a search direction, or too far from
/// the factored matrix). Near an equilibrium a Newton step moves the vertices by a small fraction
/// of their displacement and the Hessian changes as little: the preconditioned matrix is nearly
/// the identity and a few steps, each a solve with the factor and a product with H, replace a
/// factorization (a population subject's body, 26 328 rows: a factorization took 1.0 s; the
/// stage's time with and without is in docs/performance.md, Deformation).
std::optional<Eigen::VectorXd> preconditioned_direction(const Eigen::SparseMatrix<double>& H,
                                                        const HessianFactor& factor,
                                                        const Eigen::VectorXd& g) {
  const auto H_times = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
    return H.selfadjointView<Eigen::Lower>() * v;
  };
  const double tolerance = 1e-10 * g.norm();
  Eigen::VectorXd x = -factor.solve(g);
  Eigen::VectorXd r = -g - H_times(x);
  Eigen::VectorXd z = factor.solve(r);
  Eigen::VectorXd d = z;
  double rz = r.dot(z);
  for (int step = 0; step < k_preconditioned_steps; ++step) {
    if (!x.allFinite() || !std::isfinite(rz)) return std::nullopt;
    if (r.norm() <= tolerance) return x;
    const Eigen::VectorXd Hd = H_times(d);
    const double curvature = d.dot(Hd);
    if (!(curvature > 0.0)) return std::nullopt;
    const double a = rz / curvature;
    x += a * d;
    r -= a * Hd;
    z = factor.solve(r);
    const double next = r.dot(z);
    d = z + (next / rz) * d;
    rz = next;
  }
  if (x.allFinite() && r.norm() <= tolerance) return x;
  return std::nullopt;
}

/// p with its free rows moved by t x the flattened d.
Eigen::MatrixX3d moved(const Eigen::MatrixX3d& p, const FreeRows& free, const Eigen::VectorXd& d, double t) {
  Eigen::MatrixX3d q = p;
  for (Eigen::Index f = 0; f < free.count(); ++f)
    q.row(free.vertex[static_cast<std::size_t>(f)]) += t * d.segment<3>(3 * f).transpose();
  return q;
}

/// Lanczos steps that look for a direction of negative curvature at an equilibrium.
constexpr int k_stability_iterations = 30;

/// Whether the equilibrium p is unstable (a saddle of E: a buckled bar held straight), and if so a
/// direction that lowers E (flattened, free rows). The projected Hessian H (factored in `factor`)
/// is the true one plus what the projection clamped (PSD), so the pencil's Rayleigh quotient
/// v.H_true v / v.H v is at most 1, and p is a saddle where its smallest value is negative. When
/// newton_solve stops without factoring at p (preconditioned_direction), H is the projected
/// Hessian where the last step started: positive definite all the same, so the sign of the
/// smallest value still tells a saddle, and the bound of 1 holds up to the last step's change of
/// the Hessian (the ratio moved in its fourth digit on a population subject). Lanczos
/// on H^-1 H_true, self-adjoint in the H inner product, finds that value: on the first subject of
/// the Colin population the power iteration on I - H^-1 H_true that this replaces was at 0.824 and
/// still falling when it gave up after 30 steps (each two gradients); Lanczos has the value,
/// 0.8218, to a thousandth after 15 steps and stops (the test below) after 13; on the fifth, 11
/// steps where the power iteration settled after 18; on the main job's head 9 where it took 14.
/// H_true v by forward differences of the gradient, the probe scaled to `length_m`; the basis is
/// orthogonalized in full (the differences are not exactly symmetric). Stable when the smallest
/// Ritz value is above 0.01, changed by at most a thousandth of itself over the last step (the
/// power iteration's test), and its residual bound (beta |last component of its vector|, within
/// which an eigenvalue of the pencil lies) within a tenth of it; a saddle when the Ritz vector's
/// own quotient is below -0.001. The residual alone does not say stable: a random probe is nearly
/// an eigenvector of a pencil whose values are mostly 1 (on a buckling bar its residual was 1e-3
/// after one step, with the negative value found at the next).
/// The smallest Ritz value, the steps and whether it settled (stable, a saddle, or an invariant
/// subspace) go into `report` (stability_ratio, stability_steps, stability_settled), which the
/// caller (leave_saddle) has cleared.
std::optional<Eigen::VectorXd> descent_direction(const ElasticModel& model, const StepInertia& inertia,
                                                 const Eigen::MatrixX3d& p, const FreeRows& free,
                                                 const Eigen::SparseMatrix<double>& H, HessianFactor& factor,
                                                 double length_m, SolveReport& report) {
  if (free.count() == 0 || !(length_m > 0.0)) return std::nullopt;
  const auto H_times = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
    return H.selfadjointView<Eigen::Lower>() * v;
  };
  // H_true v, for v scaled to the probe's length: a forward difference of the gradient from p's
  // own, a millionth of the probe as the step (one gradient a product where a central difference
  // of a thousandth took two; both within about 1e-6 of the product, the truncation error of the
  // one O(step), of the other O(step^2)).
  const Eigen::VectorXd g_here = free.gather(model_gradient(model, inertia, p));
  const auto true_times = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
    const double scale = length_m / largest_step(v);
    const double eps = 1e-6 * scale;
    return (free.gather(model_gradient(model, inertia, moved(p, free, v, eps))) - g_here) / eps;
  };
  std::mt19937 random(44);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::VectorXd q(3 * free.count());
  for (Eigen::Index i = 0; i < q.size(); ++i)
    q[i] = uniform(random);
  std::vector<Eigen::VectorXd> basis, H_basis; // H-orthonormal q_j and H q_j
  std::vector<double> alpha, beta;
  double previous = 2.0; // the last step's smallest Ritz value (the pencil's values are at most 1)
  for (int step = 0; step < k_stability_iterations; ++step) {
    Eigen::VectorXd Hq = H_times(q);
    const double norm2 = q.dot(Hq);
    if (!(norm2 > 0.0) || !std::isfinite(norm2)) return std::nullopt;
    q /= std::sqrt(norm2);
    Hq /= std::sqrt(norm2);
    const Eigen::VectorXd true_Hq = true_times(q);
    if (!true_Hq.allFinite()) return std::nullopt;
    alpha.push_back(q.dot(true_Hq));
    basis.push_back(q);
    H_basis.push_back(std::move(Hq));
    // The next basis vector: H^-1 H_true q, H-orthogonal to the basis (twice, in full).
    Eigen::VectorXd w = factor.solve(true_Hq);
    if (!w.allFinite()) return std::nullopt;
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t j = 0; j < basis.size(); ++j)
        w -= w.dot(H_basis[j]) * basis[j];
    const double next = std::sqrt(std::max(0.0, w.dot(H_times(w))));
    // The smallest Ritz value of the tridiagonal projection and its vector.
    const auto n = static_cast<Eigen::Index>(alpha.size());
    Eigen::MatrixXd T = Eigen::MatrixXd::Zero(n, n);
    for (Eigen::Index i = 0; i < n; ++i) {
      T(i, i) = alpha[static_cast<std::size_t>(i)];
      if (i + 1 < n) T(i, i + 1) = T(i + 1, i) = beta[static_cast<std::size_t>(i)];
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ritz(T);
    if (ritz.info() != Eigen::Success) return std::nullopt;
    const double theta = ritz.eigenvalues()[0];
    const double residual = next * std::abs(ritz.eigenvectors()(n - 1, 0));
    report.stability_ratio = theta;
    report.stability_steps = step + 1;
    if (theta < -1e-3) {
      Eigen::VectorXd y = Eigen::VectorXd::Zero(q.size());
      for (Eigen::Index i = 0; i < n; ++i)
        y += ritz.eigenvectors()(i, 0) * basis[static_cast<std::size_t>(i)];
      y *= length_m / largest_step(y);
      const double curvature = y.dot(true_times(y)), bound = y.dot(H_times(y));
      if (std::isfinite(curvature) && bound > 0.0 && curvature < -1e-3 * bound) {
        report.stability_settled = true;
        return y;
      }
    } else if (theta > 1e-2 && residual <= 0.1 * theta && previous - theta <= 1e-3 * theta) {
      report.stability_settled = true;
      return std::nullopt; // settled well above 0: stable
    }
    previous = theta;
    if (!(next > 1e-10)) { // an invariant subspace: its values are the pencil's
      report.stability_settled = true;
      return std::nullopt;
    }
    beta.push_back(next);
    q = w / next;
  }
  return std::nullopt;
}

/// Equilibria a solve leaves along a direction of negative curvature before it stops at one.
constexpr int k_saddle_escapes = 3;

/// The largest free vertex's displacement from rest (m).
double largest_displacement(const ElasticModel& model, const FreeRows& free, const Eigen::MatrixX3d& p) {
  double largest = 0.0;
  for (int v : free.vertex)
    largest = std::max(largest, (p.row(v) - model.rest_positions_m.row(v)).norm());
  return largest;
}

/// Newton iterations that finish a local/global solve whose distance test fails.
constexpr int k_finishing_newton_iterations = 200;

using Clock = std::chrono::steady_clock;

/// A solve's energies and times per iteration (when asked), and its observer, whose time is
/// left out of the solve's.
class IterationRecord {
public:
  IterationRecord(SolveReport& report, bool record_energies, const IterationObserver& observer)
      : m_report(report), m_record(record_energies), m_observer(observer) {}
  void add(int iteration, const Eigen::MatrixX3d& p, double energy) {
    if (m_record) {
      m_report.energies_J.push_back(energy);
      m_report.seconds.push_back(elapsed());
    }
    if (m_observer) {
      const auto before = Clock::now();
      m_observer(iteration, p, energy);
      m_observer_seconds += std::chrono::duration<double>(Clock::now() - before).count();
    }
  }

private:
  double elapsed() const {
    return std::chrono::duration<double>(Clock::now() - m_start).count() - m_observer_seconds;
  }
  SolveReport& m_report;
  bool m_record;
  const IterationObserver& m_observer;
  const Clock::time_point m_start = Clock::now();
  double m_observer_seconds = 0.0;
};

/// At an equilibrium that may be a saddle (a pushed bar held straight has a small residual and
/// step too): the point lower along the direction of negative curvature, and its energy, or none
/// when the equilibrium is stable (or enough saddles were left).
std::optional<std::pair<Eigen::MatrixX3d, double>>
leave_saddle(const ElasticModel& model, const StepInertia& inertia, const Eigen::MatrixX3d& p,
             const FreeRows& free, const Eigen::SparseMatrix<double>& H, HessianFactor& factor, double energy,
             SolveReport& report) {
  // Past the escapes no check runs: the report says none did (not the last saddle's).
  report.stability_ratio = std::numeric_limits<double>::quiet_NaN();
  report.stability_steps = 0;
  report.stability_settled = false;
  const std::optional<Eigen::VectorXd> down =
      report.saddles_left < k_saddle_escapes
          ? descent_direction(model, inertia, p, free, H, factor, 0.1 * report.largest_displacement_m, report)
          : std::nullopt;
  Eigen::MatrixX3d lower;
  double lower_energy = energy;
  for (double t = 1.0; down && t > 1e-3 && !(lower_energy < energy); t *= 0.5) {
    for (double sign : {1.0, -1.0}) {
      const Eigen::MatrixX3d q = moved(p, free, *down, sign * t);
      const double e = model_energy(model, inertia, q);
      if (e < energy && e < lower_energy) {
        lower = q;
        lower_energy = e;
      }
    }
  }
  if (!(lower_energy < energy)) return std::nullopt;
  return std::make_pair(lower, lower_energy);
}

/// Where a line search along a Newton direction ends: the point, its energy, and its gradient
/// when the search computed it (else empty).
struct LineSearch {
  bool accepted = false;
  Eigen::MatrixX3d trial, gradient;
  double energy = 0.0;
};

/// The backtracking line search (Armijo) along `direction` from p (energy `energy`, gradient
/// `gradient`, slope g . direction).
LineSearch line_search(const ElasticModel& model, const StepInertia& inertia, const Eigen::MatrixX3d& p,
                       const FreeRows& free, const Eigen::VectorXd& direction, double slope, double energy,
                       const Eigen::MatrixX3d& gradient) {
  LineSearch s;
  s.trial = p;
  s.energy = energy;
  double step = 1.0;
  auto place = [&](double t) {
    for (Eigen::Index f = 0; f < free.count(); ++f)
      s.trial.row(free.vertex[static_cast<std::size_t>(f)]) =
          p.row(free.vertex[static_cast<std::size_t>(f)]) + t * direction.segment<3>(3 * f).transpose();
  };
  // Near the minimizer the decrease a step promises falls below the round-off of E itself and
  // Armijo's test becomes a coin toss: there, the full Newton step is taken when it lowers the
  // gradient norm instead (the merit function of Newton's method for the equation grad E = 0).
  const bool below_roundoff = -slope <= 1e-13 * std::abs(energy);
  if (below_roundoff) {
    place(1.0);
    s.gradient = model_gradient(model, inertia, s.trial);
    if (free_gradient_norm(model, s.gradient) < free_gradient_norm(model, gradient)) {
      s.energy = model_energy(model, inertia, s.trial);
      s.accepted = true;
    } else {
      s.gradient.resize(0, 3);
    }
  }
  for (int backtrack = 0; backtrack < 60 && !s.accepted; ++backtrack) {
    place(step);
    s.energy = model_energy(model, inertia, s.trial);
    if (s.energy <= energy + 1e-4 * step * slope) {
      s.accepted = true;
      break;
    }
    step *= 0.5;
  }
  return s;
}

} // namespace

SolveReport newton_solve(const ElasticModel& model, const StepInertia& inertia, Eigen::MatrixX3d& p,
                         const StopCriteria& stop, bool record_energies, const IterationObserver& observer) {
  SolveReport report;
  IterationRecord record(report, record_energies, observer);
  report.solver = "newton";
  const FreeRows free(model);
  double energy = model_energy(model, inertia, p);
  report.initial_energy_J = energy;
  record.add(0, p, energy);
  report.stopped_by = "max_iterations";
  HessianFactor factor(3 * free.count());
  bool factored = false; // factor holds the factor of H
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::SparseMatrix<double> H, H_here;
  Eigen::MatrixX3d gradient = model_gradient(model, inertia, p);
  const ResidualTest test(stop, free_gradient_norm(model, gradient));
  const bool distance_test = stop.relative_distance > 0.0 && stop.gradient_norm_N <= 0.0;
  bool distance_known = false; // report.equilibrium_distance_m is the step at p
  for (int iteration = 1; iteration <= stop.max_iterations; ++iteration) {
    throw_if_cancelled(); // an iteration takes milliseconds to a second: SIGINT stops here
    const double residual = free_gradient_norm(model, gradient);
    if (progress_detail_due()) progress_detail(solver_detail(iteration, residual));
    if (residual <= stop.gradient_norm_N) {
      report.stopped_by = "gradient";
      break;
    }
    const bool residual_passes = stop.gradient_norm_N <= 0.0 && test.passes(residual);
    if (residual_passes && !distance_test) {
      report.stopped_by = "residual";
      break;
    }
    const Eigen::VectorXd g = free.gather(gradient);
    report.largest_displacement_m = largest_displacement(model, free, p);
    // The distance test: the step itself measures how far the equilibrium is. Where the residual
    // passes, the step from the last factor (preconditioned_direction) measures it first: when it
    // passes, the solve stops without a factorization, and the stability check below works with
    // the last factor and its matrix (H, the Hessian where the last step started), a pencil as
    // valid as the current Hessian's. Otherwise the Hessian here is factored and the step is the
    // one a factorization gives.
    std::optional<Eigen::VectorXd> measured;
    if (residual_passes && factored) {
      H_here = assemble_hessian(model, inertia, p, free.index, free.count(), entries);
      measured = preconditioned_direction(H_here, factor, g);
      if (measured && !distance_passes(stop, largest_step(*measured), report.largest_displacement_m))
        measured.reset();
      if (!measured) H.swap(H_here);
    }
    const Eigen::VectorXd direction = measured ? *measured
                                      : residual_passes && factored
                                          ? factored_direction(H, g, factor)
                                          : newton_direction(model, inertia, p, free, g, factor, entries, H);
    factored = true;
    report.equilibrium_distance_m = largest_step(direction);
    distance_known = true;
    if (residual_passes &&
        distance_passes(stop, report.equilibrium_distance_m, report.largest_displacement_m)) {
      // An equilibrium, but a stable one? A saddle is left along the direction that lowers the energy.
      const auto lower = leave_saddle(model, inertia, p, free, H, factor, energy, report);
      if (!lower) {
        report.stopped_by = "residual";
        break;
      }
      report.saddle_energies_J.push_back(energy);
      ++report.saddles_left;
      // The check's figures were the saddle's: the point the solve stops at is checked anew.
      report.stability_ratio = std::numeric_limits<double>::quiet_NaN();
      report.stability_steps = 0;
      report.stability_settled = false;
      p = lower->first;
      energy = lower->second;
      gradient = model_gradient(model, inertia, p);
      distance_known = false;
      report.iterations = iteration;
      continue;
    }
    const LineSearch search =
        line_search(model, inertia, p, free, direction, g.dot(direction), energy, gradient);
    report.iterations = iteration;
    if (!search.accepted) { // no decrease representable in double precision: converged
      report.stopped_by = "energy";
      break;
    }
    const double previous = energy;
    p = search.trial;
    energy = search.energy;
    distance_known = false;
    gradient = search.gradient.rows() == p.rows() ? search.gradient : model_gradient(model, inertia, p);
    record.add(iteration, p, energy);
    // The energy criterion stops only a solve whose residual test passes too (and, with the
    // distance test, never: the next iteration's step decides).
    if (stop.gradient_norm_N <= 0.0 && !distance_test &&
        previous - energy <= stop.relative_energy_decrease * std::abs(energy) &&
        test.passes(free_gradient_norm(model, gradient))) {
      report.stopped_by = "energy";
      break;
    }
  }
  report.final_energy_J = energy;
  report.residual_N = free_gradient_norm(model, gradient);
  if (distance_test && !distance_known) { // stopped by the limit: how far it still is
    report.equilibrium_distance_m =
        largest_step(newton_direction(model, inertia, p, free, free.gather(gradient), factor, entries, H));
    report.largest_displacement_m = largest_displacement(model, free, p);
  }
  judge_convergence(test, report, distance_test ? stop : StopCriteria{});
  return report;
}

double newton_step_length(const ElasticModel& model, const StepInertia& inertia, const Eigen::MatrixX3d& p) {
  const FreeRows free(model);
  HessianFactor factor(3 * free.count());
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::SparseMatrix<double> H;
  const Eigen::VectorXd g = free.gather(model_gradient(model, inertia, p));
  return free.count() > 0 ? largest_step(newton_direction(model, inertia, p, free, g, factor, entries, H))
                          : 0.0;
}

void finish_solve(const ElasticModel& model, const StepInertia& inertia, Eigen::MatrixX3d& p,
                  const StopCriteria& stop, const ResidualTest& test, bool newton_steps,
                  SolveReport& report) {
  judge_convergence(test, report);
  if (stop.relative_distance <= 0.0) return;
  if (newton_steps && report.converged) {
    StopCriteria finish = stop;
    finish.force_scale_N = test.scale_N;
    finish.max_iterations = std::min(stop.max_iterations, k_finishing_newton_iterations);
    const SolveReport newton = newton_solve(model, inertia, p, finish);
    report.newton_iterations = newton.iterations;
    report.iterations += newton.iterations;
    report.saddles_left = newton.saddles_left;
    report.saddle_energies_J = newton.saddle_energies_J;
    report.stability_ratio = newton.stability_ratio;
    report.stability_steps = newton.stability_steps;
    report.stability_settled = newton.stability_settled;
    if (newton.iterations > 0) {
      report.stopped_by = "newton " + newton.stopped_by;
      report.final_energy_J = newton.final_energy_J;
      report.residual_N = newton.residual_N;
      // the contacts where Newton left the vertices
      report.contacts = static_cast<int>(surface_contacts(model, p).size());
      for (Eigen::Index v = 0; v < p.rows() && !model.obstacles.empty(); ++v) {
        if (!model.fixed.empty() && model.fixed[static_cast<std::size_t>(v)]) continue;
        for (const Obstacle& o : model.obstacles) {
          if (o.signed_distance(p.row(v).transpose()) < 0.0) {
            ++report.contacts;
            break;
          }
        }
      }
    }
    report.equilibrium_distance_m = newton.equilibrium_distance_m;
    report.largest_displacement_m = newton.largest_displacement_m;
  } else {
    report.equilibrium_distance_m = newton_step_length(model, inertia, p);
    report.largest_displacement_m = largest_displacement(model, FreeRows(model), p);
  }
  judge_convergence(test, report, stop);
}

} // namespace phantasm
