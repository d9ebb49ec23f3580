// The deformation stage on whole scenes: bodies, embedded organs, held boundaries, loads, and
// the dynamic mode against the closed form of implicit Euler.

#include "core/error.hpp"
#include "geometry/tet_boundary.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"
#include "sim/enclosed_volume.hpp"
#include "sim/newton.hpp"
#include "sim/surface_contacts.hpp"
#include "tests/support/deformed_bodies.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

using namespace phantasm;

namespace {

/// No tet of the body inverted, and its volume within `tolerance` (relative) of the rest volume.
void expect_no_inversion_and_volume_kept(const DeformedBody& body, double tolerance) {
  double rest_volume = 0.0, volume = 0.0;
  for (Eigen::Index t = 0; t < body.tets.rows(); ++t) {
    ASSERT_GT(phantasm::testing::body_tet_volume(body.deformed_mm, body.tets, t), 0.0) << "tet " << t;
    rest_volume += phantasm::testing::body_tet_volume(body.rest_mm, body.tets, t);
    volume += phantasm::testing::body_tet_volume(body.deformed_mm, body.tets, t);
  }
  EXPECT_NEAR(volume / rest_volume, 1.0, tolerance);
}

} // namespace

// The small head: grey matter is the body (inside the fixed scalp, so its boundary is held
// except where the load pushes it), white matter is embedded in it.
TEST(DeformPhantom, PushedSurfaceReachesItsTargetAndEmbeddedOrgansFollow) {
  const Scene scene = phantasm::testing::load_repository_scene("tests/data/scenes/small-head.yaml");
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  StageReport report;
  const PhantomDeformation d = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
  ASSERT_EQ(d.organs.size(), 3u);
  EXPECT_EQ(d.organs[0].moved_by, "fixed");
  EXPECT_EQ(d.organs[1].moved_by, "solver");
  EXPECT_EQ(d.organs[2].moved_by, "embedded in grey_matter");
  ASSERT_EQ(d.bodies.size(), 1u);
  EXPECT_EQ(report.status, "done");
  EXPECT_LT(d.attachment_error_mm, 0.01);
  EXPECT_LT(d.solves.back().residual_N, 1e-2);

  // The fixed scalp does not move; the pushed cortex moved by the load, (-2, 0, -3) mm.
  EXPECT_EQ(d.organs[0].surface_mm, phantom.organs[0].surface->rest_positions());
  const Eigen::MatrixX3d moved = d.organs[1].surface_mm - phantom.organs[1].surface->rest_positions();
  const double largest = moved.rowwise().norm().maxCoeff();
  EXPECT_NEAR(largest, std::sqrt(13.0), 0.01);
  // The white matter follows, by less than the surface that was pushed.
  const double inner =
      (d.organs[2].surface_mm - phantom.organs[2].surface->rest_positions()).rowwise().norm().maxCoeff();
  EXPECT_GT(inner, 0.01);
  EXPECT_LT(inner, largest);
  // No tet inverted; the body's volume nearly kept (nu 0.45 under a local push).
  expect_no_inversion_and_volume_kept(d.bodies[0], 0.01);
  // The deformed phantom's patch surfaces follow their base.
  const Phantom deformed = deformed_phantom(phantom, d);
  EXPECT_EQ(deformed.organs[1].surface->base_mesh().vertices, d.organs[1].surface_mm);
}

/// The bar scene with half as many cells along each axis (3 x 3 x 14, 630 tets against the
/// shipped 5040): its vertices still lie on the ends, the middle cross-section and the corners the
/// tests below read, and the fast tests (which the sanitizer pass runs too) solve an eighth of the
/// tets.
Scene coarse_bar() {
  Scene scene = phantasm::testing::load_repository_scene("data-synthetic/bar.yaml");
  scene.anatomy.organs[0].shape.cells = Eigen::Vector3i(3, 3, 14);
  return scene;
}

/// The bar scene under gravity alone, its clamps taken off: nothing holds it.
Scene free_bar() {
  Scene scene = coarse_bar();
  auto& loads = scene.deformation.loads;
  loads.erase(std::remove_if(loads.begin(), loads.end(),
                             [](const LoadSettings& l) { return l.kind != LoadKind::gravity; }),
              loads.end());
  EXPECT_EQ(loads.size(), 1u);
  return scene;
}

