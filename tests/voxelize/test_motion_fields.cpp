// The map between the reference and deformed phantom on one cube of six tets under an affine
// motion y = A x + b, where every answer is known in closed form: inside the body both ways the
// affine map and its inverse, exactly; outside, within extension_mm of the moved boundary, the
// smoothstep fade-out of the boundary's displacement (not exact); beyond, the identity (exact).

#include "voxelize/motion_fields.hpp"

#include "geometry/closest_point_triangle.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>

#include <cmath>
#include <limits>
#include <random>

using namespace phantasm;

namespace {

const double k_side_mm = 20.0;
const double k_extension_mm = 5.0;

/// The affine motion: a mild shear and stretch (det 1.04) and a 1 mm shift along x.
Eigen::Matrix3d motion_matrix() {
  Eigen::Matrix3d A;
  A << 1.1, 0.05, 0.0, 0.0, 0.95, 0.02, 0.03, 0.0, 1.0;
  return A;
}
const Eigen::Vector3d k_shift(1.0, -0.5, 0.3);

Eigen::Vector3d moved(const Eigen::Vector3d& x) {
  return motion_matrix() * x + k_shift;
}

/// The cube [0, side]^3 cut into six tets around its diagonal from corner 0 to corner 7
/// (corner k at (k & 1, k & 2, k & 4) * side), its vertices moved by the affine motion.
DeformedBody affine_cube() {
  DeformedBody body;
  body.organ = "cube";
  body.rest_mm.resize(8, 3);
  for (int k = 0; k < 8; ++k)
    body.rest_mm.row(k) = k_side_mm * Eigen::RowVector3d(k & 1, (k >> 1) & 1, (k >> 2) & 1);
  body.deformed_mm.resize(8, 3);
  for (int k = 0; k < 8; ++k)
    body.deformed_mm.row(k) = moved(body.rest_mm.row(k).transpose()).transpose();
  // One tet per order in which the axes are walked from corner 0 to corner 7.
  const int axes[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  body.tets.resize(6, 4);
  for (int t = 0; t < 6; ++t) {
    const int first = 1 << axes[t][0], second = first | (1 << axes[t][1]);
    body.tets.row(t) << 0, first, second, 7;
  }
  return body;
}

/// The fade-out of the extension: 1 on the boundary, 0 at extension_mm (a smoothstep).
double fade(double distance_mm) {
  const double s = 1.0 - distance_mm / k_extension_mm;
  return s <= 0.0 ? 0.0 : s * s * (3.0 - 2.0 * s);
}

} // namespace

TEST(DeformationMap, InsideTheBodyForwardIsTheMotionAndInverseTakesItBackExactly) {
  const DeformationMap map({affine_cube()}, k_extension_mm);
  std::mt19937 random(5);
  std::uniform_real_distribution<double> coordinate(0.0, k_side_mm);
  std::vector<Eigen::Vector3d> points = {
      Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(k_side_mm),
      Eigen::Vector3d(k_side_mm, 0.0, 0.5 * k_side_mm)}; // corners, an edge
  for (int n = 0; n < 200; ++n)
    points.emplace_back(coordinate(random), coordinate(random), coordinate(random));
  for (const Eigen::Vector3d& x : points) {
    SCOPED_TRACE(x.transpose());
    bool exact = false;
    const Eigen::Vector3d y = map.forward(x, &exact);
    EXPECT_TRUE(exact);
    EXPECT_LT((y - moved(x)).norm(), 1e-9);
    bool back_exact = false;
    EXPECT_LT((map.inverse(y, &back_exact) - x).norm(), 1e-9);
    EXPECT_TRUE(back_exact);
  }
}

TEST(DeformationMap, OutsideTheBodyTheBoundaryMotionFadesOutOverTheExtensionAndIsNotExact) {
  const DeformationMap map({affine_cube()}, k_extension_mm);
  // In front of the centre of the face x = 0 at distance d: the closest boundary point is the
  // face centre, which moves by u = A c + b - c; the map moves x by fade(d) u.
  const Eigen::Vector3d centre(0.0, 0.5 * k_side_mm, 0.5 * k_side_mm);
  const Eigen::Vector3d u = moved(centre) - centre;
  for (double d : {0.5, 1.0, 2.5, 4.0}) {
    SCOPED_TRACE(d);
    const Eigen::Vector3d x = centre - Eigen::Vector3d(d, 0.0, 0.0);
    bool exact = true;
    const Eigen::Vector3d y = map.forward(x, &exact);
    EXPECT_FALSE(exact);
    EXPECT_LT((y - (x + fade(d) * u)).norm(), 1e-9);
    // The way back: the fixed-point inverse of the extension returns to x, still not exact
    // (y lies outside the deformed cube, whose face moved away by about 1 mm).
    bool back_exact = true;
    EXPECT_LT((map.inverse(y, &back_exact) - x).norm(), 1e-6);
    EXPECT_FALSE(back_exact);
  }
  // The gap the moved face leaves: inside the reference cube but outside the deformed one, the
  // way back has no exact answer.
  const Eigen::Vector3d gap(0.3, 0.5 * k_side_mm, 0.5 * k_side_mm);
  ASSERT_LT(gap.x(), moved(Eigen::Vector3d(0.0, gap.y(), gap.z())).x()); // left of the moved face
  bool gap_exact = true;
  map.inverse(gap, &gap_exact);
  EXPECT_FALSE(gap_exact);
  // Beyond extension_mm of the boundary in both states: tissue that does not move, exactly.
  for (const Eigen::Vector3d& far :
       {Eigen::Vector3d(-12.0, 10.0, 10.0), Eigen::Vector3d(40.0, 40.0, -15.0)}) {
    SCOPED_TRACE(far.transpose());
    bool exact = false;
    EXPECT_EQ(map.forward(far, &exact), far);
    EXPECT_TRUE(exact);
    exact = false;
    EXPECT_EQ(map.inverse(far, &exact), far);
    EXPECT_TRUE(exact);
  }
}

// The dense fields on a grid: the motion inside the cube, its Jacobian determinant det A (central
// differences of an affine field are exact) and det A^-1 for the way back, zero and exact far away.
TEST(DeformationMap, MotionFieldsHoldTheMotionAndItsJacobianInsideAndNothingFarAway) {
  const DeformationMap map({affine_cube()}, k_extension_mm);
  ImageGrid grid;
  grid.dims = {24, 24, 24}; // 2 mm voxels from -13 mm to 33 mm
  grid.spacing_mm = Eigen::Vector3d::Constant(2.0);
  grid.world_from_voxel.topLeftCorner<3, 3>() = 2.0 * Eigen::Matrix3d::Identity();
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d::Constant(-13.0);
  const MotionFields fields = compute_motion_fields(grid, map);
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  const double det = motion_matrix().determinant();
  int inside = 0, inside_deformed = 0, far = 0;
  for (int k = 0; k < grid.dims.z(); ++k) {
    for (int j = 0; j < grid.dims.y(); ++j) {
      for (int i = 0; i < grid.dims.x(); ++i) {
        const std::size_t v = static_cast<std::size_t>(i + grid.dims.x() * (j + grid.dims.y() * k));
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        const Eigen::Vector3d u(fields.ref_to_def[v], fields.ref_to_def[count + v],
                                fields.ref_to_def[2 * count + v]);
        // Voxels whose neighbours are inside the cube too: the motion and det A.
        if ((x.array() >= 2.0).all() && (x.array() <= k_side_mm - 2.0).all()) {
          ++inside;
          EXPECT_LT((u - (moved(x) - x)).norm(), 1e-5) << x.transpose();
          EXPECT_TRUE(fields.ref_to_def_exact[v]);
          EXPECT_NEAR(fields.jacobian[v], det, 1e-5) << x.transpose();
        }
        // Deformed voxels whose stencil lies inside the moved cube: the way back has det A^-1.
        const Eigen::Vector3d back(fields.def_to_ref[v], fields.def_to_ref[count + v],
                                   fields.def_to_ref[2 * count + v]);
        const Eigen::Vector3d origin = x + back;
        if ((origin.array() >= 4.0).all() && (origin.array() <= k_side_mm - 4.0).all()) {
          ++inside_deformed;
          EXPECT_TRUE(fields.def_to_ref_exact[v]);
          EXPECT_NEAR(fields.def_to_ref_jacobian[v], 1.0 / det, 1e-5) << x.transpose();
        }
        // More than extension_mm from the cube in both states: nothing moves.
        const Eigen::Vector3d low = Eigen::Vector3d::Constant(-k_extension_mm - 3.0);
        const Eigen::Vector3d high = Eigen::Vector3d::Constant(k_side_mm + k_extension_mm + 4.0);
        if ((x.array() < low.array()).any() || (x.array() > high.array()).any()) {
          ++far;
          EXPECT_EQ(u, Eigen::Vector3d::Zero()) << x.transpose();
          EXPECT_TRUE(fields.ref_to_def_exact[v] && fields.def_to_ref_exact[v]) << x.transpose();
          EXPECT_EQ(fields.jacobian[v], 1.0f) << x.transpose();
          EXPECT_EQ(fields.def_to_ref_jacobian[v], 1.0f) << x.transpose();
        }
      }
    }
  }
  // Both kinds of voxel were there to check (x = 3, 5, ..., 17 mm inside; -13 to -9 and 31 to
  // 33 mm far along each axis).
  EXPECT_GT(inside, 100);
  EXPECT_GT(inside_deformed, 50);
  EXPECT_GT(far, 100);
}

namespace reference {

/// The moved boundary's distance from x by a scan of every moved face, in order (the way before
/// the buckets; kept here only to compare): the nearest face, the first of equals.
double scan_distance(const DeformationMap& map, const Eigen::Vector3d& x, bool deformed,
                     Eigen::Vector3d* displacement) {
  double best = std::numeric_limits<double>::infinity();
  for (const DeformationMap::MovedFace& f : map.moved_faces()) {
    const auto& v = deformed ? f.deformed : f.rest;
    const Eigen::Vector3d w = closest_point_on_triangle(x, v[0], v[1], v[2]).barycentric;
    const double d = (x - (w[0] * v[0] + w[1] * v[1] + w[2] * v[2])).norm();
    if (d < best) {
      best = d;
      *displacement = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k)
        *displacement += w[k] * (f.deformed[k] - f.rest[k]);
    }
  }
  return best;
}

} // namespace reference

