// The bulk term on vertex stars and on groups of tets (sim/vertex_star_volumes.hpp): gradients
// and Hessians against finite differences, energies against the per-tet term's, the grouping of
// unstructured meshes, and the cantilever under gravity as nu -> 1/2 (sim/cantilever.hpp):
// groups do not lock, and local/global reaches Newton's answer with them.

#include "anatomy/implicit_shape.hpp"
#include "anatomy/structured_mesh.hpp"
#include "anatomy/tet_mesh.hpp"
#include "sim/cantilever.hpp"
#include "sim/elastic_model.hpp"
#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/vertex_star_volumes.hpp"
#include "tests/support/finite_difference.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>

using namespace phantasm;

namespace {

/// The cantilever of sim/cantilever.hpp: size_mm on `cells` structured cells, E in Pa.
ElasticModel cantilever(const Eigen::Vector3d& size_mm, const Eigen::Vector3i& cells, double E, double nu,
                        VolumeFormulation formulation) {
  CantileverSettings s;
  s.size_mm = size_mm;
  s.cells = cells;
  s.youngs_modulus_Pa = E;
  s.poisson_ratio = nu;
  s.volume = formulation;
  return cantilever_model(s);
}

/// The rest positions moved by N(0, 1 mm) per coordinate (seeded).
Eigen::MatrixX3d perturbed(const ElasticModel& model) {
  std::mt19937 random(5);
  std::normal_distribution<double> normal(0.0, 1e-3);
  Eigen::MatrixX3d p = model.rest_positions_m;
  for (Eigen::Index v = 0; v < p.rows(); ++v)
    for (int c = 0; c < 3; ++c)
      p(v, c) += normal(random);
  return p;
}

::testing::AssertionResult gradient_matches(const ElasticModel& model, const Eigen::MatrixX3d& p) {
  const StepInertia none;
  const Eigen::MatrixX3d numeric = phantasm::testing::central_difference_gradient(
      [&](const Eigen::MatrixX3d& q) { return model_energy(model, none, q); }, p, 1e-7);
  return phantasm::testing::matches_finite_differences(model_gradient(model, none, p), numeric, 1e-6);
}

double newton_tip_mm(const ElasticModel& model) {
  Eigen::MatrixX3d p = model.rest_positions_m;
  StopCriteria stop;
  stop.max_iterations = 200;
  stop.gradient_norm_N = 1e-9;
  const SolveReport report = newton_solve(model, StepInertia{}, p, stop);
  EXPECT_EQ(report.stopped_by, "gradient")
      << report.iterations << " iterations, residual " << report.residual_N;
  return cantilever_tip_deflection_mm(model, p);
}

/// Bulk energy of a model at p: its energy minus that of its tets' strain terms alone.
double bulk_energy(const ElasticModel& model, const Eigen::MatrixX3d& p) {
  ElasticModel strain_only = model;
  for (TetElement& e : strain_only.tets)
    e.volume_weight = 0.0;
  strain_only.tet_groups.clear();
  strain_only.volumes.clear();
  return model_energy(model, {}, p) - model_energy(strain_only, {}, p);
}

} // namespace

// (a) The model's gradient with stars (their energy w/2 |X - P(X)|^2) matches central
// differences of its energy at a deformed state.
TEST(VertexStarVolumes, GradientMatchesFiniteDifferences) {
  const ElasticModel model = cantilever({20, 20, 40}, {2, 2, 4}, 3e4, 0.49, VolumeFormulation::vertex_star);
  ASSERT_EQ(static_cast<Eigen::Index>(model.volumes.size()), model.vertex_count());
  EXPECT_TRUE(gradient_matches(model, perturbed(model)));
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
    const double bulk_tet = bulk_energy(tet, p);
    const double bulk_star = bulk_energy(star, p);
    const double linear = 0.5 * lambda * 9.0 * s * s * volume;
    EXPECT_NEAR(bulk_star / bulk_tet, 1.0, 5.0 * s) << s;
    EXPECT_NEAR(bulk_star / linear, 1.0, 5.0 * s) << s;
  }
}