// The bar scene: one end held, the other turned 30 degrees about the bar's axis (a displacement
// load with a rotation), under gravity. The clamped ends are where the loads put them, the
// middle twists part of the way and sags a little, and the bar stays in the field of view.
TEST(DeformPhantom, TheBarSceneHoldsOneEndAndTwistsTheOther) {
  const Scene scene = coarse_bar();
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  StageReport report;
  const PhantomDeformation d = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
  EXPECT_EQ(d.organs[0].moved_by, "solver");
  EXPECT_LT(d.attachment_error_mm, 0.05);
  const Eigen::MatrixX3d& rest = phantom.organs[0].solid->vertices;
  const Eigen::MatrixX3d& moved = d.organs[0].solid_mm;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(M_PI / 6.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d half_fov = 0.5 * scene.grid.field_of_view_mm;
  double held = 0.0, turned = 0.0, middle_angle = 0.0;
  int middle = 0;
  for (Eigen::Index v = 0; v < rest.rows(); ++v) {
    const Eigen::Vector3d x = rest.row(v).transpose(), y = moved.row(v).transpose();
    EXPECT_TRUE((y.cwiseAbs().array() < half_fov.array()).all()) << y.transpose();
    if (x.z() < -139.999) held = std::max(held, (y - x).norm());
    if (x.z() > 139.999) turned = std::max(turned, (y - turn * x).norm());
    if (std::abs(x.z()) < 1e-6 && x.head<2>().norm() > 20.0) {
      middle_angle += std::atan2(x.x() * y.y() - x.y() * y.x(), x.x() * y.x() + x.y() * y.y());
      ++middle;
    }
  }
  EXPECT_LT(held, 0.05);
  EXPECT_LT(turned, 0.05);
  ASSERT_GT(middle, 0);
  middle_angle /= middle;
  EXPECT_GT(middle_angle, 10.0 * M_PI / 180.0); // about half the end's turn
  EXPECT_LT(middle_angle, 20.0 * M_PI / 180.0);
  expect_no_inversion_and_volume_kept(d.bodies[0], 0.05);
}

// The bar scene without its clamps falls as a rigid body, and implicit Euler's free fall after
// n steps is h^2 g n (n + 1) / 2 exactly. Every solver of a dynamic scene, the position-based
// ones included.
TEST(DeformPhantom, DynamicFreeFallMatchesImplicitEulerInClosedForm) {
  Scene scene = free_bar();
  scene.deformation.frames = 10;
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  for (const SolverMethod method :
       {SolverMethod::local_global, SolverMethod::xpbd, SolverMethod::gauss_seidel_pbd}) {
    SCOPED_TRACE(to_string(method));
    scene.deformation.solver.method = method;
    StageReport report;
    const PhantomDeformation d = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
    ASSERT_EQ(d.solves.size(), 10u);
    EXPECT_EQ(d.solves.back().solver, to_string(method));
    const double h = scene.deformation.time_step_s;
    const double fall_mm = 1e3 * h * h * 9.81 * 10 * 11 / 2.0;
    const Eigen::MatrixX3d displacement = d.organs[0].solid_mm - phantom.organs[0].solid->vertices;
    EXPECT_NEAR(displacement.col(1).mean(), -fall_mm, 1e-3 * fall_mm);
    EXPECT_LT((displacement.col(1).array() + fall_mm).abs().maxCoeff(), 1e-3 * fall_mm); // rigid: no sag
    EXPECT_LT(displacement.col(0).cwiseAbs().maxCoeff(), 1e-6);
  }
}

TEST(DeformPhantom, AQuasiStaticBodyThatNothingHoldsIsAClearError) {
  Scene scene = free_bar();
  scene.deformation.mode = DeformationMode::quasi_static;
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  StageReport report;
  try {
    deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("deformation.fixed"), std::string::npos) << error.what();
  }
}

// A position-based solver cannot solve a quasi-static scene: the scene's validation rejects it
// (ParseScene.PositionBasedSolversInAQuasiStaticSceneAreRejectedAtTheirLine); settings made in
// code that ask for it stop the stage with the setting's key path, which the pipeline turns into
// the scene's line.
TEST(DeformPhantom, APositionBasedSolverInAQuasiStaticSceneStopsAtItsSetting) {
  Scene scene = phantasm::testing::load_repository_scene("tests/data/scenes/small-head.yaml");
  scene.deformation.solver.method = SolverMethod::xpbd;
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  StageReport report;
  try {
    deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
    FAIL() << "no error";
  } catch (const SettingError& error) {
    EXPECT_EQ(error.key_path(), "deformation.solver.method");
    EXPECT_NE(error.message().find("xpbd steps in time"), std::string::npos) << error.message();
    EXPECT_GT(scene.location_of(error.key_path()).line, 0);
  }
}

