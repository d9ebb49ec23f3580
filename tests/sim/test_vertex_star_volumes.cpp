// The bulk term on vertex stars (sim/vertex_star_volumes.hpp): its gradient, its energy against
// the per-tet term's, and the cantilever under gravity, which no longer stiffens as nu -> 1/2.

#include "anatomy/structured_mesh.hpp"
#include "sim/elastic_model.hpp"
#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/vertex_star_volumes.hpp"
#include "tests/support/finite_difference.hpp"

#include <gtest/gtest.h>

#include <array>
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
  if (formulation == VolumeFormulation::tet_group) { // structured_box: 5 consecutive tets per cell
    std::vector<std::vector<int>> cells(model.tets.size() / 5);
    for (std::size_t t = 0; t < model.tets.size(); ++t)
      cells[t / 5].push_back(static_cast<int>(t));
    move_bulk_to_tet_groups(model, cells);
  }
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
  const Eigen::MatrixX3d numeric = phantasm::testing::central_difference_gradient(
      [&](const Eigen::MatrixX3d& q) { return model_energy(model, none, q); }, p, 1e-7);
  EXPECT_TRUE(phantasm::testing::matches_finite_differences(model_gradient(model, none, p), numeric, 1e-6));
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

// (c) The cantilever (20 x 20 x 100 mm on 4 x 4 x 20 cells, one end held, gravity, density
// 1000 kg/m^3, Newton converged): with the per-tet bulk term the tip rises by 16 % from nu = 0.45
// to 0.499 (locking); with vertex stars by 11 % (figures in docs/deformation.md). Stars stiffen
// less, but this mesh still does not reach the 5 % aimed at: what is checked is that stars
// deflect more than tets at every nu and lose less as nu -> 1/2, and that both stay below beam
// theory (linear tets are stiff in bending at 5 cells across).
TEST(VertexStarVolumes, CantileverStiffensLessAsPoissonRatioTendsToOneHalf) {
  const double E = 2.5e5, length = 0.1, side = 0.02;
  const double q = 1000.0 * k_gravity * side * side, inertia = std::pow(side, 4) / 12.0;
  const double euler_bernoulli_mm = 1e3 * q * std::pow(length, 4) / (8.0 * E * inertia);
  std::array<double, 2> tet{}, star{};
  const std::array<double, 2> nus = {0.45, 0.499};
  for (std::size_t k = 0; k < 2; ++k) {
    tet[k] = newton_tip_mm(cantilever({20, 20, 100}, {4, 4, 20}, E, nus[k], VolumeFormulation::tet));
    star[k] = newton_tip_mm(cantilever({20, 20, 100}, {4, 4, 20}, E, nus[k], VolumeFormulation::vertex_star));
    std::printf("nu %.3f: tet %.2f mm, star %.2f mm, Euler-Bernoulli %.2f mm\n", nus[k], tet[k], star[k],
                euler_bernoulli_mm);
    EXPECT_GT(star[k], tet[k]);
    EXPECT_LT(star[k], euler_bernoulli_mm);
  }
  EXPECT_GT(star[1] / star[0], tet[1] / tet[0]);
  EXPECT_GT(star[1] / star[0], 0.88);
  EXPECT_LT(tet[1] / tet[0], 0.86);
}

// The local step projects the stars in parallel, each into its own slot, and sums their energy
// in star order: 1 and 2 threads give the same bytes.
TEST(VertexStarVolumes, LocalGlobalGivesIdenticalResultsOnOneAndTwoThreads) {
  const ElasticModel model = cantilever({20, 20, 60}, {2, 2, 6}, 2.5e5, 0.49, VolumeFormulation::vertex_star);
  StopCriteria stop;
  stop.max_iterations = 40;
  Eigen::MatrixX3d one = model.rest_positions_m, two = model.rest_positions_m;
  LocalGlobalSolver single(model, 0.0, 1);
  LocalGlobalSolver pair(model, 0.0, 2);
  const SolveReport a = single.solve(one, model.rest_positions_m, stop, true);
  const SolveReport b = pair.solve(two, model.rest_positions_m, stop, true);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.energies_J, b.energies_J);
  EXPECT_EQ(one, two);
}

