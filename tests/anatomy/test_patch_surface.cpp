#include "anatomy/patch_surface.hpp"
#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "geometry/triangle_mesh.hpp"
#include "tests/support/finite_difference.hpp"
#include "tests/support/patch_bumps.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>

using namespace phantasm;
using namespace phantasm::testing;

namespace {

TriangleMesh sphere_mesh(int level, double radius) {
  TriangleMesh mesh = unit_icosphere(level);
  mesh.vertices *= radius;
  return mesh;
}

/// A sphere base mesh whose patches carry a few bumps of both signs.
PatchSurface bumpy_sphere() {
  PatchSurface surface(sphere_mesh(1, 30.0), "bumpy sphere");
  std::mt19937 random(7);
  std::uniform_real_distribution<double> amplitude(-1.0, 1.0);
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t) {
    const TriangleMesh& base = surface.base_mesh();
    const PatchBump centre = disc_in_triangle(base, t, {1.0 / 3.0, 1.0 / 3.0}, 0.9, amplitude(random));
    const PatchBump side = disc_in_triangle(base, t, {0.5, 0.25}, 0.5, amplitude(random));
    surface.set_bumps(t, {centre, side});
  }
  return surface;
}

} // namespace

TEST(PatchSurface, GradientMatchesCentralFiniteDifferences) {
  PatchSurface surface = bumpy_sphere();
  // Move the vertices so the frames are not the rest frames.
  Eigen::MatrixX3d moved = surface.base_mesh().vertices;
  moved.col(0) *= 1.2;
  moved.col(2) *= 0.9;
  surface.set_positions(moved);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> coordinate(0.05, 0.6), height(-1.0, 1.0);
  const double h = 1e-5;
  for (Eigen::Index t = 0; t < surface.patch_count(); t += 7) {
    const PatchFrame f = surface.frame(t);
    for (int sample = 0; sample < 5; ++sample) {
      const double u = coordinate(random), v = 0.5 * coordinate(random);
      const Eigen::Vector3d x = f.origin + u * f.edge1 + v * f.edge2 + height(random) * f.normal;
      const Eigen::Vector3d numeric =
          central_difference_gradient([&](const Eigen::Vector3d& y) { return surface.value(t, y); }, x, h);
      // Scale floor 1: the patch function is a distance in mm, its gradient near unit length.
      EXPECT_TRUE(matches_finite_differences(surface.gradient(t, x), numeric, 1e-6, 1.0)) << "triangle " << t;
    }
  }
}

TEST(PatchSurface, SurfacePointsAreRootsOfThePatchFunction) {
  const PatchSurface surface = bumpy_sphere();
  for (Eigen::Index t = 0; t < surface.patch_count(); t += 5) {
    for (double u : {0.1, 0.3, 0.5}) {
      const Eigen::Vector3d p = surface.surface_point(t, u, 0.3);
      EXPECT_NEAR(surface.value(t, p), 0.0, 1e-12);
    }
  }
}

TEST(PatchSurface, GeneralQuadricsWithHeightTermsAreSolvedByNewton) {
  Quadric q;
  q.c = {1.0, 0.3, -0.2, 0.5, -1.0, 0.4, -1.0, 0.25, -0.6, -2.0}; // every term, so each one is checked
  const Eigen::Vector3d p(0.2, -0.1, 0.3);
  const Eigen::Vector3d numeric =
      central_difference_gradient([&](const Eigen::Vector3d& x) { return q.value(x); }, p, 1e-6);
  EXPECT_TRUE(matches_finite_differences(q.gradient(p), numeric, 1e-8, 1.0));
}

// PatchSurface::height computes each bump's term once and solves g(h) = -h + sum of the terms:
// right only while a bump's quadric has no w terms (its Q the same at every height, g's slope -1).
TEST(PatchSurface, BumpQuadricsHaveNoHeightTerms) {
  const PatchSurface surface = bumpy_sphere();
  std::size_t checked = 0;
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t)
    for (const PatchBump& bump : surface.bumps(t)) {
      const Quadric q = bump.quadric();
      for (const std::size_t w_term : {3, 7, 8, 9})
        ASSERT_EQ(q.c[w_term], 0.0) << "triangle " << t << ", coefficient " << w_term;
      ++checked;
    }
  EXPECT_GT(checked, 0u);
}

