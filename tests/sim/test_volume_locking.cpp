// Volume locking of the bulk term (#44): the extremes table's cantilever
// (bench/solver_extremes.hpp: 20 x 20 x 100 mm, E = 100 kPa, under its weight, its x-min end held)
// solved by Newton to a relative residual of 1e-7 as nu goes from 0.45 to 0.499, on its 4 x 4 x 20
// cells and on 6 x 6 x 30. The bulk term on groups of tets (`volume: tet_groups`) and on groups
// and tets (`tet_groups_and_tets`: each tet keeps a bulk weight capped by its strain weight) must
// keep the tip within 5 % and must not make the coarse bar softer than the refined one, and so
// must the default bulk term (groups and tets); the per-tet term loses more than 10 %. The split between tets
// and groups: its gradient and its energy under a uniform strain (docs/deformation.md, Volume locking).

#include "bench/solver_extremes.hpp"
#include "tests/support/finite_difference.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <random>

using namespace phantasm;
using namespace phantasm::bench;

namespace {

/// Newton's tip deflection (mm) of the cantilever with `cells` cells across at Poisson ratio nu.
double tip_mm(int cells, double nu, std::optional<VolumeFormulation> volume = std::nullopt) {
  ExtremeCase c; // 100 kPa, quasi-static
  c.poisson_ratio = nu;
  c.cells_across = cells;
  c.volume = volume;
  const ExtremeCantilever k = extreme_cantilever(c);
  const ExtremeOracle oracle = extreme_oracle(k);
  EXPECT_TRUE(oracle_converged(oracle)) << "relative residual " << oracle.report.relative_residual;
  EXPECT_EQ(inversions(k.model, oracle.p).inverted, 0);
  return tip_deflection_mm(k, oracle.p);
}

/// The bar's model with `cells` across at Poisson ratio nu, no load, bulk term `volume`.
ElasticModel bar(int cells, double nu, VolumeFormulation volume) {
  ExtremeCase c; // 100 kPa, quasi-static
  c.poisson_ratio = nu;
  c.cells_across = cells;
  c.volume = volume;
  ElasticModel model = extreme_cantilever(c).model;
  model.external_forces_N.resize(0, 3);
  return model;
}

/// The bulk energy of a model at p: its energy less that of its tets' strain terms alone.
double bulk_energy(const ElasticModel& model, const Eigen::MatrixX3d& p) {
  ElasticModel strain_only = model;
  for (TetElement& e : strain_only.tets)
    e.volume_weight = 0.0;
  strain_only.tet_groups.clear();
  return model_energy(model, {}, p) - model_energy(strain_only, {}, p);
}

} // namespace

// With groups and tets every grouped tet keeps a bulk weight of tet_bulk_ratio times its strain
// weight (all of it where lambda is smaller) and its group the rest: the model's energy, the sum
// of both terms, has the gradient central differences give, at a state where tets and groups
// are off their volume.
TEST(VolumeLocking, GroupsAndTetsGradientMatchesFiniteDifferences) {
  for (double nu : {0.49, 0.499}) {
    const ElasticModel model = bar(2, nu, VolumeFormulation::tet_group_and_tet);
    ASSERT_FALSE(model.tet_groups.empty());
    std::size_t kept = 0;
    for (const TetElement& e : model.tets) {
      EXPECT_LE(e.volume_weight, tet_bulk_ratio * e.strain_weight * (1.0 + 1e-12));
      kept += e.volume_weight > 0.0;
    }
    EXPECT_EQ(kept, model.tets.size());
    std::mt19937 random(7);
    std::normal_distribution<double> normal(0.0, 1e-3);
    Eigen::MatrixX3d p = model.rest_positions_m;
    for (Eigen::Index v = 0; v < p.rows(); ++v)
      for (int c = 0; c < 3; ++c)
        p(v, c) += normal(random);
    const Eigen::MatrixX3d numeric = phantasm::testing::central_difference_gradient(
        [&](const Eigen::MatrixX3d& q) { return model_energy(model, {}, q); }, p, 1e-7);
    EXPECT_TRUE(phantasm::testing::matches_finite_differences(model_gradient(model, {}, p), numeric, 1e-6))
        << "nu " << nu;
  }
}

