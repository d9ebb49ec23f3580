// Landmarks are material points of the organ they name: the deepest point of its own material
// lies inside it and outside every organ nested in it, in both states, and moves with that
// material; the extreme points are its own surface vertices.

#include "anatomy/mesh_distance.hpp"
#include "anatomy/phantom.hpp"
#include "anatomy/triangle_mesh.hpp"
#include "core/format.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"
#include "tests/support/patch_bumps.hpp"
#include "voxelize/landmarks.hpp"
#include "voxelize/motion_fields.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <string>

using namespace phantasm;

namespace {

Scene load(const std::string& path) {
  SceneLoadResult result = load_scene(std::string(PHANTASM_SOURCE_DIR) + "/" + path);
  EXPECT_TRUE(result.scene) << format_diagnostics(result.problems);
  return *result.scene;
}

/// Signed distances to an organ's surface and to each organ nested in it, in one state: the
/// clearance of x in the organ's own material (mm; positive inside it, outside the nested ones).
double clearance(const Phantom& phantom, const std::string& organ, const Eigen::Vector3d& x) {
  const Organ& own = *phantom.find(organ);
  double c = -MeshDistance(own.surface->tessellate(0.25)).signed_distance(x);
  for (const Organ& nested : phantom.organs)
    if (nested.inside == organ && nested.surface)
      c = std::min(c, MeshDistance(nested.surface->tessellate(0.25)).signed_distance(x));
  return c;
}

/// A sphere of `radius_mm` on an 80-triangle base; with a spike, one narrow inward bump
/// `spike_mm` deep on the patch facing (1, 1, 1), deeper than the sphere is wide: it passes
/// through the centre and leaves through the far side. Its tessellation then has walls and a tip
/// facing out of the sphere's material beyond that side, so their pseudonormals call the space
/// around the protruding tip inside, and a whole cone beyond the tip (the fold's kind on the
/// Colin head's white matter), while the base mesh and the patch heights tell its side right.
PatchSurface sphere(double radius_mm, double spike_mm = 0.0) {
  TriangleMesh base = unit_icosphere(1);
  base.vertices *= radius_mm;
  PatchSurface surface(base, "sphere");
  if (spike_mm > 0.0) {
    Eigen::Index facing = 0;
    double best = -1.0;
    for (Eigen::Index t = 0; t < base.face_count(); ++t) {
      const double c = surface.frame(t).normal.dot(Eigen::Vector3d(1, 1, 1).normalized());
      if (c > best) best = c, facing = t;
    }
    surface.set_bumps(
        facing, {phantasm::testing::disc_in_triangle(base, facing, {1.0 / 3.0, 1.0 / 3.0}, 0.5, -spike_mm)});
  }
  return surface;
}

Organ organ(const std::string& name, const std::string& inside, PatchSurface surface) {
  Organ o;
  o.name = name;
  o.inside = inside;
  o.surface.emplace(std::move(surface));
  return o;
}

} // namespace

// A shell 4 mm thick (a sphere of 20 mm with one of 16 mm nested in it) whose outer surface
// folds where a spike passes through it: the deepest point of the shell's own material lies in
// the shell, about 2 mm from both of its sides, not in the cone the folded tessellation calls
// inside (where the search climbed out of the organ).
TEST(OrganLandmarks, DeepestPointStaysInItsOrganWhereTheTessellationFolds) {
  Phantom phantom;
  phantom.organs.push_back(organ("shell", "", sphere(20.0, 55.0)));
  phantom.organs.push_back(organ("core", "shell", sphere(16.0)));
  std::vector<std::string> warnings;
  const std::vector<Landmark> landmarks = organ_landmarks(phantom, nullptr, nullptr, 0.5, &warnings);
  EXPECT_TRUE(warnings.empty());
  ASSERT_EQ(landmarks.size(), 14u);
  ASSERT_EQ(landmarks[0].name, "shell_deepest");
  const Eigen::Vector3d x = landmarks[0].reference_mm;
  // Between the spheres (the icosphere's faces lie up to 2 mm inside its vertices' radius)...
  EXPECT_GT(x.norm(), 16.0) << x.transpose();
  EXPECT_LT(x.norm(), 20.0) << x.transpose();
  // ... and away from the spike's line through the centre.
  EXPECT_GT(x.cross(Eigen::Vector3d(1, 1, 1).normalized()).norm(), 4.0) << x.transpose();
}

// An organ whose nested organ fills it has no material of its own: its deepest point is left
// out with a warning, never placed in the nested organ.
TEST(OrganLandmarks, AnOrganFilledByItsNestedOrganHasNoDeepestPointAndAWarning) {
  Phantom phantom;
  phantom.organs.push_back(organ("outer", "", sphere(20.0)));
  phantom.organs.push_back(organ("filling", "outer", sphere(20.0)));
  std::vector<std::string> warnings;
  const std::vector<Landmark> landmarks = organ_landmarks(phantom, nullptr, nullptr, 0.5, &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("outer_deepest"), std::string::npos) << warnings[0];
  ASSERT_EQ(landmarks.size(), 13u);
  for (const Landmark& l : landmarks)
    EXPECT_NE(l.name, "outer_deepest");
  EXPECT_EQ(landmarks[6].name, "filling_deepest");
}

