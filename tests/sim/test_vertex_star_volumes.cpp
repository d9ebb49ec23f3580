// The bulk term on vertex stars (sim/vertex_star_volumes.hpp): its gradient, its energy against
// the per-tet term's, and the cantilever under gravity, which no longer stiffens as nu -> 1/2.

#include "anatomy/structured_mesh.hpp"
#include "sim/elastic_model.hpp"
#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/vertex_star_volumes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

using namespace phantasm;

namespace {

constexpr double k_gravity = 9.81;

/// A cantilever of size_mm (long axis z) meshed with `cells`, its z-min face held, gravity
/// along -y as external forces (quasi-static), E in Pa.
ElasticModel cantilever(const Eigen::Vector3d& size_mm, const Eigen::Vector3i& cells, double E, double nu,
                        VolumeFormulation formulation) {
  const TetMesh mesh = structured_box(size_mm, cells, Eigen::Matrix3d::Identity(), 0.5 * size_mm);
  ElasticModel model;
  add_body(model, 1e-3 * mesh.vertices, mesh.tets, lame_parameters(E, nu), 1000.0);
  if (formulation == VolumeFormulation::vertex_star) move_bulk_to_vertex_stars(model);
  model.external_forces_N = Eigen::MatrixX3d::Zero(model.vertex_count(), 3);
  model.external_forces_N.col(1) = -k_gravity * model.masses_kg;
  for (Eigen::Index v = 0; v < model.vertex_count(); ++v)
    model.fixed[static_cast<std::size_t>(v)] = model.rest_positions_m(v, 2) < 1e-9 ? 1 : 0;
  return model;
}

/// The mean downward deflection of the free end's face (z max), mm.
double tip_deflection_mm(const ElasticModel& model, const Eigen::MatrixX3d& p) {
  const double length = model.rest_positions_m.col(2).maxCoeff();
  double sum = 0.0;
  int count = 0;
  for (Eigen::Index v = 0; v < p.rows(); ++v) {
    if (model.rest_positions_m(v, 2) > length - 1e-9) {
      sum += model.rest_positions_m(v, 1) - p(v, 1);
      ++count;
    }
  }
  return 1e3 * sum / count;
}

double newton_tip_mm(const ElasticModel& model) {
  Eigen::MatrixX3d p = model.rest_positions_m;
  StopCriteria stop;
  stop.max_iterations = 200;
  stop.gradient_norm_N = 1e-9;
  const SolveReport report = newton_solve(model, StepInertia{}, p, stop);
  EXPECT_EQ(report.stopped_by, "gradient")
      << report.iterations << " iterations, residual " << report.residual_N;
  return tip_deflection_mm(model, p);
}

} // namespace

// (a) The model's gradient with stars (their energy w/2 |X - P(X)|^2) matches central
// differences of its energy at a deformed state.
TEST(VertexStarVolumes, GradientMatchesFiniteDifferences) {
  ElasticModel model = cantilever({20, 20, 40}, {2, 2, 4}, 3e4, 0.49, VolumeFormulation::vertex_star);
  ASSERT_EQ(static_cast<Eigen::Index>(model.volumes.size()), model.vertex_count());
  std::mt19937 random(5);
  std::normal_distribution<double> normal(0.0, 1e-3);
  Eigen::MatrixX3d p = model.rest_positions_m;
  for (Eigen::Index v = 0; v < p.rows(); ++v)
    for (int c = 0; c < 3; ++c)
      p(v, c) += normal(random);
  const StepInertia none;
  const Eigen::MatrixX3d g = model_gradient(model, none, p);
  const double h = 1e-7;
  double worst = 0.0;
  for (Eigen::Index v = 0; v < p.rows(); v += 3) {
    for (int c = 0; c < 3; ++c) {
      Eigen::MatrixX3d plus = p, minus = p;
      plus(v, c) += h;
      minus(v, c) -= h;
      const double fd = (model_energy(model, none, plus) - model_energy(model, none, minus)) / (2.0 * h);
      worst = std::max(worst, std::abs(fd - g(v, c)));
    }
  }
  EXPECT_LT(worst, 1e-6 * g.cwiseAbs().maxCoeff());
}

