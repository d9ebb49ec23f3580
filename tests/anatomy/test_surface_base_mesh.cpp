// Base meshes from a target's own surface: shapes that rays from a centre cannot sample (a
// torus, a folded spheroid, a horseshoe, a thin shell), imported as meshes into a phantom.

#include "anatomy/patch_fit.hpp"
#include "anatomy/phantom.hpp"
#include "anatomy/surface_extraction.hpp"
#include "scene/scene.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <set>
#include <utility>
#include <vector>

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

TEST(SurfaceBaseMesh, ATorusFromALabelVolumeBecomesAnOrganOfGenusOne) {
  // Label 1: a torus (R 30, r 10 mm) on a 1 mm grid, as a label volume file would bring it.
  ImageGrid grid;
  grid.dims = {96, 96, 32};
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(-47.5, -47.5, -15.5);
  std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 0);
  std::size_t i = 0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int x = 0; x < grid.dims.x(); ++x, ++i) {
        const Eigen::Vector3d p = grid.world_from_index(Eigen::Vector3d(x, j, k));
        if (Eigen::Vector2d(p.head<2>().norm() - 30.0, p.z()).norm() < 10.0) labels[i] = 1;
      }
  const auto folder = phantasm::testing::fresh_folder("label-torus");
  phantasm::testing::write_text_file(folder / "labels.nii.gz", "read by the test itself\n");
  const SceneLoadResult loaded = parse_scene("phantasm: 1\nname: ring\nseed: 1\nfield_strength_T: 3.0\ngrid: "
                                             "{field_of_view_mm: 96, voxel_size_mm: 2}\n"
                                             "anatomy:\n  base_mesh_triangles: 320\n  organs:\n"
                                             "    - {name: ring, tissue: white_matter, solid: false, shape: "
                                             "{type: label_volume, file: labels.nii.gz, "
                                             "label: 1}}\n",
                                             folder / "scene.yaml");
  ASSERT_TRUE(loaded.scene) << format_diagnostics(loaded.problems);
  std::map<std::string, ShapeData> files;
  files["ring"].label_grid = grid;
  files["ring"].labels = std::make_shared<const std::vector<std::int32_t>>(labels);
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(loaded.scene->anatomy, files, quiet);
  const Organ& organ = *phantom.find("ring");
  std::printf("ring: %ld patches, fit to the source: max %.3f mm, volume %.1f ml (torus %.1f ml)\n",
              static_cast<long>(organ.surface->patch_count()), organ.fit.source_max_mm,
              organ.surface->volume() / 1000.0, 2 * k_pi * k_pi * 30 * 10 * 10 / 1000.0);
  EXPECT_EQ(euler_characteristic(organ.surface->base_mesh()), 0);
  // The volume is the label's voxels'; they sample the torus within a few per cent.
  EXPECT_NEAR(organ.surface->volume() / organ.target->volume(), 1.0, 1e-6);
  EXPECT_NEAR(organ.surface->volume() / (2 * k_pi * k_pi * 30 * 10 * 10), 1.0, 0.05);
  EXPECT_LT(organ.fit.source_max_mm, 3.0);
}