// More bumps at one point than height() keeps on its stack (64): the rest go to its overflow
// list, and the height is still -0 + the terms summed in the bumps' order.
TEST(PatchSurface, HeightSumsEveryTermWhenManyBumpsOverlap) {
  PatchSurface surface(sphere_mesh(1, 30.0), "stacked bumps");
  const TriangleMesh& base = surface.base_mesh();
  std::vector<PatchBump> bumps;
  for (int b = 0; b < 100; ++b)
    bumps.push_back(disc_in_triangle(base, 0, {1.0 / 3.0, 1.0 / 3.0}, 0.5 + 0.004 * b, 0.01 * (1 + b % 7)));
  surface.set_bumps(0, bumps);
  const Eigen::Vector2d at(0.3, 0.35);
  double h = -0.0;
  for (const PatchBump& bump : bumps) {
    const double q = bump.quadric().value(Eigen::Vector3d(at.x(), at.y(), 0.0));
    if (q > 0.0) h += bump.amplitude_mm * q * q * q;
  }
  EXPECT_GT(h, 0.65); // every bump reaches the point: 100 terms of 0.01-0.07 x Q^3
  EXPECT_EQ(surface.height(0, at.x(), at.y()), h);
}

TEST(PatchSurface, NeighbouringPatchTessellationsShareTheirBoundary) {
  const PatchSurface surface = bumpy_sphere();
  const TriangleMesh tessellation = surface.tessellate(0.05);
  // Watertight: every edge of the tessellation is shared by exactly two triangles, in opposite
  // directions, so neighbouring patches meet without gaps or T-junctions.
  std::map<std::pair<int, int>, int> directed;
  for (Eigen::Index t = 0; t < tessellation.face_count(); ++t) {
    for (int k = 0; k < 3; ++k)
      ++directed[{tessellation.faces(t, k), tessellation.faces(t, (k + 1) % 3)}];
  }
  for (const auto& [edge, count] : directed) {
    ASSERT_EQ(count, 1);
    ASSERT_EQ(directed.count({edge.second, edge.first}), 1u)
        << "open edge " << edge.first << "-" << edge.second;
  }
  EXPECT_NO_THROW(check_closed_manifold(tessellation, "tessellation"));
  // Each patch evaluated on its own gives the same points along a shared edge (the straight
  // base edge): gap below 1e-9 of the edge length.
  const TriangleMesh& base = surface.base_mesh();
  const int n = 16;
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t) {
    const Eigen::Vector3d a = base.vertex(base.faces(t, 0)), b = base.vertex(base.faces(t, 1));
    for (int i = 0; i <= n; ++i) {
      const Eigen::Vector3d p = surface.surface_point(t, double(i) / n, 0.0);
      const Eigen::Vector3d on_edge = a + (double(i) / n) * (b - a);
      EXPECT_LT((p - on_edge).norm(), 1e-9 * (b - a).norm());
    }
  }
}

TEST(PatchSurface, TessellationStaysWithinTheRequestedDeviation) {
  const PatchSurface surface = bumpy_sphere();
  for (double tolerance : {0.2, 0.05, 0.02}) {
    TessellationStats stats;
    const TriangleMesh mesh = surface.tessellate(tolerance, &stats);
    EXPECT_LE(stats.max_deviation_mm, tolerance);
    // The tessellation's volume converges to the exact patch volume as the tolerance shrinks.
    const double error = std::abs(enclosed_volume(mesh) - surface.volume()) / surface.volume();
    EXPECT_LT(error, 2e-3 * tolerance / 0.01) << tolerance;
  }
}

TEST(PatchSurface, ExactBumpVolumeMatchesAFineTessellation) {
  PatchSurface surface = bumpy_sphere();
  const double fine = enclosed_volume(surface.tessellate(1e-4));
  EXPECT_NEAR(surface.volume(), fine, 1e-6 * fine);
  // Still exact after the vertices move (bumps follow their triangles affinely).
  Eigen::MatrixX3d moved = surface.base_mesh().vertices;
  moved.col(1) *= 1.3;
  surface.set_positions(moved);
  const double moved_fine = enclosed_volume(surface.tessellate(1e-4));
  EXPECT_NEAR(surface.volume(), moved_fine, 1e-6 * moved_fine);
}

