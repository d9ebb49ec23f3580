// Landmarks are material points of the organ they name: the deepest point of its own material
// lies inside it and outside every organ nested in it, in both states, and moves with that
// material; the extreme points are its own surface vertices.

#include "anatomy/mesh_distance.hpp"
#include "anatomy/phantom.hpp"
#include "core/format.hpp"
#include "geometry/triangle_mesh.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"
#include "tests/support/patch_bumps.hpp"
#include "voxelize/dense_landmarks.hpp"
#include "voxelize/landmarks.hpp"
#include "voxelize/motion_fields.hpp"
#include "voxelize/voxelize_phantom.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <map>
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

/// The small head test scene, built and deformed.
struct SmallHead {
  Scene scene;
  Phantom phantom;
  PhantomDeformation deformation;
  Phantom moved;
};

SmallHead deformed_small_head() {
  SmallHead head;
  head.scene = load("tests/data/scenes/small-head.yaml");
  Reporter quiet = Reporter::silent();
  head.phantom = build_phantom(head.scene.anatomy, {}, quiet);
  StageReport report;
  head.deformation = deform_phantom(head.scene.deformation, head.scene.organs, head.phantom, report, quiet);
  head.moved = deformed_phantom(head.phantom, head.deformation);
  return head;
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
  const SmallHead head = deformed_small_head();
  const Phantom &phantom = head.phantom, &moved = head.moved;
  const PhantomDeformation& d = head.deformation;
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

namespace {

/// A 1 mm grid over x in [x_low, x_high], y and z in [-25, 25] (voxel centres on whole mm), its
/// labels by radius: 2 (the core) within core_mm of the origin, 1 (the shell) out to shell_mm.
struct LabelledSpheres {
  ImageGrid grid;
  std::vector<std::int32_t> labels;
};

LabelledSpheres labelled_spheres(int x_low, int x_high, double core_mm, double shell_mm) {
  LabelledSpheres out;
  out.grid.dims = Eigen::Vector3i(x_high - x_low + 1, 51, 51);
  out.grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(x_low, -25.0, -25.0);
  out.labels.resize(static_cast<std::size_t>(out.grid.voxel_count()));
  for (int k = 0; k < out.grid.dims.z(); ++k)
    for (int j = 0; j < out.grid.dims.y(); ++j)
      for (int i = 0; i < out.grid.dims.x(); ++i) {
        const double r = out.grid.world_from_index(Eigen::Vector3d(i, j, k)).norm();
        out.labels[voxel_index(out.grid.dims, i, j, k)] = r < core_mm ? 2 : r < shell_mm ? 1 : 0;
      }
  return out;
}

/// Every organ the labels can tell takes its depth from them (these spheres carry no bumps).
constexpr double k_always = std::numeric_limits<double>::infinity();

bool voxel_centre(const ImageGrid& grid, const Eigen::Vector3d& x) {
  const Eigen::Vector3d ijk = grid.index_from_world(x);
  return (ijk - ijk.array().round().matrix()).norm() < 1e-9;
}

} // namespace

// With the reference labels, an organ inside the grid takes its deepest point from the distance
// transform of its label (a voxel centre: the core's is the centre voxel); an organ the grid cuts
// (the shell, beyond x = 12) takes it from the tessellations, the same bits as without labels.
// On one and two threads alike.
TEST(OrganLandmarks, AnOrganTheGridCutsTakesItsDepthFromTheSurfacesOneInsideFromItsLabel) {
  Phantom phantom;
  phantom.organs.push_back(organ("shell", "", sphere(20.0)));
  phantom.organs.push_back(organ("core", "shell", sphere(8.0)));
  const LabelledSpheres labelled = labelled_spheres(-25, 12, 6.5, 17.0);
  const ReferenceLabels labels{&labelled.grid, &labelled.labels, k_always};
  const std::vector<Landmark> surfaces = organ_landmarks(phantom, nullptr, nullptr, 0.5);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::vector<Landmark> one = organ_landmarks(phantom, nullptr, nullptr, 0.5, nullptr, {}, labels);
  omp_set_num_threads(2);
  const std::vector<Landmark> two = organ_landmarks(phantom, nullptr, nullptr, 0.5, nullptr, {}, labels);
  omp_set_num_threads(threads);
  ASSERT_EQ(one.size(), 14u);
  EXPECT_EQ(landmarks_csv(one, false), landmarks_csv(two, false));
  ASSERT_EQ(one[0].name, "shell_deepest");
  EXPECT_EQ(one[0].reference_mm, surfaces[0].reference_mm);
  EXPECT_FALSE(voxel_centre(labelled.grid, one[0].reference_mm)) << one[0].reference_mm.transpose();
  ASSERT_EQ(one[7].name, "core_deepest");
  EXPECT_TRUE(voxel_centre(labelled.grid, one[7].reference_mm)) << one[7].reference_mm.transpose();
  EXPECT_EQ(one[7].reference_mm, Eigen::Vector3d::Zero());

  // The whole shell on the grid: now both from the labels. The shell's label voxels deepest in
  // it lie 5.5 mm from the core's label and from the grid's outside, all in its material.
  const LabelledSpheres whole = labelled_spheres(-25, 25, 6.5, 17.0);
  const std::vector<Landmark> both =
      organ_landmarks(phantom, nullptr, nullptr, 0.5, nullptr, {}, {&whole.grid, &whole.labels, k_always});
  EXPECT_TRUE(voxel_centre(whole.grid, both[0].reference_mm)) << both[0].reference_mm.transpose();
  EXPECT_GT(both[0].reference_mm.norm(), 8.0);
  EXPECT_LT(both[0].reference_mm.norm(), 17.0);
  EXPECT_EQ(both[7].reference_mm, Eigen::Vector3d::Zero());
  // By default a surface without bumps in a box of 50 000 voxels searches its tessellation,
  // the cheaper way: the same landmarks as without labels.
  EXPECT_EQ(
      landmarks_csv(
          organ_landmarks(phantom, nullptr, nullptr, 0.5, nullptr, {}, {&whole.grid, &whole.labels}), false),
      landmarks_csv(surfaces, false));
}

// Labels whose voxels have no centre in their organ's own material (the core's drawn where only
// the shell is, the shell's inside the core): the labels cannot tell, and the tessellations give
// both deepest points.
TEST(OrganLandmarks, ALabelOutsideItsOrgansMaterialFallsBackToTheSurfaces) {
  Phantom phantom;
  phantom.organs.push_back(organ("shell", "", sphere(20.0)));
  phantom.organs.push_back(organ("core", "shell", sphere(8.0)));
  LabelledSpheres labelled = labelled_spheres(-25, 25, 6.5, 17.0);
  for (int k = 0; k < labelled.grid.dims.z(); ++k)
    for (int j = 0; j < labelled.grid.dims.y(); ++j)
      for (int i = 0; i < labelled.grid.dims.x(); ++i) {
        const double r = labelled.grid.world_from_index(Eigen::Vector3d(i, j, k)).norm();
        labelled.labels[voxel_index(labelled.grid.dims, i, j, k)] = r < 6.5 ? 1 : r > 9.0 && r < 17.0 ? 2 : 0;
      }
  const std::vector<Landmark> surfaces = organ_landmarks(phantom, nullptr, nullptr, 0.5);
  const std::vector<Landmark> swapped = organ_landmarks(phantom, nullptr, nullptr, 0.5, nullptr, {},
                                                        {&labelled.grid, &labelled.labels, k_always});
  ASSERT_EQ(swapped.size(), surfaces.size());
  EXPECT_EQ(landmarks_csv(swapped, false), landmarks_csv(surfaces, false));
}

// On the small head voxelized at 2 mm, the deepest points from the labels are material points
// of their organs in both states, moved exactly by the map, and as deep as the tessellations'
// (within 0.5 mm) to within a voxel's diagonal; each is a voxel centre (every organ lies within
// the grid).
TEST(OrganLandmarks, DeepestPointsFromTheLabelsAreAsDeepAsFromTheSurfacesToWithinAVoxel) {
  const SmallHead head = deformed_small_head();
  const Phantom &phantom = head.phantom, &moved = head.moved;
  const PhantomDeformation& d = head.deformation;
  const ImageGrid grid = head.scene.grid.grid();
  StageReport report;
  Reporter quiet = Reporter::silent();
  const VoxelizedPhantom voxelized =
      voxelize_phantom(head.scene.voxelization, head.scene.organs, grid, phantom, &moved, &d, report, quiet);
  const DeformationMap map(d.bodies, 2.0 * grid.spacing_mm.maxCoeff());
  const std::vector<Landmark> surfaces = organ_landmarks(phantom, &d, &map, 0.5);
  ASSERT_EQ(voxelized.landmarks.size(), surfaces.size());
  const double diagonal = grid.spacing_mm.norm();
  for (std::size_t l = 0; l < surfaces.size(); ++l) {
    const Landmark& from_labels = voxelized.landmarks[l];
    if (from_labels.name != from_labels.organ + "_deepest") continue;
    SCOPED_TRACE(from_labels.name);
    ASSERT_EQ(from_labels.name, surfaces[l].name);
    EXPECT_TRUE(voxel_centre(grid, from_labels.reference_mm)) << from_labels.reference_mm.transpose();
    const double depth = clearance(phantom, from_labels.organ, from_labels.reference_mm);
    EXPECT_GT(depth, 0.0);
    EXPECT_GT(clearance(moved, from_labels.organ, from_labels.deformed_mm), 0.0);
    EXPECT_GT(depth, clearance(phantom, from_labels.organ, surfaces[l].reference_mm) - diagonal);
    const Organ& organ = *phantom.find(from_labels.organ);
    const auto o = static_cast<std::size_t>(&organ - phantom.organs.data());
    if (d.organs[o].moved_by == "fixed") {
      EXPECT_EQ(from_labels.deformed_mm, from_labels.reference_mm);
    }
    if (d.organs[o].moved_by == "solver") {
      bool exact = false;
      EXPECT_EQ(from_labels.deformed_mm, map.forward(from_labels.reference_mm, &exact));
      EXPECT_TRUE(exact);
    }
  }
}

namespace {

/// A shell (a sphere of 20 mm) that stays, around a core (a sphere of 12 mm) the solver moves:
/// one body, the cube [-30, 30]^3 in six tets that all hold the core's material, moved by an
/// affine map.
struct MovedCore {
  Phantom phantom;
  PhantomDeformation deformation;
  Eigen::Matrix3d A;
  Eigen::Vector3d b = Eigen::Vector3d(1.5, -0.5, 0.8);
};

MovedCore moved_core() {
  MovedCore c;
  c.phantom.organs.push_back(organ("shell", "", sphere(20.0)));
  c.phantom.organs.push_back(organ("core", "shell", sphere(12.0)));
  c.A << 1.1, 0.05, 0.0, 0.0, 0.95, 0.02, 0.03, 0.0, 1.0;
  DeformedBody body;
  body.organ = "core";
  body.rest_mm.resize(8, 3);
  body.deformed_mm.resize(8, 3);
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d x =
        60.0 * Eigen::Vector3d(k & 1, (k >> 1) & 1, (k >> 2) & 1) - Eigen::Vector3d::Constant(30.0);
    body.rest_mm.row(k) = x.transpose();
    body.deformed_mm.row(k) = (c.A * x + c.b).transpose();
  }
  const int axes[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  body.tets.resize(6, 4);
  for (int t = 0; t < 6; ++t) {
    const int first = 1 << axes[t][0], second = first | (1 << axes[t][1]);
    body.tets.row(t) << 0, first, second, 7;
  }
  body.tet_organ.assign(6, 1);
  c.deformation.bodies.push_back(body);
  c.deformation.organs.push_back({"shell", "fixed", {}, {}});
  c.deformation.organs.push_back({"core", "solver", {}, {}});
  return c;
}

} // namespace

// The deepest points' candidates from the labels, given back to organ_landmarks, give the
// landmarks the labels give: the first candidate where the map moves its surroundings exactly
// with the organ (the moved core's first; the shell stays while the core's tets move it, so none
// of its candidates is exact for it and it keeps its first), else the first. A first candidate
// the map does not reach gives way to the next; with none exact, the first stays.
TEST(OrganLandmarks, FromGivenCandidatesTheDeepestIsTheFirstTheMapMovesExactlyElseTheFirst) {
  MovedCore c = moved_core();
  // The surfaces' moved vertices (the extreme points read them): the shell's where they were,
  // the core's by the affine motion of its tets.
  c.deformation.organs[0].surface_mm = c.phantom.organs[0].surface->rest_positions();
  c.deformation.organs[1].surface_mm =
      ((c.phantom.organs[1].surface->rest_positions() * c.A.transpose()).rowwise() + c.b.transpose()).eval();
  const DeformationMap map(c.deformation.bodies, 4.0);
  const LabelledSpheres labelled = labelled_spheres(-25, 25, 6.5, 17.0);
  const ReferenceLabels labels{&labelled.grid, &labelled.labels, k_always};
  const DeepestCandidates candidates = deepest_candidates(c.phantom, labels);
  ASSERT_EQ(candidates.size(), 2u);
  EXPECT_EQ(candidates[0].size(), 65u); // the shell's deepest and 64 more, a step apart
  ASSERT_GT(candidates[1].size(), 1u);
  const std::vector<Landmark> from_labels =
      organ_landmarks(c.phantom, &c.deformation, &map, 0.5, nullptr, {}, labels);
  const std::vector<Landmark> given =
      organ_landmarks(c.phantom, &c.deformation, &map, 0.5, nullptr, {}, labels, &candidates);
  EXPECT_EQ(landmarks_csv(given, false), landmarks_csv(from_labels, false));
  EXPECT_EQ(landmarks_csv(given, true), landmarks_csv(from_labels, true));
  ASSERT_EQ(given.size(), 14u);
  ASSERT_EQ(given[0].name, "shell_deepest");
  EXPECT_EQ(given[0].reference_mm, candidates[0][0]);
  ASSERT_EQ(given[7].name, "core_deepest");
  EXPECT_EQ(given[7].reference_mm, candidates[1][0]);
  // Without a map the labels give the first candidates too.
  EXPECT_EQ(landmarks_csv(organ_landmarks(c.phantom, nullptr, nullptr, 0.5, nullptr, {}, labels, &candidates),
                          false),
            landmarks_csv(organ_landmarks(c.phantom, nullptr, nullptr, 0.5, nullptr, {}, labels), false));

  // Just past the moved body's face: the map extends the motion there, not exact.
  const Eigen::Vector3d far(0.0, 0.0, 31.0);
  DeepestCandidates unreached = candidates;
  unreached[1].insert(unreached[1].begin(), far);
  EXPECT_EQ(
      organ_landmarks(c.phantom, &c.deformation, &map, 0.5, nullptr, {}, labels, &unreached)[7].reference_mm,
      candidates[1][0]);
  DeepestCandidates none_exact = candidates;
  none_exact[1] = {far, far + Eigen::Vector3d(0.0, 5.0, 0.0)};
  EXPECT_EQ(
      organ_landmarks(c.phantom, &c.deformation, &map, 0.5, nullptr, {}, labels, &none_exact)[7].reference_mm,
      far);
}

// Dense landmarks: as many as asked per organ, each in its organ's own material (the shell's
// outside the core: signed distances to tessellations, not the patches' test the points were
// picked with), spread over it, the moved core's carried exactly by the map (the affine motion
// of its tets), the shell's unchanged.
TEST(DenseLandmarks, AreMaterialPointsSpreadOverTheirOrgansAndExactInBothStates) {
  const MovedCore c = moved_core();
  const DeformationMap map(c.deformation.bodies, 4.0);
  std::vector<std::string> warnings;
  const std::vector<Landmark> points = dense_landmarks(c.phantom, &c.deformation, &map, 150, 7, &warnings);
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  ASSERT_EQ(points.size(), 300u);
  // The clearance in each organ's own material (as clearance() above, each surface tessellated once).
  const MeshDistance shell(c.phantom.organs[0].surface->tessellate(0.25)),
      core(c.phantom.organs[1].surface->tessellate(0.25));
  const std::map<std::string, std::function<double(const Eigen::Vector3d&)>> material = {
      {"shell",
       [&](const Eigen::Vector3d& x) {
         return std::min(-shell.signed_distance(x), core.signed_distance(x));
       }},
      {"core", [&](const Eigen::Vector3d& x) { return -core.signed_distance(x); }}};
  for (const std::string organ_name : {"shell", "core"}) {
    SCOPED_TRACE(organ_name);
    Eigen::AlignedBox3d box;
    int count = 0;
    for (const Landmark& l : points) {
      if (l.organ != organ_name) continue;
      ++count;
      box.extend(l.reference_mm);
      EXPECT_EQ(l.name.rfind(organ_name + "_point_", 0), 0u) << l.name;
      EXPECT_GT(material.at(organ_name)(l.reference_mm), 0.0) << l.reference_mm.transpose();
      if (organ_name == "shell") {
        EXPECT_EQ(l.deformed_mm, l.reference_mm);
      } else {
        bool exact = false;
        EXPECT_EQ(l.deformed_mm, map.forward(l.reference_mm, &exact));
        EXPECT_TRUE(exact);
        EXPECT_LT((l.deformed_mm - (c.A * l.reference_mm + c.b)).norm(), 1e-9);
      }
    }
    EXPECT_EQ(count, 150);
    // The icosahedral spheres' faces lie within 20 % of their vertices' radius: the points span
    // at least 70 % of the organ's width along every axis.
    const double radius = organ_name == std::string("shell") ? 20.0 : 12.0;
    EXPECT_GT(box.sizes().minCoeff(), 0.7 * 2.0 * radius) << box.sizes().transpose();
  }
}

// The same phantom, count and seed give the same bytes, on one thread and on two; another seed
// other points; a count of 0 none.
TEST(DenseLandmarks, AreTheSameBytesForTheSameSeedOnAnyThreadCount) {
  const MovedCore c = moved_core();
  const DeformationMap map(c.deformation.bodies, 4.0);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::string one = landmarks_csv(dense_landmarks(c.phantom, &c.deformation, &map, 100, 3), true);
  omp_set_num_threads(2);
  const std::string two = landmarks_csv(dense_landmarks(c.phantom, &c.deformation, &map, 100, 3), true);
  omp_set_num_threads(threads);
  EXPECT_EQ(std::count(one.begin(), one.end(), '\n'), 1 + 200);
  EXPECT_EQ(one, two);
  EXPECT_NE(one, landmarks_csv(dense_landmarks(c.phantom, &c.deformation, &map, 100, 4), true));
  EXPECT_TRUE(dense_landmarks(c.phantom, &c.deformation, &map, 0, 3).empty());
}

// An organ filled by the one nested in it has no own material: no dense landmark of it, and a
// note saying so; the nested organ still gets its points.
TEST(DenseLandmarks, AnOrganWithoutMaterialOfItsOwnGetsNoneAndANote) {
  Phantom phantom;
  phantom.organs.push_back(organ("outer", "", sphere(20.0)));
  phantom.organs.push_back(organ("filling", "outer", sphere(20.0)));
  std::vector<std::string> warnings;
  const std::vector<Landmark> points = dense_landmarks(phantom, nullptr, nullptr, 50, 1, &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("outer: 0 of the 50"), std::string::npos) << warnings[0];
  ASSERT_EQ(points.size(), 50u);
  for (const Landmark& l : points) {
    EXPECT_EQ(l.organ, "filling");
    EXPECT_EQ(l.deformed_mm, l.reference_mm);
  }
}