// deformation.volume: tet_groups puts the body's bulk term on groups of tets (the log says how
// many); the small head's push is met as with the per-tet term, and the solve converges.
TEST(DeformPhantom, BulkTermOnGroupsOfTetsFromTheScene) {
  Scene scene = phantasm::testing::load_repository_scene("tests/data/scenes/small-head.yaml");
  scene.deformation.volume = VolumeFormulation::tet_group;
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  StageReport report;
  const PhantomDeformation d = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
  EXPECT_EQ(report.status, "done");
  bool logged = false;
  for (const std::string& line : report.modelled)
    logged = logged || line.find("groups of tets (volume-averaged F)") != std::string::npos;
  EXPECT_TRUE(logged);
  ASSERT_FALSE(d.solves.empty());
  EXPECT_TRUE(d.solves.back().converged);
  EXPECT_LT(d.attachment_error_mm, 0.01);
  ASSERT_EQ(d.bodies.size(), 1u);
  expect_no_inversion_and_volume_kept(d.bodies[0], 0.01);
}

// anatomy.tet_size_mm meshes the small head's body (grey matter) with white matter nested in it.
// By organ (the default) white matter is a region of its own; by material it is meshed with
// grey matter, whose material it shares, unless its material differs. Either way the solve
// converges and no tet inverts.
TEST(DeformPhantom, TetInterfacesFollowOrgansOrOnlyMaterialChanges) {
  struct Case {
    TetInterfaces interfaces;
    const char* white_material;
    bool white_has_tets;
  };
  for (const Case& c :
       {Case{TetInterfaces::organs, "brain", true}, Case{TetInterfaces::materials, "brain", false},
        Case{TetInterfaces::materials, "scalp", true}}) {
    Scene scene = phantasm::testing::load_repository_scene("tests/data/scenes/small-head.yaml");
    scene.anatomy.tet_size_mm = 8.0;
    scene.anatomy.tet_interfaces = c.interfaces;
    scene.deformation.organs[2].material = c.white_material;
    Reporter quiet = Reporter::silent();
    const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
    StageReport report;
    const PhantomDeformation d = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
    std::string materials, mesh;
    for (const std::string& line : report.modelled) {
      if (line.find("materials by tet:") != std::string::npos) materials = line;
      if (line.find("one tet mesh of it") != std::string::npos) mesh = line;
    }
    const std::string what = std::string(to_string(c.interfaces)) + ", white matter of " + c.white_material;
    EXPECT_NE(materials.find("grey_matter"), std::string::npos) << what << ": " << materials;
    EXPECT_EQ(materials.find("white_matter") != std::string::npos, c.white_has_tets)
        << what << ": " << materials;
    EXPECT_EQ(mesh.find("anatomy.tet_interfaces: materials): white_matter") != std::string::npos,
              !c.white_has_tets)
        << what << ": " << mesh;
    ASSERT_FALSE(d.solves.empty());
    EXPECT_TRUE(d.solves.back().converged) << what;
    ASSERT_EQ(d.bodies.size(), 1u);
    expect_no_inversion_and_volume_kept(d.bodies[0], 0.02);
    // Each tet names its organ (index 1 grey matter, 2 white matter), white matter only when it
    // is a region of its own.
    const std::vector<int>& tet_organ = d.bodies[0].tet_organ;
    ASSERT_EQ(tet_organ.size(), static_cast<std::size_t>(d.bodies[0].tets.rows())) << what;
    EXPECT_TRUE(std::all_of(tet_organ.begin(), tet_organ.end(), [](int o) { return o == 1 || o == 2; }));
    EXPECT_EQ(std::count(tet_organ.begin(), tet_organ.end(), 2) > 0, c.white_has_tets) << what;
  }
}