// The deepest-point search evaluates its candidates' clearances in parallel, reading the organs'
// distance structures from both threads: the landmarks are the same bytes on one thread and on
// two (on the folded shell). The candidates' order matters only between exactly equal
// clearances, which this shell does not have.
TEST(OrganLandmarks, AreTheSameOnOneAndTwoThreads) {
  Phantom phantom;
  phantom.organs.push_back(organ("shell", "", sphere(20.0, 55.0)));
  phantom.organs.push_back(organ("core", "shell", sphere(16.0)));
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::vector<Landmark> one = organ_landmarks(phantom, nullptr, nullptr, 0.5, nullptr);
  omp_set_num_threads(2);
  const std::vector<Landmark> two = organ_landmarks(phantom, nullptr, nullptr, 0.5, nullptr);
  omp_set_num_threads(threads);
  ASSERT_EQ(one.size(), two.size());
  for (std::size_t l = 0; l < one.size(); ++l) {
    EXPECT_EQ(one[l].name, two[l].name);
    EXPECT_EQ(one[l].reference_mm, two[l].reference_mm) << one[l].name;
  }
}

// The surfaces are tessellated several at once (an organ's own and nested ones, with the next
// organ's), one per thread: on three levels of nesting (the first organ's step builds all four
// surfaces), the landmarks CSV is the same text on one thread and on two.
TEST(OrganLandmarks, AreTheSameOnOneAndTwoThreadsWhenSurfacesAreBuiltTogether) {
  Phantom phantom;
  phantom.organs.push_back(organ("shell", "", sphere(20.0, 55.0)));
  phantom.organs.push_back(organ("core", "shell", sphere(16.0)));
  phantom.organs.push_back(organ("kernel", "core", sphere(8.0)));
  phantom.organs.push_back(organ("pit", "core", sphere(4.0)));
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::string one = landmarks_csv(organ_landmarks(phantom, nullptr, nullptr, 0.5, nullptr), false);
  omp_set_num_threads(2);
  const std::string two = landmarks_csv(organ_landmarks(phantom, nullptr, nullptr, 0.5, nullptr), false);
  omp_set_num_threads(threads);
  EXPECT_EQ(one.substr(0, one.find('\n')), "name,organ,x_mm,y_mm,z_mm");
  EXPECT_EQ(std::count(one.begin(), one.end(), '\n'), 1 + 7 * 4) << one;
  EXPECT_EQ(one, two);
}

TEST(OrganLandmarks, DeepestPointsLieInTheirOrgansOwnMaterialInBothStates) {
  const Scene scene = load("tests/data/scenes/small-head.yaml");
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  StageReport report;
  const PhantomDeformation d = deform_phantom(scene.deformation, scene.organs, phantom, report, quiet);
  const Phantom moved = deformed_phantom(phantom, d);
  const DeformationMap map(d.bodies, 4.0);
  const std::vector<Landmark> landmarks = organ_landmarks(phantom, &d, &map, 0.5);
  ASSERT_EQ(landmarks.size(), 7u * phantom.organs.size());
  double moved_most = 0.0;
  for (const Landmark& l : landmarks) {
    SCOPED_TRACE(l.name);
    const Organ& organ = *phantom.find(l.organ);
    const std::size_t o = static_cast<std::size_t>(&organ - phantom.organs.data());
    if (l.name == l.organ + "_deepest") {
      // Well inside: the scalp's shell is about 6 mm thick, its deepest point about 3 mm from both sides.
      EXPECT_GT(clearance(phantom, l.organ, l.reference_mm), 2.0);
      EXPECT_GT(clearance(moved, l.organ, l.deformed_mm), 2.0);
      if (d.organs[o].moved_by == "fixed") {
        EXPECT_EQ(l.deformed_mm, l.reference_mm);
      }
      if (d.organs[o].moved_by == "solver") {
        bool exact = false;
        EXPECT_EQ(l.deformed_mm, map.forward(l.reference_mm, &exact));
        EXPECT_TRUE(exact);
      }
      moved_most = std::max(moved_most, (l.deformed_mm - l.reference_mm).norm());
    } else {
      // An extreme point is one of the organ's own surface vertices, in both states.
      const Eigen::MatrixX3d& rest = organ.surface->rest_positions();
      Eigen::Index v = 0;
      (rest.rowwise() - l.reference_mm.transpose()).rowwise().norm().minCoeff(&v);
      EXPECT_EQ(rest.row(v).transpose(), l.reference_mm);
      EXPECT_EQ(d.organs[o].surface_mm.row(v).transpose(), l.deformed_mm);
    }
  }
  EXPECT_GT(moved_most, 0.0); // the grey matter's deepest point moves with the push
}