// The buckets of moved faces find the same closest face as the scan of every face wherever it is
// nearer than the extension (the only distances the maps read), in both states, at the voxels of
// a grid not aligned with the cube that reaches past the buckets and at random points; and where
// the buckets call a point far from the moved boundary, the scan finds no face within the
// extension in either state (so the identity there is exact).
TEST(DeformationMap, FaceBucketsFindTheFaceTheScanOfEveryFaceFinds) {
  const DeformationMap map({affine_cube()}, k_extension_mm);
  ASSERT_EQ(map.moved_faces().size(), 12u); // every boundary face moves
  std::vector<Eigen::Vector3d> points;
  ImageGrid grid;
  grid.dims = {31, 29, 27};
  grid.spacing_mm = Eigen::Vector3d(1.3, 1.4, 1.5);
  grid.world_from_voxel.topLeftCorner<3, 3>() = grid.spacing_mm.asDiagonal();
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(-9.7, -10.1, -9.9);
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i)
        points.push_back(grid.world_from_index(Eigen::Vector3d(i, j, k)));
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-12.0, 35.0);
  for (int n = 0; n < 2000; ++n)
    points.emplace_back(coordinate(random), coordinate(random), coordinate(random));
  int near = 0, far = 0;
  for (const Eigen::Vector3d& x : points) {
    for (const bool deformed : {false, true}) {
      Eigen::Vector3d u_buckets = Eigen::Vector3d::Constant(-1.0), u_scan = u_buckets;
      const double d_buckets = map.moved_boundary_distance(x, deformed, &u_buckets);
      const double d_scan = reference::scan_distance(map, x, deformed, &u_scan);
      if (d_scan < k_extension_mm) {
        ++near;
        EXPECT_EQ(d_buckets, d_scan) << x.transpose();
        EXPECT_EQ(u_buckets, u_scan) << x.transpose();
      } else {
        EXPECT_FALSE(d_buckets < k_extension_mm) << x.transpose();
      }
    }
    if (map.far_from_moved_boundary(x)) {
      ++far;
      Eigen::Vector3d u;
      EXPECT_GE(reference::scan_distance(map, x, false, &u), k_extension_mm) << x.transpose();
      EXPECT_GE(reference::scan_distance(map, x, true, &u), k_extension_mm) << x.transpose();
    }
  }
  // Both kinds of point were there to check.
  EXPECT_GT(near, 1000);
  EXPECT_GT(far, 1000);
  EXPECT_LT(far, static_cast<int>(points.size()) - 1000);
}