// The shipped breast scene: two paddles close in by 15 mm each in four load steps, the chest
// wall held. Nothing passes a paddle beyond the penalty's give, the paddles carry the load
// (contacts at the end), no tet inverts and the volume is kept (nu 0.49).
TEST(DeformPhantom, PaddlesCompressTheBreastWithoutPassingThroughIt) {
  const Scene scene = phantasm::testing::load_repository_scene("data-synthetic/breast.yaml");
  ASSERT_EQ(scene.deformation.obstacles.size(), 2u);
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  StageReport report;
  const PhantomDeformation d = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
  EXPECT_EQ(report.status, "done");
  ASSERT_EQ(d.solves.size(), 4u);
  EXPECT_GT(d.solves.back().contacts, 4);
  EXPECT_GT(d.solves.back().rank_updates, 0);
  EXPECT_LT(d.obstacle_penetration_mm, 1e-3);
  const Eigen::MatrixX3d& rest = phantom.organs[0].surface->rest_positions();
  const Eigen::MatrixX3d& moved = d.organs[0].surface_mm;
  ASSERT_GT(rest.col(2).maxCoeff(), 50.0); // the paddles end at z = +-43 mm
  ASSERT_LT(rest.col(2).minCoeff(), -50.0);
  EXPECT_LT(d.bodies[0].deformed_mm.col(2).maxCoeff(), 43.0 + 1e-3);
  EXPECT_GT(d.bodies[0].deformed_mm.col(2).minCoeff(), -43.0 - 1e-3);
  // Embedded points of the surface follow the tets; they may bulge past the faceted tet
  // boundary by the patches' height only.
  EXPECT_LT(moved.col(2).maxCoeff(), 45.0);
  // Squeezed from 105 to 86 mm, it bulges sideways and forward (4.4 and 5.0 mm measured); the
  // chest wall side stays.
  std::printf("breast: %.1f mm wider, %.1f mm further forward\n",
              (moved.col(0).maxCoeff() - moved.col(0).minCoeff()) -
                  (rest.col(0).maxCoeff() - rest.col(0).minCoeff()),
              moved.col(1).maxCoeff() - rest.col(1).maxCoeff());
  EXPECT_GT(moved.col(0).maxCoeff() - moved.col(0).minCoeff(),
            rest.col(0).maxCoeff() - rest.col(0).minCoeff() + 3.0);
  EXPECT_GT(moved.col(1).maxCoeff(), rest.col(1).maxCoeff() + 3.0);
  EXPECT_NEAR(moved.col(1).minCoeff(), rest.col(1).minCoeff(), 0.5);
  expect_no_inversion_and_volume_kept(d.bodies[0], 0.01);
}

// The shipped cloth scene, coarser (20 x 20 cells instead of 40 x 40) and for its first 0.4 s
// (24 of its 60 frames), to keep the sanitizer run short: a sheet (solid: false) is simulated as a shell,
// held at two neighbouring corners of its flat start, falling and swinging under gravity. The corners stay,
// the sheet swings down (a physical pendulum of 1 m is near the bottom of its swing at 0.4 s), and the
// membrane barely stretches (E 1 MPa, 0.5 mm thick) except next to the six held points that carry it.
TEST(DeformPhantom, ClothHangsFromItsCornersAsAShell) {
  Scene scene = phantasm::testing::load_repository_scene("data-synthetic/cloth.yaml");
  scene.deformation.frames = 24;
  scene.anatomy.organs[0].shape.cells = Eigen::Vector3i(20, 20, 1);
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  ASSERT_TRUE(phantom.organs[0].sheet);
  StageReport report;
  const PhantomDeformation d = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
  EXPECT_EQ(report.status, "done");
  EXPECT_EQ(d.organs[0].moved_by, "solver");
  EXPECT_TRUE(d.bodies.empty()); // no tets: no displacement-field body
  ASSERT_EQ(d.solves.size(), 24u);
  const TriangleMesh& rest = *phantom.organs[0].sheet;
  const Eigen::MatrixX3d& moved = d.organs[0].surface_mm;
  ASSERT_TRUE(moved.allFinite());
  EXPECT_LT(d.attachment_error_mm, 0.05);
  double worst = 0.0, mean = 0.0;
  int edges = 0;
  for (Eigen::Index f = 0; f < rest.faces.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = rest.faces(f, k), b = rest.faces(f, (k + 1) % 3);
      const double l0 = (rest.vertices.row(a) - rest.vertices.row(b)).norm();
      const double strain = std::abs((moved.row(a) - moved.row(b)).norm() / l0 - 1.0);
      worst = std::max(worst, strain);
      mean += strain;
      ++edges;
    }
  }
  mean /= edges;
  std::printf("cloth: lowest point %.1f mm, edge strain mean %.4f, largest %.4f\n", moved.col(2).minCoeff(),
              mean, worst);
  EXPECT_LT(moved.col(2).minCoeff(), -200.0);
  EXPECT_GT(moved.col(2).minCoeff(), -1100.0); // never longer than the sheet
  EXPECT_LT(mean, 0.005);
  EXPECT_LT(worst, 0.1);
}

