// The shipped procedural head (data-synthetic/head.yaml) nearly incompressible (#44): every material of
// Poisson ratio 0.45 or more set to 0.499 and solved with the scene's own solver to a relative
// residual of 1e-6 and the default bulk term. The retractor pushes the grey matter into a body held
// by the fixed skull, so the loads ask the body for a loss of volume; nearly incompressible tissue
// shares it by its bulk modulus K = E / (3 (1 - 2 nu)) under one pressure. With one bulk modulus
// for every tissue each organ's volume (its patch surface's base mesh, moved with the tets) changes
// by what the body's does within 1 % of its volume, the lateral ventricles included, though the
// shipped body (the CSF's own mesh of 440 tets) gives each of them only a couple of tets. With the
// scene's own materials the CSF (500 Pa against the brain's 3000 Pa: a sixth of its bulk modulus)
// gives more: the ventricles lose more than the brain's organs, and at most K_brain / K_csf times as
// much (docs/deformation.md, Volume locking; the Colin head behaves alike). And the shipped head at
// 0.499 as it is, solved with the scene's own solver and stop test: converged within 1 % of Newton's
// field, or a warning (#44, the extremes table's head row).

#include "geometry/triangle_mesh.hpp"
#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

using namespace phantasm;

namespace {

/// The shipped head.yaml.
Scene shipped_head() {
  const SceneLoadResult loaded = load_scene(std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/head.yaml");
  if (!loaded.scene) throw std::runtime_error(format_diagnostics(loaded.problems));
  return *loaded.scene;
}

/// Every material of Poisson ratio 0.45 or more set to 0.499.
void nearly_incompressible(DeformationSettings& d) {
  for (MaterialSettings& m : d.materials)
    if (m.poisson_ratio >= 0.45) m.poisson_ratio = 0.499;
}

/// Each organ's relative volume change (its patch surface's base mesh moved with the tets; 0 for
/// organs without a surface or fixed) and the index of the body's organ, after solving `d`.
struct OrganVolumeChanges {
  std::vector<double> change;
  std::size_t body = 0;
  PhantomDeformation result;
};

OrganVolumeChanges solve_volumes(const Scene& scene, const Phantom& phantom, const DeformationSettings& d) {
  Reporter quiet = Reporter::silent();
  StageReport report;
  OrganVolumeChanges out;
  out.result = deform_phantom(d, scene.organs, phantom, report, quiet);
  const PhantomDeformation& result = out.result;
  out.change.assign(result.organs.size(), 0.0);
  out.body = result.organs.size();
  for (std::size_t o = 0; o < result.organs.size(); ++o) {
    if (result.bodies.size() == 1 && result.organs[o].organ == result.bodies[0].organ) out.body = o;
    if (!phantom.organs[o].surface || result.organs[o].moved_by == "fixed") continue;
    const TriangleMesh& base = phantom.organs[o].surface->base_mesh();
    out.change[o] = enclosed_volume({result.organs[o].surface_mm, base.faces}) / enclosed_volume(base) - 1.0;
  }
  return out;
}

/// The bulk modulus of a material, Pa.
double bulk_modulus(const MaterialSettings& m) {
  return m.youngs_modulus_Pa / (3.0 * (1.0 - 2.0 * m.poisson_ratio));
}

} // namespace

TEST(HeadOrganVolumes, EveryOrganSharesTheBodysVolumeChangeByItsBulkModulusAtPoissonRatio0499) {
  const Scene scene = shipped_head();
  Reporter quiet = Reporter::silent();
  const Phantom phantom = simulate(scene, quiet, SimulationStage::anatomy).phantom;
  DeformationSettings d = scene.deformation;
  ASSERT_EQ(d.volume, DeformationSettings{}.volume)
      << "the scene names its bulk term: this tests the default";
  d.solver.relative_residual_tolerance = 1e-6;
  nearly_incompressible(d);
  const MaterialSettings* brain = nullptr;
  const MaterialSettings* csf = nullptr;
  for (const MaterialSettings& m : d.materials) {
    if (m.name == "brain") brain = &m;
    if (m.name == "csf") csf = &m;
  }
  ASSERT_TRUE(brain && csf);
  ASSERT_GT(bulk_modulus(*brain), 2.0 * bulk_modulus(*csf))
      << "no contrast of bulk moduli: the second half proves nothing";

  // One bulk modulus: every tissue at the brain's Young's modulus (and 0.499).
  DeformationSettings same = d;
  for (MaterialSettings& m : same.materials)
    if (m.poisson_ratio >= 0.45) m.youngs_modulus_Pa = brain->youngs_modulus_Pa;
  const OrganVolumeChanges one = solve_volumes(scene, phantom, same);
  ASSERT_EQ(one.result.solves.size(), 1u);
  EXPECT_TRUE(one.result.solves[0].converged)
      << "relative residual " << one.result.solves[0].relative_residual;
  ASSERT_EQ(one.result.bodies.size(), 1u);
  EXPECT_EQ(one.result.bodies[0].inverted_tets, 0);
  ASSERT_LT(one.body, one.change.size());
  // The push asks for a loss of volume; nearly incompressible tissue gives no more than that.
  EXPECT_LT(one.change[one.body], -0.001);
  int compared = 0;
  for (std::size_t o = 0; o < one.change.size(); ++o) {
    if (!phantom.organs[o].surface || one.result.organs[o].moved_by == "fixed" || o == one.body) continue;
    std::printf("one bulk modulus: %s %+.2f %% (body %+.2f %%)\n", one.result.organs[o].organ.c_str(),
                100.0 * one.change[o], 100.0 * one.change[one.body]);
    EXPECT_NEAR(one.change[o], one.change[one.body], 0.01)
        << one.result.organs[o].organ << " against the body, " << one.result.organs[one.body].organ;
    ++compared;
  }
  EXPECT_EQ(compared, 4); // grey and white matter, both ventricles

  // The scene's materials: the CSF's organs (the ventricles) give more than the brain's, by at most
  // the ratio of the bulk moduli.
  const OrganVolumeChanges two = solve_volumes(scene, phantom, d);
  ASSERT_EQ(two.result.solves.size(), 1u);
  EXPECT_TRUE(two.result.solves[0].converged);
  double brain_change = 0.0;
  int brain_organs = 0;
  for (std::size_t o = 0; o < two.change.size(); ++o) {
    const OrganSettings* organ = scene.find_organ(two.result.organs[o].organ);
    if (o != two.body && organ && organ->material == "brain" && two.change[o] != 0.0) {
      brain_change += two.change[o];
      ++brain_organs;
    }
  }
  ASSERT_EQ(brain_organs, 2);
  brain_change /= brain_organs;
  ASSERT_LT(brain_change, 0.0);
  const double ratio = bulk_modulus(*brain) / bulk_modulus(*csf);
  int ventricles = 0;
  for (std::size_t o = 0; o < two.change.size(); ++o) {
    const OrganSettings* organ = scene.find_organ(two.result.organs[o].organ);
    if (o == two.body || !organ || organ->material != "csf" || two.change[o] == 0.0) continue;
    std::printf("scene's materials: %s %+.2f %%, the brain's organs %+.2f %% (bulk moduli %.1f : 1)\n",
                organ->name.c_str(), 100.0 * two.change[o], 100.0 * brain_change, ratio);
    EXPECT_LT(two.change[o], brain_change) << organ->name;
    EXPECT_GT(two.change[o], ratio * brain_change) << organ->name;
    ++ventricles;
  }
  EXPECT_EQ(ventricles, 2);
}

// The residual test alone stopped the head at 0.499 (1280-triangle surfaces) 18.7 % of its largest
// displacement from Newton's answer and called it converged. With the scene's own solver and stop
// test (local/global, relative residual 1e-3) a solve reported converged, with no tet inverted,
// lies within 1 % of Newton's field solved to 1e-7 at every vertex; else the stage warns.
TEST(HeadOrganVolumes, TheHeadAtPoissonRatio0499IsConvergedWithinOnePercentOfNewtonOrWarns) {
  const Scene scene = shipped_head();
  Reporter quiet = Reporter::silent();
  const Phantom phantom = simulate(scene, quiet, SimulationStage::anatomy).phantom;
  DeformationSettings d = scene.deformation;
  nearly_incompressible(d);
  StageReport report;
  const PhantomDeformation run = deform_phantom(d, scene.organs, phantom, report, quiet);
  DeformationSettings tight = d;
  tight.solver.method = SolverMethod::newton;
  tight.solver.relative_residual_tolerance = 1e-7;
  tight.solver.max_iterations = 200;
  StageReport reference_report;
  const PhantomDeformation reference = deform_phantom(tight, scene.organs, phantom, reference_report, quiet);
  ASSERT_EQ(reference.solves.size(), 1u);
  ASSERT_LE(reference.solves[0].relative_residual, 1e-5) << "no oracle to judge the run by";
  ASSERT_EQ(run.solves.size(), 1u);
  ASSERT_EQ(run.bodies.size(), reference.bodies.size());
  const bool warned = !run.solves[0].converged || run.bodies[0].inverted_tets > 0;
  EXPECT_EQ(warned, !report.warnings.empty());
  for (std::size_t b = 0; b < run.bodies.size(); ++b) {
    const DeformedBody& x = run.bodies[b];
    const DeformedBody& r = reference.bodies[b];
    const double largest = (r.deformed_mm - r.rest_mm).rowwise().norm().maxCoeff();
    const double distance = (x.deformed_mm - r.deformed_mm).rowwise().norm().maxCoeff();
    ASSERT_GT(largest, 1.0) << "the head does not move: the test would prove nothing";
    std::printf("%s: %d iterations, %s, %.3g of its largest displacement (%.2f mm) from Newton's\n",
                x.organ.c_str(), run.solves[0].iterations,
                run.solves[0].converged ? "converged" : "not converged", distance / largest, largest);
    if (!warned) {
      EXPECT_LE(distance / largest, 0.01) << x.organ;
    }
  }
}