TEST(PatchSurface, AreaOfABumplessSphereMeshIsItsTriangleArea) {
  const PatchSurface plain(sphere_mesh(2, 10.0), "sphere");
  EXPECT_NEAR(plain.area(0.01), surface_area(plain.base_mesh()), 1e-9);
  // Bumps add area: a bumpy surface has more than its base mesh.
  const PatchSurface bumpy = bumpy_sphere();
  EXPECT_GT(bumpy.area(0.01), surface_area(bumpy.base_mesh()));
}

TEST(PatchSurface, PlainSphereVolumeErrorFallsAtOrderTwo) {
  const double radius = 10.0, exact = 4.0 / 3.0 * M_PI * radius * radius * radius;
  std::vector<double> errors, sizes;
  for (int level = 1; level <= 5; ++level) {
    const PatchSurface surface(sphere_mesh(level, radius), "sphere");
    errors.push_back(std::abs(surface.volume() - exact) / exact);
    sizes.push_back(mean_edge_length(surface.base_mesh()));
  }
  for (std::size_t i = 1; i < errors.size(); ++i) {
    const double order = std::log(errors[i - 1] / errors[i]) / std::log(sizes[i - 1] / sizes[i]);
    EXPECT_NEAR(order, 2.0, 0.1) << "level " << i + 1;
  }
}

TEST(PatchSurface, ClippingPlanesAreSharedByNeighboursAndContainTheirEdge) {
  const PatchSurface surface = bumpy_sphere();
  const TriangleMesh& base = surface.base_mesh();
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t) {
    const auto planes = surface.clipping_planes(t);
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = base.vertex(base.faces(t, k)), b = base.vertex(base.faces(t, (k + 1) % 3));
      EXPECT_NEAR(planes[static_cast<std::size_t>(k)].signed_distance(a), 0.0, 1e-9);
      EXPECT_NEAR(planes[static_cast<std::size_t>(k)].signed_distance(b), 0.0, 1e-9);
    }
    // The patch's own surface points lie in its wedge.
    EXPECT_TRUE(surface.in_wedge(t, surface.surface_point(t, 1.0 / 3.0, 1.0 / 3.0)));
  }
}

TEST(PatchSurface, BumpsThatLeaveTheirTriangleAreRejected) {
  PatchSurface surface(sphere_mesh(0, 10.0), "sphere");
  const TriangleMesh& base = surface.base_mesh();
  const Eigen::Vector3d e1 = base.vertex(base.faces(0, 1)) - base.vertex(base.faces(0, 0));
  Eigen::Matrix2d metric = Eigen::Matrix2d::Identity() * e1.squaredNorm();
  metric(0, 1) = metric(1, 0) = 0.5 * e1.squaredNorm(); // equilateral
  EXPECT_NO_THROW(surface.set_bumps(0, {PatchBump::disc({1.0 / 3.0, 1.0 / 3.0}, 0.28 * e1.norm(), metric)}));
  EXPECT_THROW(surface.set_bumps(0, {PatchBump::disc({1.0 / 3.0, 1.0 / 3.0}, 0.30 * e1.norm(), metric)}),
               InputError);
  EXPECT_THROW(surface.set_bumps(0, {PatchBump::disc({0.05, 0.5}, 0.1 * e1.norm(), metric)}), InputError);
  // A centre that is not a number passed every edge test (each comparison with NaN is false).
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const Eigen::Vector2d& centre : {Eigen::Vector2d(nan, 0.3), Eigen::Vector2d(0.3, nan)}) {
    try {
      surface.set_bumps(0, {PatchBump::disc(centre, 0.1 * e1.norm(), metric)});
      ADD_FAILURE() << "a centre of NaN was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("bump 0: expected a finite centre"), std::string::npos)
          << e.what();
    }
  }
  Eigen::Matrix2d infinite = metric;
  infinite(0, 0) = std::numeric_limits<double>::infinity();
  PatchBump endless = PatchBump::disc({1.0 / 3.0, 1.0 / 3.0}, 0.1 * e1.norm(), metric);
  endless.shape_uv = infinite;
  EXPECT_THROW(surface.set_bumps(0, {endless}), InputError);
}