// (c) The cantilever (20 x 20 x 100 mm on 4 x 4 x 20 cells, one end held, gravity, density
// 1000 kg/m^3, Newton converged): with the per-tet bulk term the tip rises by 16 % from nu = 0.45
// to 0.499 (locking); with vertex stars by 11 % (figures in docs/deformation.md). Stars stiffen
// less, but do not reach the 5 % aimed at: what is checked is that stars deflect more than tets
// at every nu and lose less as nu -> 1/2, and that both stay below beam theory.
TEST(VertexStarVolumes, CantileverStiffensLessAsPoissonRatioTendsToOneHalf) {
  CantileverSettings beam;
  const double euler_bernoulli_mm = cantilever_beam_theory_mm(beam, false);
  std::array<double, 2> tet{}, star{};
  const std::array<double, 2> nus = {0.45, 0.499};
  for (std::size_t k = 0; k < 2; ++k) {
    tet[k] = newton_tip_mm(cantilever({20, 20, 100}, {4, 4, 20}, 2.5e5, nus[k], VolumeFormulation::tet));
    star[k] =
        newton_tip_mm(cantilever({20, 20, 100}, {4, 4, 20}, 2.5e5, nus[k], VolumeFormulation::vertex_star));
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

// The elements' SVDs and projections are evaluated in parallel (sim/elastic_model.cpp), each into
// its own slot, then summed in element order: the same energy and gradient, bit for bit, on one
// thread and on two, with tets and groups both (more than the 1024 elements below which one
// thread does all).
TEST(TetGroupVolumes, EnergyAndGradientAreTheSameOnOneAndTwoThreads) {
  const ElasticModel model = cantilever({20, 20, 60}, {4, 4, 12}, 3e4, 0.49, VolumeFormulation::tet_group);
  ASSERT_GT(model.tets.size() + model.tet_groups.size(), std::size_t{1024});
  ASSERT_FALSE(model.tet_groups.empty());
  const Eigen::MatrixX3d p = perturbed(model);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const double energy_one = model_energy(model, {}, p);
  const Eigen::MatrixX3d gradient_one = model_gradient(model, {}, p);
  omp_set_num_threads(2);
  const double energy_two = model_energy(model, {}, p);
  const Eigen::MatrixX3d gradient_two = model_gradient(model, {}, p);
  omp_set_num_threads(threads);
  EXPECT_GT(energy_one, 0.0);
  EXPECT_EQ(energy_one, energy_two);
  EXPECT_EQ(gradient_one, gradient_two);
}

// (d) One constraint per group of tets on the group's volume-averaged F (mean dilatation).
TEST(TetGroupVolumes, GradientMatchesFiniteDifferences) {
  const ElasticModel model = cantilever({20, 20, 40}, {2, 2, 4}, 3e4, 0.49, VolumeFormulation::tet_group);
  ASSERT_EQ(model.tet_groups.size(), std::size_t{16});
  EXPECT_TRUE(gradient_matches(model, perturbed(model)));
}

// Newton's block of a group (the exact Hessian, unclamped) against central differences of the
// group's gradient, at a state where its volume is off the set.
TEST(TetGroupVolumes, HessianMatchesFiniteDifferences) {
  ElasticModel model = cantilever({20, 20, 40}, {2, 2, 4}, 3e4, 0.49, VolumeFormulation::tet_group);
  model.external_forces_N.resize(0, 3);
  const Eigen::MatrixX3d p = perturbed(model);
  for (std::size_t i : {std::size_t{0}, std::size_t{7}}) {
    ElasticModel one = model;
    one.tets.clear();
    one.tet_groups = {model.tet_groups[i]};
    const TetGroup& g = one.tet_groups[0];
    const auto n = static_cast<Eigen::Index>(g.vertices.size());
    // Group vertices' coordinates as one vector (vertex-major) -> the group's gradient there.
    auto gradient = [&](const Eigen::VectorXd& x) {
      Eigen::MatrixX3d q = p;
      for (Eigen::Index k = 0; k < n; ++k)
        q.row(g.vertices[static_cast<std::size_t>(k)]) = x.segment<3>(3 * k).transpose();
      const Eigen::MatrixX3d full = model_gradient(one, {}, q);
      Eigen::VectorXd out(3 * n);
      for (Eigen::Index k = 0; k < n; ++k)
        out.segment<3>(3 * k) = full.row(g.vertices[static_cast<std::size_t>(k)]).transpose();
      return out;
    };
    Eigen::VectorXd x(3 * n);
    for (Eigen::Index k = 0; k < n; ++k)
      x.segment<3>(3 * k) = p.row(g.vertices[static_cast<std::size_t>(k)]).transpose();
    const Eigen::MatrixXd numeric = phantasm::testing::central_difference_jacobian(gradient, x, 1e-7);
    const Eigen::MatrixXd analytic = tet_group_hessian(one, g, p, false);
    EXPECT_GT(analytic.norm(), 0.0);
    EXPECT_TRUE(phantasm::testing::matches_finite_differences(analytic, numeric, 1e-4)) << "group " << i;
  }
}

// A uniform strain makes every tet's F the group's F: the group's bulk energy is exactly the sum
// of its tets' volume terms (the per-tet term's), at any strain.
TEST(TetGroupVolumes, UniformDilationEnergyEqualsThePerTetTerm) {
  ElasticModel tet = cantilever({20, 20, 40}, {2, 2, 4}, 3e4, 0.45, VolumeFormulation::tet);
  ElasticModel group = cantilever({20, 20, 40}, {2, 2, 4}, 3e4, 0.45, VolumeFormulation::tet_group);
  tet.external_forces_N.resize(0, 3);
  group.external_forces_N.resize(0, 3);
  for (double s : {1e-1, 1e-2, 1e-4}) {
    const Eigen::MatrixX3d p = (1.0 + s) * tet.rest_positions_m;
    EXPECT_NEAR(bulk_energy(group, p) / bulk_energy(tet, p), 1.0, 1e-9) << s;
  }
}

TEST(TetGroupVolumes, ATetInTwoGroupsIsRefused) {
  ElasticModel model = cantilever({20, 20, 40}, {2, 2, 4}, 3e4, 0.45, VolumeFormulation::tet);
  EXPECT_THROW(move_bulk_to_tet_groups(model, {{0, 1}, {1, 2}}), std::invalid_argument);
  EXPECT_THROW(move_bulk_to_tet_groups(model, {{-1}}), std::invalid_argument);
}

// group_tets on a CGAL mesh: every tet in exactly one group, groups face-connected, of about the
// size asked for, labels kept apart, and the same groups on every call.
TEST(TetGroupVolumes, GroupingOfAnUnstructuredMeshIsAPartitionOfSmallConnectedGroups) {
  const TetMesh mesh = mesh_implicit_solid(
      *make_box(Eigen::Vector3d(10, 10, 20), Eigen::Vector3d(20, 20, 40), Eigen::Matrix3d::Identity()),
      criteria_for_tet_size(6.0), 1);
  std::vector<int> labels(static_cast<std::size_t>(mesh.tets.rows()));
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    labels[static_cast<std::size_t>(t)] = mesh.vertices(mesh.tets(t, 0), 2) < 20.0 ? 0 : 1;
  const auto groups = group_tets(mesh, 5, labels);
  EXPECT_EQ(groups, group_tets(mesh, 5, labels));
  std::vector<int> seen(static_cast<std::size_t>(mesh.tets.rows()), 0);
  std::size_t sum = 0;
  for (const auto& g : groups) {
    sum += g.size();
    EXPECT_LE(g.size(), std::size_t{10});
    std::set<int> group_labels;
    for (int t : g) {
      ++seen[static_cast<std::size_t>(t)];
      group_labels.insert(labels[static_cast<std::size_t>(t)]);
    }
    EXPECT_EQ(group_labels.size(), std::size_t{1});
    // Connected: grow from the first tet over shared faces (3 shared vertices).
    std::set<int> reached = {g[0]};
    for (bool grew = true; grew;) {
      grew = false;
      for (int t : g) {
        if (reached.count(t)) continue;
        for (int r : reached) {
          int shared = 0;
          for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b)
              shared += mesh.tets(t, a) == mesh.tets(r, b) ? 1 : 0;
          if (shared == 3) {
            reached.insert(t);
            grew = true;
            break;
          }
        }
      }
    }
    EXPECT_EQ(reached.size(), g.size());
  }
  EXPECT_EQ(sum, static_cast<std::size_t>(mesh.tets.rows()));
  for (int count : seen)
    EXPECT_EQ(count, 1);
  const double mean = static_cast<double>(sum) / static_cast<double>(groups.size());
  std::printf("%zu tets in %zu groups (mean %.2f)\n", sum, groups.size(), mean);
  EXPECT_GT(mean, 4.0);
  EXPECT_LT(mean, 6.0);
}

// The structured cantilever of (c) with one group per hexahedral cell: within 5 % between nu =
// 0.45 and 0.499 (13.08 and 12.84 mm: -1.8 %; docs/deformation.md), where tets lose 16 %.
TEST(TetGroupVolumes, CantileverDoesNotLockAsPoissonRatioTendsToOneHalf) {
  const double at_045 =
      newton_tip_mm(cantilever({20, 20, 100}, {4, 4, 20}, 2.5e5, 0.45, VolumeFormulation::tet_group));
  const double at_0499 =
      newton_tip_mm(cantilever({20, 20, 100}, {4, 4, 20}, 2.5e5, 0.499, VolumeFormulation::tet_group));
  std::printf("cells: nu 0.45 %.3f mm, nu 0.499 %.3f mm\n", at_045, at_0499);
  EXPECT_GT(at_0499 / at_045, 0.95);
  EXPECT_LT(at_0499 / at_045, 1.0);
}

// The same cantilever on a CGAL tet mesh (6 mm tets), grouped by group_tets: the tip at nu =
// 0.499 within 5 % of nu = 0.45's, where per-tet tets lock (they lose most of it), and within
// 15 % of Timoshenko's beam (linear tets stay stiff in bending at 3 tets across).
TEST(TetGroupVolumes, UnstructuredCantileverDoesNotLock) {
  CantileverSettings s;
  s.tet_size_mm = 6.0;
  s.volume = VolumeFormulation::tet_group;
  std::array<double, 2> group{}, tet{};
  const std::array<double, 2> nus = {0.45, 0.499};
  for (std::size_t k = 0; k < 2; ++k) {
    s.poisson_ratio = nus[k];
    s.volume = VolumeFormulation::tet_group;
    group[k] = newton_tip_mm(cantilever_model(s));
    s.volume = VolumeFormulation::tet;
    tet[k] = newton_tip_mm(cantilever_model(s));
    std::printf("CGAL 6 mm, nu %.3f: groups %.2f mm, per tet %.2f mm, Timoshenko %.2f mm\n", nus[k], group[k],
                tet[k], cantilever_beam_theory_mm(s, true));
    EXPECT_GT(group[k], 0.85 * cantilever_beam_theory_mm(s, true));
  }
  EXPECT_GT(group[1] / group[0], 0.95);
  EXPECT_LT(tet[1] / tet[0], 0.5);
}

// Local/global minimizes the same energy as Newton with groups: on a coarse cantilever it
// reaches Newton's tip within 0.1 % (nu = 0.45 and 0.49; the residual test of the scene
// defaults tightened to 1e-6).
TEST(TetGroupVolumes, LocalGlobalReachesNewtonsAnswer) {
  for (double nu : {0.45, 0.49}) {
    const ElasticModel model = cantilever({20, 20, 100}, {2, 2, 10}, 2.5e5, nu, VolumeFormulation::tet_group);
    const double newton = newton_tip_mm(model);
    Eigen::MatrixX3d q = model.rest_positions_m;
    StopCriteria stop;
    stop.max_iterations = 20000;
    stop.relative_residual = 1e-6;
    stop.force_scale_N = 9.81 * model.masses_kg.maxCoeff();
    LocalGlobalSolver solver(model, 0.0, 1);
    const SolveReport report = solver.solve(q, q, stop);
    const double local_global = cantilever_tip_deflection_mm(model, q);
    std::printf("nu %.2f: Newton %.4f mm, local/global %.4f mm after %d iterations\n", nu, newton,
                local_global, report.iterations);
    EXPECT_TRUE(report.converged);
    EXPECT_NEAR(local_global / newton, 1.0, 1e-3);
  }
}

// Local/global at nu -> 1/2 with the scene defaults (relative residual 1e-3 of the heaviest
// vertex's weight, at most 2000 iterations, one thread): on the 4 x 4 x 20 cantilever with the
// bulk term on its cells it converges at nu = 0.45, 0.49 and 0.499 to Newton's tip on the same
// energy (within 1 %), its tip at 0.499 is within 5 % of its tip at 0.45 (no locking) and within
// 20 % of Timoshenko's beam (linear tets stay stiff in bending at 4 tets across); with the bulk
// term per tet it converges to Newton's tip too (the plain iteration did not above nu = 0.45).
// The same bits on one thread and on two.
TEST(TetGroupVolumes, LocalGlobalConvergesToNewtonAsPoissonRatioTendsToOneHalf) {
  const std::array<double, 3> nus = {0.45, 0.49, 0.499};
  std::array<double, 3> tip{};
  for (VolumeFormulation formulation : {VolumeFormulation::tet_group, VolumeFormulation::tet}) {
    for (std::size_t k = 0; k < nus.size(); ++k) {
      CantileverSettings s;
      s.poisson_ratio = nus[k];
      s.volume = formulation;
      const ElasticModel model = cantilever_model(s);
      const double newton = newton_tip_mm(model);
      Eigen::MatrixX3d q = model.rest_positions_m;
      StopCriteria defaults;
      defaults.max_iterations = 2000;
      defaults.force_scale_N = 9.81 * model.masses_kg.maxCoeff();
      LocalGlobalSolver solver(model, 0.0, 1);
      const SolveReport report = solver.solve(q, q, defaults);
      tip[k] = cantilever_tip_deflection_mm(model, q);
      std::printf("%s, nu %.3f: local/global %.3f mm after %d iterations (%s), Newton %.3f mm, Timoshenko "
                  "%.2f mm\n",
                  formulation == VolumeFormulation::tet_group ? "cells" : "per tet", nus[k], tip[k],
                  report.iterations, report.converged ? "converged" : "not converged", newton,
                  cantilever_beam_theory_mm(s, true));
      EXPECT_TRUE(report.converged) << nus[k];
      EXPECT_NEAR(tip[k] / newton, 1.0, 0.01) << nus[k];
      if (formulation == VolumeFormulation::tet_group) {
        EXPECT_GT(tip[k], 0.8 * cantilever_beam_theory_mm(s, true));
      }
    }
    if (formulation == VolumeFormulation::tet_group) {
      EXPECT_NEAR(tip[2] / tip[0], 1.0, 0.05);
    }
  }
  // The L-BFGS phase gives the same bits on one thread and on two.
  CantileverSettings s;
  s.poisson_ratio = 0.499;
  s.volume = VolumeFormulation::tet_group;
  const ElasticModel model = cantilever_model(s);
  StopCriteria defaults;
  defaults.max_iterations = 2000;
  defaults.force_scale_N = 9.81 * model.masses_kg.maxCoeff();
  Eigen::MatrixX3d one = model.rest_positions_m, two = model.rest_positions_m;
  LocalGlobalSolver single(model, 0.0, 1), pair(model, 0.0, 2);
  const SolveReport a = single.solve(one, one, defaults);
  const SolveReport b = pair.solve(two, two, defaults);
  EXPECT_GT(a.iterations, 100);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_TRUE((one.array() == two.array()).all());
}