// Tissue that does not move (by its label in each state) carries zero displacement in the field
// of that state and is exact, inside the body's tets or in the extension; its Jacobian is 1, and
// the Jacobian of a moving voxel next to it is differenced on the moving side only: under the
// affine motion every moving voxel with a moving neighbour on each side along each axis, or on
// one side, has the motion's determinant. The voxels of other labels keep the fields without
// still tissue, bit for bit.
TEST(MotionFields, StillTissueHasZeroDisplacementAndTheExtensionStopsAtIt) {
  const DeformationMap map({affine_cube()}, k_extension_mm);
  ImageGrid grid;
  grid.dims = {24, 24, 24};
  grid.spacing_mm = Eigen::Vector3d::Ones();
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d::Constant(-2.0);
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  // Label 1 (moving) inside x < 14 mm, label 2 (still) from there on: the still slab cuts
  // through the cube (inside its tets) and through the extension beyond it.
  std::vector<std::int32_t> labels(count, 1);
  for (std::size_t v = 0; v < count; ++v)
    if (grid.world_from_index(Eigen::Vector3d(static_cast<double>(v % 24), 0, 0)).x() >= 14.0) labels[v] = 2;
  const StillTissue still{&labels, &labels, {0, 0, 1}};
  const MotionFields free = compute_motion_fields(grid, map);
  const MotionFields held = compute_motion_fields(grid, map, still);
  const double det = motion_matrix().determinant();
  long still_voxels = 0, moving_in_cube = 0, checked_jacobians = 0, had_extension = 0;
  for (int k = 0; k < 24; ++k) {
    for (int j = 0; j < 24; ++j) {
      for (int i = 0; i < 24; ++i) {
        const std::size_t v = voxel_index(grid.dims, i, j, k);
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        if (labels[v] == 2) {
          ++still_voxels;
          for (std::size_t c = 0; c < 3; ++c) {
            EXPECT_EQ(held.ref_to_def[c * count + v], 0.0f);
            EXPECT_EQ(held.def_to_ref[c * count + v], 0.0f);
          }
          EXPECT_EQ(held.ref_to_def_exact[v], 1);
          EXPECT_EQ(held.def_to_ref_exact[v], 1);
          EXPECT_EQ(held.jacobian[v], 1.0f);
          EXPECT_EQ(held.def_to_ref_jacobian[v], 1.0f);
          if (free.ref_to_def[v] != 0.0f) ++had_extension;
          continue;
        }
        for (std::size_t c = 0; c < 3; ++c) {
          EXPECT_EQ(held.ref_to_def[c * count + v], free.ref_to_def[c * count + v]);
          EXPECT_EQ(held.def_to_ref[c * count + v], free.def_to_ref[c * count + v]);
        }
        // Moving voxels inside the cube, off its faces, whose stencil stays inside it.
        const bool interior = (x.array() >= 1.0).all() && (x.array() <= k_side_mm - 1.0).all();
        if (!interior) continue;
        ++moving_in_cube;
        EXPECT_NEAR(held.jacobian[v], det, 1e-4) << x.transpose();
        ++checked_jacobians;
      }
    }
  }
  EXPECT_GT(still_voxels, 1000);
  EXPECT_GT(had_extension, 100); // without still tissue, the extension reached into the slab
  EXPECT_GT(moving_in_cube, 1000);
  EXPECT_GT(checked_jacobians, 1000);
  EXPECT_EQ(held.folded_exact_voxels, 0);
}