// Every patch's bumps set at once (in parallel) make the surface set_bumps makes patch by patch:
// the same heights bit for bit; a bad bump names its patch (the first of several, in order) and
// leaves the surface as it was.
TEST(PatchSurface, AllBumpsSetAtOnceAreEachPatchsSetAlone) {
  const PatchSurface one_by_one = bumpy_sphere();
  PatchSurface at_once(sphere_mesh(1, 30.0), "bumpy sphere");
  std::vector<std::vector<PatchBump>> bumps(static_cast<std::size_t>(at_once.patch_count()));
  for (Eigen::Index t = 0; t < at_once.patch_count(); ++t)
    bumps[static_cast<std::size_t>(t)] = one_by_one.bumps(t);
  bumps[3].clear(); // a patch without bumps, as set_bumps never called there
  PatchSurface reference = one_by_one;
  reference.set_bumps(3, {});
  at_once.set_all_bumps(bumps);
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (Eigen::Index t = 0; t < at_once.patch_count(); ++t) {
    ASSERT_EQ(at_once.bumps(t).size(), reference.bumps(t).size());
    for (int k = 0; k < 20; ++k) {
      const double u = unit(random), v = (1.0 - u) * unit(random);
      EXPECT_EQ(at_once.height(t, u, v), reference.height(t, u, v)) << "patch " << t;
      EXPECT_EQ(at_once.bump_lattice(t).at(u, v).size(), reference.bump_lattice(t).at(u, v).size());
    }
  }
  // Bad bumps on patches 9 and 5: patch 5 is named, and nothing changed.
  std::vector<std::vector<PatchBump>> bad = bumps;
  for (const std::size_t t : {9u, 5u}) {
    bad[t] = bumps[t];
    bad[t][0].center_uv = Eigen::Vector2d(-0.5, 0.5);
  }
  try {
    at_once.set_all_bumps(bad);
    ADD_FAILURE() << "a bump outside its triangle was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 5, bump 0"), std::string::npos) << e.what();
  }
  for (Eigen::Index t = 0; t < at_once.patch_count(); ++t)
    EXPECT_EQ(at_once.height(t, 0.3, 0.3), reference.height(t, 0.3, 0.3)) << "patch " << t;
  EXPECT_THROW(at_once.set_all_bumps(std::vector<std::vector<PatchBump>>(3)), std::invalid_argument);
}

// The height bounds a surface holds are patch_height_ranges' bit for bit; changing a patch's
// bumps forgets them (no stale bounds reach a level set); bounds given back are checked.
TEST(PatchSurface, HeldHeightBoundsAreComputedOnesAndForgottenWhenBumpsChange) {
  PatchSurface surface(sphere_mesh(1, 10.0), "sphere");
  const TriangleMesh& base = surface.base_mesh();
  const Eigen::Vector3d e1 = base.vertex(base.faces(0, 1)) - base.vertex(base.faces(0, 0));
  Eigen::Matrix2d metric = Eigen::Matrix2d::Identity() * e1.squaredNorm();
  metric(0, 1) = metric(1, 0) = 0.5 * e1.squaredNorm();
  const auto bump = [&](double amplitude_mm) {
    PatchBump b = PatchBump::disc({0.3, 0.35}, 0.2 * e1.norm(), metric);
    b.amplitude_mm = amplitude_mm;
    return b;
  };
  for (Eigen::Index t = 0; t < surface.patch_count(); t += 3)
    surface.set_bumps(t, {bump(0.1 * static_cast<double>(t % 7) - 0.3)});
  EXPECT_EQ(surface.height_ranges(), nullptr);
  surface.hold_height_ranges();
  ASSERT_NE(surface.height_ranges(), nullptr);
  const std::vector<HeightRange> computed = patch_height_ranges(surface);
  ASSERT_EQ(surface.height_ranges()->size(), computed.size());
  for (std::size_t t = 0; t < computed.size(); ++t) {
    EXPECT_EQ((*surface.height_ranges())[t].lowest, computed[t].lowest);
    EXPECT_EQ((*surface.height_ranges())[t].highest, computed[t].highest);
  }
  PatchSurface moved = surface;
  moved.set_positions(1.5 * base.vertices);
  EXPECT_NE(moved.height_ranges(), nullptr); // heights over the base: they hold as it moves
  surface.set_bumps(1, {bump(2.0)});
  EXPECT_EQ(surface.height_ranges(), nullptr);

  EXPECT_NO_THROW(surface.set_height_ranges(computed));
  std::vector<HeightRange> bad = computed;
  bad.pop_back();
  EXPECT_THROW(surface.set_height_ranges(bad), InputError);
  bad = computed;
  bad[2].highest = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(surface.set_height_ranges(bad), InputError);
  bad = computed;
  bad[4] = {1.0, -1.0};
  EXPECT_THROW(surface.set_height_ranges(bad), InputError);
}