// (b) Under a uniform dilation (1 + s) the stars' bulk energy equals the per-tet term's to
// second order in s (both lambda theta^2 V / 2 with theta = 3 s): the ratio tends to 1 as s -> 0.
TEST(VertexStarVolumes, UniformDilationEnergyMatchesThePerTetTerm) {
  const double E = 3e4, nu = 0.45;
  ElasticModel tet = cantilever({20, 20, 40}, {2, 2, 4}, E, nu, VolumeFormulation::tet);
  ElasticModel star = cantilever({20, 20, 40}, {2, 2, 4}, E, nu, VolumeFormulation::vertex_star);
  tet.external_forces_N.resize(0, 3);
  star.external_forces_N.resize(0, 3);
  const double lambda = lame_parameters(E, nu).lambda;
  const double volume = 20e-3 * 20e-3 * 40e-3;
  for (double s : {1e-2, 1e-3, 1e-4}) {
    const Eigen::MatrixX3d p = (1.0 + s) * tet.rest_positions_m;
    // Strain energy alike in both: subtract it by zeroing the tets' volume weights.
    ElasticModel strain_only = tet;
    for (TetElement& e : strain_only.tets)
      e.volume_weight = 0.0;
    const double strain = model_energy(strain_only, {}, p);
    const double bulk_tet = model_energy(tet, {}, p) - strain;
    const double bulk_star = model_energy(star, {}, p) - strain;
    const double linear = 0.5 * lambda * 9.0 * s * s * volume;
    EXPECT_NEAR(bulk_star / bulk_tet, 1.0, 5.0 * s) << s;
    EXPECT_NEAR(bulk_star / linear, 1.0, 5.0 * s) << s;
  }
}

// (c) The cantilever (20 x 20 x 100 mm, one end held, gravity, density 1000 kg/m^3): with the
// per-tet bulk term the tip rises as nu -> 1/2 (locking); with vertex stars the deflection at
// nu = 0.499 stays within 5 % of nu = 0.45's, near beam theory and a refined mesh.
TEST(VertexStarVolumes, CantileverDoesNotLockAsPoissonRatioTendsToOneHalf) {
  const double E = 2.5e5, length = 0.1, side = 0.02;
  const double q = 1000.0 * k_gravity * side * side, inertia = std::pow(side, 4) / 12.0;
  const double euler_bernoulli_mm = 1e3 * q * std::pow(length, 4) / (8.0 * E * inertia);
  std::printf("Euler-Bernoulli %.2f mm\n", euler_bernoulli_mm);
  double star_045 = 0.0;
  for (double nu : {0.45, 0.49, 0.499}) {
    // Timoshenko: + q L^2 / (2 kappa G A) with kappa = 10 (1 + nu) / (12 + 11 nu) (square section).
    const double G = E / (2.0 * (1.0 + nu)), kappa = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu);
    const double timoshenko_mm =
        euler_bernoulli_mm + 1e3 * q * length * length / (2.0 * kappa * G * side * side);
    const double tet = newton_tip_mm(cantilever({20, 20, 100}, {4, 4, 20}, E, nu, VolumeFormulation::tet));
    const double star =
        newton_tip_mm(cantilever({20, 20, 100}, {4, 4, 20}, E, nu, VolumeFormulation::vertex_star));
    const double fine =
        newton_tip_mm(cantilever({20, 20, 100}, {6, 6, 30}, E, nu, VolumeFormulation::vertex_star));
    std::printf("nu %.3f: tet %.2f mm, star %.2f mm, star refined %.2f mm, Timoshenko %.2f mm\n", nu, tet,
                star, fine, timoshenko_mm);
    if (nu == 0.45) star_045 = star;
    EXPECT_NEAR(star / star_045, 1.0, 0.05) << nu;
    EXPECT_NEAR(star / timoshenko_mm, 1.0, 0.1) << nu;
    EXPECT_NEAR(star / fine, 1.0, 0.1) << nu;
  }
}