// (d) One volume per hexahedral cell (its 5 tets): the gradient against central differences, the
// bulk energy of a uniform dilation the per-tet term's to second order, and the cantilever of (c)
// within 5 % between nu = 0.45 and 0.499 (13.08 and 12.84 mm: -1.8 %; -1.5 % on 6 x 6 x 30 cells,
// docs/deformation.md), where tets lose 16 % and stars 11 %.
TEST(TetGroupVolumes, GradientMatchesFiniteDifferences) {
  ElasticModel model = cantilever({20, 20, 40}, {2, 2, 4}, 3e4, 0.49, VolumeFormulation::tet_group);
  ASSERT_EQ(model.volumes.size(), std::size_t{16});
  std::mt19937 random(5);
  std::normal_distribution<double> normal(0.0, 1e-3);
  Eigen::MatrixX3d p = model.rest_positions_m;
  for (Eigen::Index v = 0; v < p.rows(); ++v)
    for (int c = 0; c < 3; ++c)
      p(v, c) += normal(random);
  const StepInertia none;
  const Eigen::MatrixX3d numeric = phantasm::testing::central_difference_gradient(
      [&](const Eigen::MatrixX3d& q) { return model_energy(model, none, q); }, p, 1e-7);
  EXPECT_TRUE(phantasm::testing::matches_finite_differences(model_gradient(model, none, p), numeric, 1e-6));
}

TEST(TetGroupVolumes, UniformDilationEnergyMatchesThePerTetTerm) {
  const double E = 3e4, nu = 0.45;
  ElasticModel tet = cantilever({20, 20, 40}, {2, 2, 4}, E, nu, VolumeFormulation::tet);
  ElasticModel group = cantilever({20, 20, 40}, {2, 2, 4}, E, nu, VolumeFormulation::tet_group);
  tet.external_forces_N.resize(0, 3);
  group.external_forces_N.resize(0, 3);
  for (double s : {1e-2, 1e-3, 1e-4}) {
    const Eigen::MatrixX3d p = (1.0 + s) * tet.rest_positions_m;
    ElasticModel strain_only = tet;
    for (TetElement& e : strain_only.tets)
      e.volume_weight = 0.0;
    const double strain = model_energy(strain_only, {}, p);
    EXPECT_NEAR((model_energy(group, {}, p) - strain) / (model_energy(tet, {}, p) - strain), 1.0, 5.0 * s)
        << s;
  }
}

TEST(TetGroupVolumes, ATetInTwoGroupsIsRefused) {
  ElasticModel model = cantilever({20, 20, 40}, {2, 2, 4}, 3e4, 0.45, VolumeFormulation::tet);
  EXPECT_THROW(move_bulk_to_tet_groups(model, {{0, 1}, {1, 2}}), std::invalid_argument);
  EXPECT_THROW(move_bulk_to_tet_groups(model, {{-1}}), std::invalid_argument);
}

TEST(TetGroupVolumes, CantileverDoesNotLockAsPoissonRatioTendsToOneHalf) {
  const double E = 2.5e5;
  const double at_045 =
      newton_tip_mm(cantilever({20, 20, 100}, {4, 4, 20}, E, 0.45, VolumeFormulation::tet_group));
  const double at_0499 =
      newton_tip_mm(cantilever({20, 20, 100}, {4, 4, 20}, E, 0.499, VolumeFormulation::tet_group));
  std::printf("cells: nu 0.45 %.3f mm, nu 0.499 %.3f mm\n", at_045, at_0499);
  EXPECT_GT(at_0499 / at_045, 0.95);
  EXPECT_LT(at_0499 / at_045, 1.0);
}