namespace {
std::string error_of(const TriangleMesh& mesh) {
  try {
    check_closed_manifold(mesh, "organ test");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
} // namespace

TEST(BaseMeshValidation, EachKindOfDefectGetsItsOwnMessageNamingTheElement) {
  const TriangleMesh good = sphere_mesh(1, 10.0);
  EXPECT_EQ(error_of(good), "");

  TriangleMesh open = good;
  open.faces.conservativeResize(open.faces.rows() - 1, 3);
  EXPECT_NE(error_of(open).find("found an open edge (boundary)"), std::string::npos) << error_of(open);

  TriangleMesh flipped = good;
  flipped.faces.row(5) = Eigen::Vector3i(good.faces(5, 0), good.faces(5, 2), good.faces(5, 1));
  EXPECT_NE(error_of(flipped).find("(inconsistent orientation)"), std::string::npos) << error_of(flipped);

  TriangleMesh inward = good;
  inward.faces.col(1).swap(inward.faces.col(2));
  EXPECT_NE(error_of(inward).find("found an inward orientation"), std::string::npos) << error_of(inward);

  TriangleMesh repeated = good;
  repeated.faces(3, 1) = repeated.faces(3, 0);
  EXPECT_NE(error_of(repeated).find("organ test: triangle 3: expected three distinct vertices"),
            std::string::npos)
      << error_of(repeated);

  TriangleMesh flat = good;
  flat.vertices.row(flat.faces(2, 2)) =
      0.5 * (flat.vertices.row(flat.faces(2, 0)) + flat.vertices.row(flat.faces(2, 1)));
  EXPECT_NE(error_of(flat).find("degenerate one"), std::string::npos) << error_of(flat);

  TriangleMesh out_of_range = good;
  out_of_range.faces(0, 0) = 100000;
  EXPECT_NE(error_of(out_of_range).find("triangle 0: expected vertex indices in [0, 41], found 100000"),
            std::string::npos)
      << error_of(out_of_range);

  // A triangle fin glued onto an edge: three triangles share that edge.
  TriangleMesh fin = good;
  fin.vertices.conservativeResize(fin.vertices.rows() + 1, 3);
  fin.vertices.row(fin.vertices.rows() - 1) = Eigen::RowVector3d(30, 30, 30);
  fin.faces.conservativeResize(fin.faces.rows() + 1, 3);
  fin.faces.row(fin.faces.rows() - 1) =
      Eigen::Vector3i(good.faces(0, 1), good.faces(0, 0), int(fin.vertices.rows() - 1));
  EXPECT_NE(error_of(fin).find("(non-manifold)"), std::string::npos) << error_of(fin);

  // Two spheres touching at one shared vertex: every edge is fine, the vertex is not.
  TriangleMesh pinched = good;
  TriangleMesh other = good;
  other.vertices.rowwise() += Eigen::RowVector3d(20, 0, 0);
  const int offset = static_cast<int>(pinched.vertices.rows());
  pinched.vertices.conservativeResize(offset + other.vertices.rows(), 3);
  pinched.vertices.bottomRows(other.vertices.rows()) = other.vertices;
  Eigen::MatrixX3i other_faces = other.faces.array() + offset;
  // Glue: the other sphere's vertex 0 becomes this sphere's vertex 0.
  const Eigen::Index glued = 0;
  for (Eigen::Index i = 0; i < other_faces.size(); ++i) {
    if (other_faces.data()[i] == offset + glued) other_faces.data()[i] = static_cast<int>(glued);
  }
  pinched.faces.conservativeResize(pinched.faces.rows() + other_faces.rows(), 3);
  pinched.faces.bottomRows(other_faces.rows()) = other_faces;
  EXPECT_NE(error_of(pinched).find("vertex 0: expected its"), std::string::npos) << error_of(pinched);
  EXPECT_NE(error_of(pinched).find("(non-manifold vertex)"), std::string::npos);

  TriangleMesh tiny;
  tiny.vertices = good.vertices;
  tiny.faces = good.faces.topRows(2);
  EXPECT_NE(error_of(tiny).find("expected a closed surface of at least 4 triangles"), std::string::npos);

  TriangleMesh nan = good;
  nan.vertices(0, 0) = std::nan("");
  EXPECT_NE(error_of(nan).find("NaN"), std::string::npos);
}

// Writing a real organ's surface mesh tessellates it for seconds: a cancelled run gets an empty
// mesh at once (the callers poll the flag before using it), and the next call is whole again.
TEST(PatchSurface, ACancelledTessellationStopsAtOnceAndTheNextIsWhole) {
  const PatchSurface surface = bumpy_sphere();
  const Eigen::Index whole = surface.tessellate(0.05).face_count();
  ASSERT_GT(whole, surface.patch_count());
  request_cancellation();
  const Eigen::Index cancelled = surface.tessellate(0.05).face_count();
  reset_cancellation();
  EXPECT_EQ(cancelled, 0);
  EXPECT_EQ(surface.tessellate(0.05).face_count(), whole);
}

// The patches' levels (and their grid points) are found in parallel: one thread and two give the
// same mesh, bit for bit.
TEST(PatchSurface, TessellationIsTheSameOnOneAndTwoThreads) {
  const PatchSurface surface = bumpy_sphere();
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const TriangleMesh one = surface.tessellate(0.02);
  omp_set_num_threads(2);
  const TriangleMesh two = surface.tessellate(0.02);
  omp_set_num_threads(threads);
  ASSERT_GT(one.face_count(), 8 * surface.patch_count());
  EXPECT_EQ(one.vertices, two.vertices);
  EXPECT_EQ(one.faces, two.faces);
}

namespace {

/// The extremes of a patch's height over its triangle, from a lattice of 400 segments per edge.
HeightRange sampled_height_range(const std::vector<PatchBump>& bumps) {
  HeightRange range;
  const int n = 400;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i + j <= n; ++i) {
      const Eigen::Vector2d uv(static_cast<double>(i) / n, static_cast<double>(j) / n);
      double h = 0.0;
      for (const PatchBump& b : bumps) {
        const double q = b.shape_value(uv);
        if (q > 0.0) h += b.amplitude_mm * q * q * q;
      }
      range.lowest = std::min(range.lowest, h);
      range.highest = std::max(range.highest, h);
    }
  }
  return range;
}

double sum_of_amplitudes(const std::vector<PatchBump>& bumps, double sign) {
  double sum = 0.0;
  for (const PatchBump& b : bumps)
    if (sign * b.amplitude_mm > 0.0) sum += std::abs(b.amplitude_mm);
  return sum;
}

} // namespace