TEST(MotionFields, StillOrganLabelsAreTheFixedAndRigidOrgans) {
  PhantomDeformation deformation;
  for (const char* how : {"fixed", "solver", "rigid", "embedded in a"})
    deformation.organs.push_back(OrganDeformation{"organ", how, {}, {}});
  // Background, four organs, the gap.
  EXPECT_EQ(still_organ_labels(deformation), (std::vector<std::uint8_t>{0, 1, 0, 1, 0, 0}));
}

// The composition check: where neither field moves a voxel, both compositions are the identity
// and the voxel stays in both masks; a voxel one field moves and the other does not is left out
// of both (each composition misses identity by the displacement), and only it.
TEST(MotionFields, CompositionsLeaveOutTheVoxelOneFieldMovesAndKeepTheStillOnes) {
  ImageGrid grid;
  grid.dims = {8, 8, 8};
  grid.spacing_mm = Eigen::Vector3d::Ones();
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  MotionFields f = identity_motion_fields(count);
  const std::size_t v = voxel_index(grid.dims, 3, 4, 5);
  f.def_to_ref[v] = 2.0f; // x component: def_to_ref moves v by 2 mm, ref_to_def leaves it
  check_compositions(grid, f);
  EXPECT_EQ(f.inconsistent_voxels, 2);
  EXPECT_EQ(f.ref_to_def_exact[v], 0);
  EXPECT_EQ(f.def_to_ref_exact[v], 0);
  std::size_t kept = 0;
  for (std::size_t w = 0; w < count; ++w)
    kept += (f.ref_to_def_exact[w] ? 1 : 0) + (f.def_to_ref_exact[w] ? 1 : 0);
  EXPECT_EQ(kept, 2 * count - 2);
  EXPECT_EQ(f.max_composition_error_mm, 0.0);
  EXPECT_EQ(f.folded_exact_voxels, 0);
}

