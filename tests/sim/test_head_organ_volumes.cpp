// The shipped procedural head (data-synthetic/head.yaml) meshed at 10 mm tets and nearly incompressible
// (#44): every material of Poisson ratio 0.45 or more set to 0.499, solved with the scene's own solver to a
// relative residual of 1e-6 and the default bulk term. The retractor's push leaves the body less
// room, and every organ's volume (its patch surface's base mesh, moved with the tets) must change
// by what the body's does within 1 % of its volume: the lateral ventricles included, which a
// bulk term that holds only groups' volumes lets lose several per cent more on a body too coarse
// to give them tets of their own, and a per-tet bulk term (which locks) about 1.1-1.3 % more
// (docs/deformation.md, Volume locking). And the shipped head at 0.499 as it is, solved with the
// scene's own solver and stop test: converged within 1 % of Newton's field, or a warning (#44, the
// extremes table's head row).

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

} // namespace

TEST(HeadOrganVolumes, EveryOrganChangesWithTheBodyWithinOnePercentAtPoissonRatio0499) {
  Scene scene = shipped_head();
  // Tets of 10 mm: the ventricles get tets of their own (the shipped body, the CSF's own mesh of
  // 440 tets, gives each 2: no bulk term holds an organ a tet or two across).
  scene.anatomy.tet_size_mm = 10.0;
  Reporter quiet = Reporter::silent();
  const Phantom phantom = simulate(scene, quiet, SimulationStage::anatomy).phantom;
  DeformationSettings d = scene.deformation;
  ASSERT_EQ(d.volume, DeformationSettings{}.volume)
      << "the scene names its bulk term: this tests the default";
  d.solver.relative_residual_tolerance = 1e-6;
  nearly_incompressible(d);
  StageReport report;
  const PhantomDeformation result = deform_phantom(d, scene.organs, phantom, report, quiet);
  ASSERT_EQ(result.solves.size(), 1u);
  EXPECT_TRUE(result.solves[0].converged) << "relative residual " << result.solves[0].relative_residual;
  ASSERT_EQ(result.bodies.size(), 1u);
  EXPECT_EQ(result.bodies[0].inverted_tets, 0);
  // The body is the organ whose mesh it is (the CSF, holding the brain and the ventricles).
  std::vector<double> change(result.organs.size(), 0.0);
  for (std::size_t o = 0; o < result.organs.size(); ++o) {
    if (!phantom.organs[o].surface || result.organs[o].moved_by == "fixed") continue;
    const TriangleMesh& base = phantom.organs[o].surface->base_mesh();
    change[o] = enclosed_volume({result.organs[o].surface_mm, base.faces}) / enclosed_volume(base) - 1.0;
  }
  std::size_t body = result.organs.size();
  for (std::size_t o = 0; o < result.organs.size(); ++o)
    if (result.organs[o].organ == result.bodies[0].organ) body = o;
  ASSERT_LT(body, result.organs.size());
  // The push asks for a loss of volume; nearly incompressible tissue gives no more than that.
  EXPECT_LT(change[body], -0.001);
  int compared = 0;
  for (std::size_t o = 0; o < result.organs.size(); ++o) {
    if (!phantom.organs[o].surface || result.organs[o].moved_by == "fixed" || o == body) continue;
    EXPECT_NEAR(change[o], change[body], 0.01)
        << result.organs[o].organ << " against the body, " << result.organs[body].organ;
    ++compared;
  }
  EXPECT_EQ(compared, 4); // grey and white matter, both ventricles
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