// A bump's height, gradient and Hessian (PatchBump::add_height and add_hessian, the level sets'
// closest-point search) against central differences at random points inside the support of
// random round and elongated bumps, and nothing added outside it.
TEST(PatchBump, HeightGradientAndHessianMatchCentralFiniteDifferences) {
  std::mt19937 random(23);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int inside = 0;
  for (int trial = 0; trial < 400; ++trial) {
    PatchBump b;
    b.center_uv = {0.2 + 0.4 * unit(random), 0.2 + 0.4 * unit(random)};
    const Eigen::Matrix2d R = Eigen::Rotation2Dd(M_PI * unit(random)).toRotationMatrix();
    const Eigen::Vector2d eigenvalues(4.0 * std::pow(100.0, unit(random)),
                                      4.0 * std::pow(100.0, unit(random)));
    b.shape_uv = R * eigenvalues.asDiagonal() * R.transpose();
    b.amplitude_mm = 4.0 * unit(random) - 1.5;
    const Eigen::Vector2d uv = b.center_uv + 0.6 * Eigen::Vector2d(unit(random) - 0.5, unit(random) - 0.5);
    const auto height = [&b](const Eigen::Vector2d& at) {
      double h = 0.0;
      Eigen::Vector2d g = Eigen::Vector2d::Zero();
      b.add_height(at, h, g, nullptr);
      return h;
    };
    const auto gradient = [&b](const Eigen::Vector2d& at) {
      double h = 0.0;
      Eigen::Vector2d g = Eigen::Vector2d::Zero();
      b.add_height(at, h, g, nullptr);
      return g;
    };
    double h = 1.0; // added to, not overwritten
    Eigen::Vector2d g = Eigen::Vector2d::Ones();
    Eigen::Matrix2d H = Eigen::Matrix2d::Identity();
    b.add_height(uv, h, g, &H);
    // The Hessian alone (the level sets' Newton steps ask for it apart): the same bits.
    Eigen::Matrix2d H_alone = Eigen::Matrix2d::Identity();
    b.add_hessian(uv, H_alone);
    EXPECT_EQ(H_alone, H) << "trial " << trial;
    const double q = b.shape_value(uv);
    if (q <= 0.0) {
      EXPECT_EQ(h, 1.0);
      EXPECT_EQ(g, Eigen::Vector2d::Ones());
      EXPECT_EQ(H, Eigen::Matrix2d::Identity());
      continue;
    }
    if (q < 1e-3) continue; // the Hessian is only continuous at the support's edge (Q^3: C2)
    ++inside;
    EXPECT_NEAR(h - 1.0, b.amplitude_mm * q * q * q, 1e-14);
    const double step = 1e-6 / std::sqrt(eigenvalues.maxCoeff());
    EXPECT_TRUE(matches_finite_differences(g - Eigen::Vector2d::Ones(),
                                           central_difference_gradient(height, uv, step), 1e-5,
                                           1e-6 * std::abs(b.amplitude_mm) * eigenvalues.maxCoeff()))
        << "trial " << trial;
    EXPECT_TRUE(matches_finite_differences(H - Eigen::Matrix2d::Identity(),
                                           central_difference_jacobian(gradient, uv, step), 1e-5,
                                           1e-6 * std::abs(b.amplitude_mm) * eigenvalues.maxCoeff()))
        << "trial " << trial;
  }
  EXPECT_GT(inside, 100);
}