// Inside an exact mask the Jacobian reads exact values only: a linear field u = (3 x, 0, 0)
// (det 4 everywhere) with a plane of voxels left out of the mask holding something else (zero,
// as the extension or a missed composition can). A central difference across that plane gives
// its neighbours det -3.5, a fold no tissue has; the one-sided differences give 4.
TEST(MotionFields, JacobiansInsideTheExactMaskReadNoValueOutsideIt) {
  ImageGrid grid;
  grid.dims = {10, 6, 6};
  grid.spacing_mm = Eigen::Vector3d::Ones();
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  MotionFields f = identity_motion_fields(count);
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 10; ++i) {
        const std::size_t v = voxel_index(grid.dims, i, j, k);
        const bool outside = i == 5;
        f.ref_to_def[v] = outside ? 0.0f : 3.0f * static_cast<float>(i);
        f.def_to_ref[v] = outside ? 0.0f : 3.0f * static_cast<float>(i);
        f.ref_to_def_exact[v] = outside ? 0 : 1;
        f.def_to_ref_exact[v] = outside ? 0 : 1;
      }
  exact_jacobians(grid, StillTissue{}, f);
  for (std::size_t v = 0; v < count; ++v) {
    if (!f.ref_to_def_exact[v]) continue;
    EXPECT_NEAR(f.jacobian[v], 4.0f, 1e-5f) << v;
    EXPECT_NEAR(f.def_to_ref_jacobian[v], 4.0f, 1e-5f) << v;
  }
  EXPECT_EQ(f.folded_exact_voxels, 0);
  EXPECT_NEAR(f.min_exact_jacobian, 4.0, 1e-5);
  // Outside the mask nothing is promised: the plane's own determinant reads across it.
  EXPECT_LT(f.min_jacobian, 4.0);
}