// The breast's skin alone, as a closed shell 2 mm thick holding its volume (a fluid-filled
// organ): the paddles flatten it without losing volume. The constraint's volume is the patch
// surface's own (base polyhedron plus bumps), at rest and deformed.
TEST(DeformPhantom, AClosedShellKeepsTheVolumeItEnclosesUnderThePaddles) {
  Scene scene = phantasm::testing::load_repository_scene("data-synthetic/breast.yaml");
  scene.anatomy.organs.resize(1);
  scene.anatomy.organs[0].solid = false;
  scene.anatomy.organs[0].thickness_mm = 2.0;
  scene.anatomy.organs[0].enclosed_volume_tolerance = 0.002;
  resolve_stage_settings(scene); // the organ table and the organs' mechanics follow the edits
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  ASSERT_TRUE(phantom.organs[0].surface);
  const PatchSurface& surface = *phantom.organs[0].surface;

  std::vector<int> vertices;
  std::vector<std::array<int, 3>> triangles;
  std::vector<double> heights;
  const TriangleMesh& base = surface.base_mesh();
  for (Eigen::Index v = 0; v < base.vertices.rows(); ++v)
    vertices.push_back(static_cast<int>(v));
  for (Eigen::Index t = 0; t < base.face_count(); ++t) {
    triangles.push_back({base.faces(t, 0), base.faces(t, 1), base.faces(t, 2)});
    heights.push_back(surface.mean_bump_height(t));
  }
  ASSERT_GT(*std::max_element(heights.begin(), heights.end()), 0.0); // the fit made bumps
  const EnclosedVolume c = enclosed_volume_constraint(vertices, triangles, heights, base.vertices, 1.0);
  EXPECT_NEAR(c.rest_volume_m3, surface.volume(), 1e-9 * surface.volume());
  PatchSurface sheared = surface;
  Eigen::MatrixX3d moved = base.vertices;
  moved.col(0) += 0.3 * moved.col(2);
  moved.col(1) *= 0.8;
  sheared.set_positions(moved);
  EXPECT_NEAR(enclosed_volume(c, moved), sheared.volume(), 1e-9 * surface.volume());

  StageReport report;
  const PhantomDeformation d = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
  EXPECT_EQ(report.status, "done");
  bool mentioned = false;
  for (const std::string& line : report.modelled)
    mentioned = mentioned || line.find("enclosed volume kept within 0.2 %") != std::string::npos;
  EXPECT_TRUE(mentioned);
  const Phantom deformed = deformed_phantom(phantom, d);
  const Eigen::MatrixX3d& after = deformed.organs[0].surface->base_mesh().vertices;
  EXPECT_LT(after.col(2).maxCoeff(), 43.5); // flattened to the paddles (patches may rise above)
  EXPECT_GT(after.col(0).maxCoeff() - after.col(0).minCoeff(),
            base.vertices.col(0).maxCoeff() - base.vertices.col(0).minCoeff() + 1.0);
  std::printf("shell: volume ratio %.5f, x %.2f -> %.2f, y %.2f -> %.2f, z %.2f -> %.2f mm, %d iterations\n",
              deformed.organs[0].surface->volume() / surface.volume(),
              base.vertices.col(0).maxCoeff() - base.vertices.col(0).minCoeff(),
              after.col(0).maxCoeff() - after.col(0).minCoeff(), base.vertices.col(1).maxCoeff(),
              after.col(1).maxCoeff(), base.vertices.col(2).maxCoeff(), after.col(2).maxCoeff(),
              d.solves.back().iterations);
  EXPECT_NEAR(deformed.organs[0].surface->volume() / surface.volume(), 1.0, 0.005);
  // Without the constraint the shell gives up volume under the same paddles.
  scene.anatomy.organs[0].enclosed_volume_tolerance.reset();
  resolve_stage_settings(scene);
  StageReport free_report;
  const Phantom empty =
      deformed_phantom(phantom, deform_phantom(scene.deformation, scene.organs, phantom, free_report, quiet));
  std::printf("empty shell: volume ratio %.5f\n", empty.organs[0].surface->volume() / surface.volume());
  EXPECT_LT(empty.organs[0].surface->volume() / surface.volume(), 0.99);
}