// Splitting the bulk weight between tets and groups changes nothing under a uniform strain (every
// F_t is then F_g): the bulk energy is the per-tet term's, at nu where the tets keep all of it
// (0.1: 3 lambda V < 2 mu V, and no group is made) and where they keep a small part (0.499).
TEST(VolumeLocking, GroupsAndTetsCostWhatThePerTetTermCostsUnderAUniformStrain) {
  EXPECT_TRUE(bar(2, 0.1, VolumeFormulation::tet_group_and_tet).tet_groups.empty());
  for (double nu : {0.1, 0.499}) {
    const ElasticModel tet = bar(2, nu, VolumeFormulation::tet);
    const ElasticModel mixed = bar(2, nu, VolumeFormulation::tet_group_and_tet);
    for (double s : {1e-1, 1e-2, 1e-4}) {
      const Eigen::MatrixX3d p = (1.0 + s) * tet.rest_positions_m;
      EXPECT_NEAR(bulk_energy(mixed, p) / bulk_energy(tet, p), 1.0, 1e-9) << "nu " << nu << ", strain " << s;
    }
  }
}

TEST(VolumeLocking, ANegativeShareKeptPerTetIsRefused) {
  ElasticModel model = bar(2, 0.45, VolumeFormulation::tet);
  EXPECT_THROW(move_bulk_to_tet_groups(model, {{0, 1}}, -1.0), std::invalid_argument);
  EXPECT_THROW(move_bulk_to_tet_groups(model, {{0, 1}}, std::nan("")), std::invalid_argument);
}

TEST(VolumeLocking, TheDefaultBulkTermIsGroupsAndTetsAndTheOthersAreReachable) {
  EXPECT_EQ(DeformationSettings{}.volume, VolumeFormulation::tet_group_and_tet);
  EXPECT_STREQ(to_string(VolumeFormulation::tet), "per_tet");
  EXPECT_STREQ(to_string(VolumeFormulation::tet_group), "tet_groups");
  EXPECT_STREQ(to_string(VolumeFormulation::tet_group_and_tet), "tet_groups_and_tets");
}

/// The acceptance of a bulk term that does not lock: Newton's tip within 5 % from nu 0.45 to
/// 0.499 on the coarse (4 cells across) and the refined (6) bar, and the coarse bar not softer
/// than the refined one (linear tets converge from the stiff side).
static void expect_no_locking(VolumeFormulation volume) {
  const double coarse = tip_mm(4, 0.45, volume), coarse_incompressible = tip_mm(4, 0.499, volume);
  const double refined = tip_mm(6, 0.45, volume), refined_incompressible = tip_mm(6, 0.499, volume);
  SCOPED_TRACE(std::string(to_string(volume)) + ": tips at nu 0.45 / 0.499: coarse " +
               std::to_string(coarse) + " / " + std::to_string(coarse_incompressible) + " mm, refined " +
               std::to_string(refined) + " / " + std::to_string(refined_incompressible) + " mm");
  EXPECT_GT(coarse_incompressible, 0.95 * coarse);
  EXPECT_LT(coarse_incompressible, 1.05 * coarse);
  EXPECT_GT(refined_incompressible, 0.95 * refined);
  EXPECT_LT(refined_incompressible, 1.05 * refined);
  EXPECT_LE(coarse, refined);
  EXPECT_LE(coarse_incompressible, refined_incompressible);
}

TEST(VolumeLocking, TetGroupsKeepTheCantileversTipAsPoissonRatioNearsOneHalf) {
  expect_no_locking(VolumeFormulation::tet_group);
  // What groups avoid: per tet the same coarse bar locks.
  const double per_tet = tip_mm(4, 0.45, VolumeFormulation::tet);
  const double per_tet_incompressible = tip_mm(4, 0.499, VolumeFormulation::tet);
  EXPECT_LT(per_tet_incompressible, 0.9 * per_tet);
  EXPECT_LE(per_tet, tip_mm(4, 0.45, VolumeFormulation::tet_group)); // the per-tet bar is the stiffer one
}

// The default bulk term, whichever it is, does not lock. (Groups and tets: the tets' share of the
// bulk term is capped by their strain weight, not a share of lambda; it does not grow as
// nu -> 1/2, so it stiffens the bar alike at every nu.)
TEST(VolumeLocking, TheDefaultBulkTermKeepsTheCantileversTipAsPoissonRatioNearsOneHalf) {
  expect_no_locking(DeformationSettings{}.volume);
}
