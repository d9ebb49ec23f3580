// Base meshes from a target's own surface: shapes that rays from a centre cannot sample (a
// torus, a folded spheroid, a horseshoe, a thin shell), imported as meshes into a phantom.

#include "anatomy/patch_fit.hpp"
#include "anatomy/phantom.hpp"
#include "anatomy/surface_extraction.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <utility>

using namespace phantasm;

namespace {

constexpr double k_pi = 3.14159265358979323846;

/// V - E + F of a closed triangle mesh (2 - 2 genus per component).
long euler_characteristic(const TriangleMesh& mesh) {
  std::set<std::pair<int, int>> edges;
  for (Eigen::Index t = 0; t < mesh.face_count(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.faces(t, k), b = mesh.faces(t, (k + 1) % 3);
      edges.emplace(std::min(a, b), std::max(a, b));
    }
  }
  return static_cast<long>(mesh.vertex_count()) - static_cast<long>(edges.size()) +
         static_cast<long>(mesh.face_count());
}

/// Volume inside a shape by the midpoint rule on a grid of `step_mm` over its bounding cube.
double grid_volume(const ImplicitShape& shape, double step_mm) {
  const double r = 1.01 * shape.bounding_radius();
  const Eigen::Vector3d c = shape.center();
  const int n = static_cast<int>(std::ceil(2.0 * r / step_mm));
  long inside = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d x =
            c + Eigen::Vector3d(-r + (i + 0.5) * step_mm, -r + (j + 0.5) * step_mm, -r + (k + 0.5) * step_mm);
        if (shape.value(x) > 0.0) ++inside;
      }
  return static_cast<double>(inside) * step_mm * step_mm * step_mm;
}

/// Largest number of surface crossings along rays from the shape's centre (sampled every 0.05 mm
/// in the directions of an icosphere).
int most_ray_crossings(const ImplicitShape& shape) {
  const TriangleMesh directions = unit_icosphere(3);
  int most = 0;
  for (Eigen::Index v = 0; v < directions.vertex_count(); ++v) {
    int crossings = 0;
    bool previous = shape.value(shape.center()) > 0.0;
    for (double t = 0.05; t < 1.01 * shape.bounding_radius(); t += 0.05) {
      const bool now = shape.value(shape.center() + t * directions.vertex(v)) > 0.0;
      crossings += now != previous;
      previous = now;
    }
    most = std::max(most, crossings);
  }
  return most;
}

} // namespace

TEST(SurfaceBaseMesh, TheTorusMeshIsAClosedManifoldOfGenusOneWithItsVerticesOnTheTorus) {
  const auto torus = make_torus({1, 2, 3}, 30, 10);
  const TriangleMesh mesh = surface_base_mesh(*torus, 320, 0);
  EXPECT_NO_THROW(check_closed_manifold(mesh, "torus"));
  EXPECT_EQ(euler_characteristic(mesh), 0);
  EXPECT_NEAR(mesh.face_count(), 320, 0.2 * 320);
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    ASSERT_LT(std::abs(torus->value(mesh.vertex(v))), 1e-6) << v;
  // The same arguments give the same bytes.
  const TriangleMesh again = surface_base_mesh(*torus, 320, 0);
  EXPECT_EQ(again.vertices, mesh.vertices);
  EXPECT_EQ(again.faces, mesh.faces);
}

TEST(SurfaceBaseMesh, TheFoldedSpheroidAndTheHorseshoeAreNotStarShapedAndHaveTheirClosedFormVolumes) {
  const auto folded = make_folded_spheroid(40, 0.3, 5, 30, 0.04);
  const auto horseshoe = make_horseshoe(30, 8);
  EXPECT_GE(most_ray_crossings(*folded), 3);
  // The horseshoe's centre (of its bounding box) lies in its gap, outside it.
  EXPECT_LT(horseshoe->value(horseshoe->center()), 0.0);
  EXPECT_GE(most_ray_crossings(*horseshoe), 2);
  EXPECT_NEAR(grid_volume(*folded, 0.5) / folded->volume(), 1.0, 2e-3);
  EXPECT_NEAR(grid_volume(*horseshoe, 0.5) / horseshoe->volume(), 1.0, 2e-3);
  EXPECT_NEAR(grid_volume(*make_torus({0, 0, 0}, 30, 10), 0.5) / (2 * k_pi * k_pi * 30 * 10 * 10), 1.0, 2e-3);
}

TEST(SurfaceBaseMesh, AnImportedTorusMeshBecomesAnOrganOfGenusOne) {
  // A parametric torus of 48 x 16 quads, as a mesh file would bring it.
  TriangleMesh torus;
  const int nu = 48, nv = 16;
  torus.vertices.resize(nu * nv, 3);
  torus.faces.resize(2 * nu * nv, 3);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * k_pi * i / nu, v = 2 * k_pi * j / nv;
      torus.vertices.row(i * nv + j) << (30 + 10 * std::cos(v)) * std::cos(u),
          (30 + 10 * std::cos(v)) * std::sin(u), 10 * std::sin(v);
      const int a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = ((i + 1) % nu) * nv + (j + 1) % nv,
                d = i * nv + (j + 1) % nv;
      torus.faces.row(2 * a) << a, b, c;
      torus.faces.row(2 * a + 1) << a, c, d;
    }
  ASSERT_GT(enclosed_volume(torus), 0.0);
  const auto folder = phantasm::testing::fresh_folder("imported-torus");
  phantasm::testing::write_text_file(folder / "torus.vtp", "read by the test itself\n");
  const SceneLoadResult loaded = parse_scene(
      "phantasm: 1\nname: ring\nseed: 1\nfield_strength_T: 3.0\ngrid: {field_of_view_mm: 96, voxel_size_mm: "
      "2}\n"
      "anatomy:\n  base_mesh_triangles: 160\n  organs:\n"
      "    - {name: ring, tissue: white_matter, solid: false, shape: {type: mesh, file: torus.vtp}}\n",
      folder / "scene.yaml");
  ASSERT_TRUE(loaded.scene) << format_diagnostics(loaded.problems);
  std::map<std::string, ShapeData> files;
  files["ring"].mesh = torus;
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(*loaded.scene, files, quiet);
  for (const char* name : {"ring"}) {
    const Organ& organ = *phantom.find(name);
    EXPECT_EQ(euler_characteristic(organ.surface->base_mesh()), 0) << name;
    EXPECT_NEAR(organ.surface->volume() / enclosed_volume(torus), 1.0, 1e-6) << name;
    EXPECT_LT(organ.fit.hausdorff_mm, 3.0) << name; // 160 patches on a tube of radius 10 mm
    std::printf("%s: %ld patches, fit Hausdorff %.3f mm\n", name,
                static_cast<long>(organ.surface->patch_count()), organ.fit.hausdorff_mm);
  }
}