TEST(DeformPhantom, AnEnclosedVolumeOnAnOpenSheetIsAClearError) {
  Scene scene = phantasm::testing::load_repository_scene("data-synthetic/cloth.yaml");
  scene.anatomy.organs[0].shape.cells = Eigen::Vector3i(4, 4, 1);
  scene.anatomy.organs[0].enclosed_volume_tolerance = 0.01;
  resolve_stage_settings(scene);
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  StageReport report;
  try {
    deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cloth: enclosed_volume_tolerance needs a closed surface"),
              std::string::npos)
        << e.what();
  }
}

// Two balls pressed together (tests/data/scenes/two-balls.yaml): with the collision listed
// neither enters the other and the right one is pushed; without it the left one passes in.
TEST(DeformPhantom, CollidingOrgansPressOnEachOtherInsteadOfPassingThrough) {
  Scene scene = phantasm::testing::load_repository_scene("tests/data/scenes/two-balls.yaml");
  ASSERT_EQ(scene.deformation.collisions.size(), 1u);
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  ASSERT_TRUE(phantom.organs[0].solid && phantom.organs[1].solid);
  for (const bool collide : {true, false}) {
    if (!collide) scene.deformation.collisions.clear();
    StageReport report;
    const PhantomDeformation d = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
    EXPECT_EQ(report.status, "done");
    ASSERT_EQ(d.bodies.size(), 2u);
    // How deep the left ball's boundary vertices lie inside the right ball's surface, and back.
    ElasticModel probe;
    std::vector<int> first;
    for (const DeformedBody& body : d.bodies) {
      first.push_back(static_cast<int>(probe.rest_positions_m.rows()));
      probe.rest_positions_m.conservativeResize(probe.rest_positions_m.rows() + body.deformed_mm.rows(), 3);
      probe.rest_positions_m.bottomRows(body.deformed_mm.rows()) = body.deformed_mm;
      const Eigen::MatrixX3i faces = tet_boundary_faces(body.rest_mm, body.tets);
      ContactSurface surface;
      for (Eigen::Index f = 0; f < faces.rows(); ++f) {
        surface.triangles.push_back(
            {first.back() + faces(f, 0), first.back() + faces(f, 1), first.back() + faces(f, 2)});
        for (int c = 0; c < 3; ++c)
          surface.vertices.push_back(first.back() + faces(f, c));
      }
      probe.contact_surfaces.push_back(surface);
    }
    ContactGeometry geometry(probe.contact_surfaces);
    geometry.update(probe.rest_positions_m);
    double deepest = 0.0;
    for (int s = 0; s < 2; ++s)
      for (int v : probe.contact_surfaces[static_cast<std::size_t>(s)].vertices) {
        const SurfaceQuery q = geometry.query(1 - s, probe.rest_positions_m.row(v).transpose());
        if (q.inside) deepest = std::max(deepest, q.distance);
      }
    const double right_leftmost = d.bodies[1].deformed_mm.col(0).minCoeff();
    std::printf("two balls %s: deepest %.4f mm, right ball's leftmost point %.2f mm (rest %.2f)\n",
                collide ? "colliding" : "passing", deepest, right_leftmost,
                d.bodies[1].rest_mm.col(0).minCoeff());
    if (collide) {
      EXPECT_LT(deepest, 0.05);
      EXPECT_GT(right_leftmost, d.bodies[1].rest_mm.col(0).minCoeff() + 2.0);
      // in contact at the end (how many vertices the penalty lets sink in depends on how far
      // the solve converged: 3 at the Newton-finished equilibrium)
      EXPECT_GT(d.solves.back().contacts, 0);
    } else {
      EXPECT_GT(deepest, 4.0);
      EXPECT_NEAR(right_leftmost, d.bodies[1].rest_mm.col(0).minCoeff(), 0.5);
    }
  }
  // Without its load the right ball is not simulated: a collision with it is a clear error.
  scene.deformation.collisions.push_back({{"left", "right"}});
  scene.deformation.loads.pop_back();
  StageReport report;
  try {
    deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(
        message.find("deformation.collisions[0].organs: expected organs simulated as bodies of their own"),
        std::string::npos)
        << message;
    EXPECT_NE(message.find("found 'right'"), std::string::npos) << message;
  }
}
