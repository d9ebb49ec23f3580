#include "anatomy/mesh_distance.hpp"
#include "anatomy/phantom.hpp"
#include "scene/scene.hpp"

#include <gtest/gtest.h>

#include <map>

using namespace phantasm;

namespace {

const std::string k_scenes = std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/";

Scene scene_of(const std::string& name, std::uint64_t seed = 0, bool keep_seed = true) {
  SceneLoadResult result = load_scene(k_scenes + name + ".yaml");
  EXPECT_TRUE(result.scene) << format_diagnostics(result.problems);
  Scene scene = *result.scene;
  if (!keep_seed) {
    scene.seed = seed;
    resolve_stage_settings(scene);
  }
  return scene;
}

Phantom build(const Scene& scene) {
  Reporter quiet = Reporter::silent();
  return build_phantom(scene.anatomy, {}, quiet);
}

/// Every solid organ: positive tets, dihedral angles of at least 10 degrees; every closed
/// organ's base mesh passes validation (the patch surface constructor checked it).
void expect_quality_tets(const Phantom& phantom) {
  for (const Organ& organ : phantom.organs) {
    if (!organ.solid) continue;
    for (Eigen::Index t = 0; t < organ.solid->tets.rows(); ++t) {
      ASSERT_GT(tet_volume(*organ.solid, t), 0.0) << organ.name << " tet " << t;
    }
    EXPECT_GE(min_dihedral_angle_deg(*organ.solid), 10.0) << organ.name;
    // The patch base vertices are the tet mesh's boundary vertices.
    for (Eigen::Index v = 0; v < organ.surface->base_mesh().vertex_count(); ++v) {
      ASSERT_EQ(organ.surface->base_mesh().vertices.row(v),
                organ.solid->vertices.row(organ.tet_vertex_of_surface_vertex[v]));
    }
  }
}

/// Nested organs do not intersect: on the tessellations, every vertex of a child lies inside its
/// parent and every vertex of the parent outside the child; siblings lie outside each other.
void expect_nesting_without_intersections(const Phantom& phantom) {
  std::map<std::string, TriangleMesh> meshes;
  std::map<std::string, std::unique_ptr<MeshDistance>> distances;
  for (const Organ& organ : phantom.organs) {
    if (!organ.surface) continue;
    meshes[organ.name] = organ.surface->tessellate(1.0);
    distances[organ.name] = std::make_unique<MeshDistance>(meshes[organ.name]);
  }
  auto all_inside = [&](const std::string& inner, const std::string& outer) {
    const TriangleMesh& mesh = meshes.at(inner);
    for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
      if (distances.at(outer)->signed_distance(mesh.vertex(v)) >= 0.0) return false;
    }
    return true;
  };
  auto all_outside = [&](const std::string& a, const std::string& b) {
    const TriangleMesh& mesh = meshes.at(a);
    for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
      if (distances.at(b)->signed_distance(mesh.vertex(v)) <= 0.0) return false;
    }
    return true;
  };
  for (const Organ& organ : phantom.organs) {
    if (organ.inside.empty() || !organ.surface) continue;
    EXPECT_TRUE(all_inside(organ.name, organ.inside)) << organ.name << " leaves " << organ.inside;
    EXPECT_TRUE(all_outside(organ.inside, organ.name)) << organ.inside << " enters " << organ.name;
    for (const Organ& sibling : phantom.organs) {
      if (&sibling == &organ || sibling.inside != organ.inside || !sibling.surface) continue;
      EXPECT_TRUE(all_outside(organ.name, sibling.name)) << organ.name << " meets " << sibling.name;
    }
  }
}

void expect_volumes_ml(const Phantom& phantom,
                       const std::map<std::string, std::pair<double, double>>& ranges) {
  for (const auto& [name, range] : ranges) {
    const Organ* organ = phantom.find(name);
    ASSERT_NE(organ, nullptr) << name;
    const double ml = organ->surface->volume() / 1000.0;
    EXPECT_GE(ml, range.first) << name;
    EXPECT_LE(ml, range.second) << name;
  }
}

} // namespace

// Volumes enclose nested organs (a skull's volume includes the brain).
TEST(ProceduralPhantom, HeadOrgansAreNestedWithPlausibleVolumesAndQualityTets) {
  const Phantom head = build(scene_of("head"));
  expect_quality_tets(head);
  expect_nesting_without_intersections(head);
  expect_volumes_ml(head, {{"scalp", {1800, 2900}},
                           {"skull", {1500, 2400}},
                           {"csf", {1200, 1900}},
                           {"grey_matter", {1000, 1650}},
                           {"white_matter", {750, 1300}},
                           {"ventricle_left", {3, 15}},
                           {"ventricle_right", {3, 15}}});
}

TEST(ProceduralPhantom, AbdomenOrgansAreNestedWithPlausibleVolumesAndQualityTets) {
  const Phantom abdomen = build(scene_of("abdomen"));
  expect_quality_tets(abdomen);
  expect_nesting_without_intersections(abdomen);
  expect_volumes_ml(abdomen, {{"liver", {550, 2000}},
                              {"spleen", {80, 350}},
                              {"kidney_right", {50, 220}},
                              {"kidney_left", {50, 220}},
                              {"medulla_right", {10, 50}},
                              {"medulla_left", {10, 50}},
                              {"vertebra", {50, 300}}});
}

TEST(ProceduralPhantom, BreastOrgansAreNestedWithPlausibleVolumesAndQualityTets) {
  const Phantom breast = build(scene_of("breast"));
  expect_quality_tets(breast);
  expect_nesting_without_intersections(breast);
  expect_volumes_ml(breast, {{"adipose", {400, 1500}}, {"fibroglandular", {50, 300}}});
}

TEST(ProceduralPhantom, TwistingBarAndClothHaveTheirBenchmarkSizes) {
  const Phantom bar = build(scene_of("bar"));
  ASSERT_TRUE(bar.organs.at(0).solid);
  EXPECT_EQ(bar.organs[0].solid->vertices.rows(), 1421);
  EXPECT_EQ(bar.organs[0].solid->tets.rows(), 5040);
  expect_quality_tets(bar);
  EXPECT_NEAR(bar.organs[0].surface->volume(), 60.0 * 60.0 * 280.0, 1e-6);
  const Phantom cloth = build(scene_of("cloth"));
  ASSERT_TRUE(cloth.organs.at(0).sheet);
  EXPECT_EQ(cloth.organs[0].sheet->vertex_count(), 41 * 41);
  EXPECT_EQ(cloth.organs[0].sheet->face_count(), 2 * 40 * 40);
  EXPECT_FALSE(cloth.organs[0].surface);
}