TEST(PatchHeightRange, EnclosesEveryHeightOfRandomBumps) {

  // 1-12 bumps of both signs, round and elongated, wide and narrow (the eigenvalues of S from 4
  // to 400), centred anywhere in the triangle.
  std::mt19937 random(11);
  for (int patch = 0; patch < 300; ++patch) {
    const std::vector<PatchBump> bumps = random_bumps(random, 1 + patch % 12, 4.0, 100.0, -1.5, 2.5);
    const HeightRange range = patch_height_range(bumps), sampled = sampled_height_range(bumps);
    ASSERT_LE(range.lowest, sampled.lowest) << "patch " << patch;
    ASSERT_GE(range.highest, sampled.highest) << "patch " << patch;
    // Never looser than the sums of the amplitudes.
    EXPECT_LE(range.highest, sum_of_amplitudes(bumps, 1.0) + 1e-9) << "patch " << patch;
    EXPECT_GE(range.lowest, -sum_of_amplitudes(bumps, -1.0) - 1e-9) << "patch " << patch;
  }
}

namespace {

/// patch_height_range's bounds one sub-triangle at a time, as written out in its comment: each
/// bump's Q at the three corners of each sub-triangle of the 32 x 32 lattice its support box
/// meets, the bounds summed in bump order, the extremes over every sub-triangle.
HeightRange height_range_by_sub_triangle(const std::vector<PatchBump>& bumps) {
  constexpr int n = 32;
  std::vector<double> upper(2 * n * n, 0.0), lower(2 * n * n, 0.0);
  const double step = 1.0 / n;
  const Eigen::Vector2d edges[3] = {{step, 0.0}, {0.0, step}, {step, -step}};
  const auto cube_of_positive = [](double x) { return x > 0.0 ? x * x * x : 0.0; };
  for (const PatchBump& bump : bumps) {
    const Eigen::Matrix2d S = 0.5 * (bump.shape_uv + bump.shape_uv.transpose());
    const double a = bump.amplitude_mm;
    if (a == 0.0) continue;
    double widest = 0.0;
    for (const Eigen::Vector2d& e : edges)
      widest = std::max(widest, e.dot(S * e));
    const double det = S.determinant();
    const Eigen::Vector2d half(std::sqrt(S(1, 1) / det), std::sqrt(S(0, 0) / det));
    const auto cell = [](double x) { return static_cast<int>(std::clamp(std::floor(x * n), 0.0, n - 1.0)); };
    const auto q = [&](int i, int j) {
      const Eigen::Vector2d d = step * Eigen::Vector2d(i, j) - bump.center_uv;
      return 1.0 - d.dot(S * d);
    };
    const auto add = [&](std::size_t id, double q0, double q1, double q2) {
      const double q_low = std::min({q0, q1, q2});
      const double q_high = std::min(1.0, std::max({q0, q1, q2}) + widest / 3.0);
      lower[id] += a * cube_of_positive(a > 0.0 ? q_low : q_high);
      upper[id] += a * cube_of_positive(a > 0.0 ? q_high : q_low);
    };
    for (int j = cell(bump.center_uv.y() - half.y()); j <= cell(bump.center_uv.y() + half.y()); ++j) {
      for (int i = cell(bump.center_uv.x() - half.x()); i <= cell(bump.center_uv.x() + half.x()) && i + j < n;
           ++i) {
        const auto id = static_cast<std::size_t>(2 * (j * n + i));
        add(id, q(i, j), q(i + 1, j), q(i, j + 1));
        if (i + j + 2 <= n) add(id + 1, q(i + 1, j), q(i, j + 1), q(i + 1, j + 1));
      }
    }
  }
  HeightRange range;
  for (std::size_t id = 0; id < upper.size(); ++id) {
    range.highest = std::max(range.highest, upper[id]);
    range.lowest = std::min(range.lowest, lower[id]);
  }
  double total = 0.0;
  for (const PatchBump& bump : bumps)
    total += std::abs(bump.amplitude_mm);
  range.lowest -= 1e-12 * total;
  range.highest += 1e-12 * total;
  return range;
}

} // namespace

TEST(PatchHeightRange, IsTheSubTriangleBoundsToTheBit) {
  // Computed row by row without branches, the bounds are those summed sub-triangle by sub-triangle,
  // bit for bit: fitted anatomy's level sets and the anatomy cache hold them.
  std::mt19937 random(23);
  for (int patch = 0; patch < 400; ++patch) {
    std::vector<PatchBump> bumps = random_bumps(random, 1 + patch % 21, 2.0, 200.0, -2.0, 2.0);
    if (patch % 5 == 0) bumps[static_cast<std::size_t>(patch / 5) % bumps.size()].amplitude_mm = 0.0;
    const HeightRange range = patch_height_range(bumps), reference = height_range_by_sub_triangle(bumps);
    ASSERT_EQ(range.lowest, reference.lowest) << "patch " << patch;
    ASSERT_EQ(range.highest, reference.highest) << "patch " << patch;
  }
}

TEST(PatchHeightRange, StaysNearTheExtremesOfAFittedPatchsBumps) {
  // The fitting basis of anatomy/patch_fit: the incircles of the sub-triangles of levels 0-2
  // (21 nested discs) on an equilateral triangle of 4 mm edges, random amplitudes of both signs.
  Eigen::Matrix2d metric;
  metric << 16.0, 8.0, 8.0, 16.0;
  const double inradius = 4.0 / (2.0 * std::sqrt(3.0));
  std::mt19937 random(5);
  std::uniform_real_distribution<double> amplitude(-1.0, 1.0);
  double bound_to_sum = 0.0, bound_to_extreme = 0.0;
  const int patches = 50;
  for (int patch = 0; patch < patches; ++patch) {
    std::vector<PatchBump> bumps;
    for (const BasisDisc& disc : fitting_basis_discs(2))
      bumps.push_back(PatchBump::disc(disc.center_uv, 0.999 * inradius / disc.subdivisions, metric));
    for (PatchBump& b : bumps)
      b.amplitude_mm = amplitude(random);
    const HeightRange range = patch_height_range(bumps), sampled = sampled_height_range(bumps);
    ASSERT_LE(range.lowest, sampled.lowest) << "patch " << patch;
    ASSERT_GE(range.highest, sampled.highest) << "patch " << patch;
    bound_to_sum += range.highest / sum_of_amplitudes(bumps, 1.0) / patches;
    bound_to_extreme += (range.highest - sampled.highest) / patches;
  }
  // About a fifth of the sum of the positive amplitudes (the former bound), and within 0.05 mm
  // of the true highest point on average.
  EXPECT_LT(bound_to_sum, 0.3);
  EXPECT_LT(bound_to_extreme, 0.1);
}

TEST(PatchHeightRange, FlatPatchHasNoHeight) {
  const HeightRange range = patch_height_range({});
  EXPECT_EQ(range.lowest, 0.0);
  EXPECT_EQ(range.highest, 0.0);
}
