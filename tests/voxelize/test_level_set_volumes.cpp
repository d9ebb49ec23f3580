// Level sets and partial-volume fractions on analytic shapes: volume from fractions against the
// exact enclosed volume, its convergence under refinement, and the signed-distance property.

#include "anatomy/patch_surface.hpp"
#include "geometry/mesh_signed_distance.hpp"
#include "geometry/triangle_mesh.hpp"
#include "tests/support/finite_difference.hpp"
#include "tests/support/patch_bumps.hpp"
#include "tests/support/sphere_level_set.hpp"
#include "voxelize/level_set.hpp"
#include "voxelize/tissue_volumes.hpp"

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

using namespace phantasm;
using namespace phantasm::testing;

namespace {

/// A fine icosphere scaled to an ellipsoid: the exact volume of the surface the level set is
/// built from is enclosed_volume(mesh).
TriangleMesh ellipsoid_mesh(const Eigen::Vector3d& radii) {
  TriangleMesh mesh = unit_icosphere(6); // 81920 triangles: chord error far below the voxels
  mesh.vertices = mesh.vertices * radii.asDiagonal();
  return mesh;
}

double fraction_volume(const LevelSet& level_set, double voxel_mm, double extent_mm) {
  ImageGrid grid;
  const int n = static_cast<int>(std::ceil(extent_mm / voxel_mm));
  grid.dims = {n, n, n};
  grid.spacing_mm = Eigen::Vector3d::Constant(voxel_mm);
  grid.world_from_voxel.topLeftCorner<3, 3>() = voxel_mm * Eigen::Matrix3d::Identity();
  // Offset by a third of a voxel so the grid is not symmetric about the shape.
  grid.world_from_voxel.topRightCorner<3, 1>() =
      Eigen::Vector3d::Constant(-0.5 * (n - 1) * voxel_mm + voxel_mm / 3.0);
  const VoxelizedOrgan organ{&level_set, 0, 1, 0};
  const TissueVolumes v = voxelize_tissues(grid, {organ}, 1, 4);
  return v.fraction_sum(0) * voxel_mm * voxel_mm * voxel_mm;
}

/// A sphere of radius 20 mm on an 80-triangle base with one round bump per patch, 0.6 mm out
/// and in by turns, 0.8 times as wide as the patch's inscribed circle.
PatchSurface bumpy_sphere() {
  TriangleMesh base = unit_icosphere(1);
  base.vertices *= 20.0;
  PatchSurface surface(base, "bumpy sphere");
  for (Eigen::Index t = 0; t < base.face_count(); ++t) {
    surface.set_bumps(
        t, {phantasm::testing::disc_in_triangle(base, t, {1.0 / 3.0, 1.0 / 3.0}, 0.8, t % 2 ? -0.6 : 0.6)});
  }
  return surface;
}

/// An icosahedron of radius 20 mm with 16 bumps on every patch, off centre and elongated, as
/// fitted anatomy carries them (there, 27 per patch), 0.3 to 0.6 mm out and in by turns, each
/// inside its triangle. `centres` gets each patch's bump centres (u, v).
PatchSurface many_bumps_surface(std::vector<std::vector<Eigen::Vector2d>>* centres) {
  TriangleMesh base = unit_icosphere(0);
  base.vertices *= 20.0;
  PatchSurface surface(base, "many bumps");
  std::mt19937 random(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  centres->assign(static_cast<std::size_t>(base.face_count()), {});
  for (Eigen::Index t = 0; t < base.face_count(); ++t) {
    std::vector<PatchBump> bumps;
    for (int i = 0; i < 16; ++i) {
      // Centres well inside the triangle, radii small enough that the support stays inside.
      double u = 0.0, v = 0.0;
      do {
        u = unit(random);
        v = unit(random);
      } while (u < 0.25 || v < 0.25 || u + v > 0.75);
      const double amplitude = (i % 2 ? -1.0 : 1.0) * (0.3 + 0.3 * unit(random));
      PatchBump bump = disc_in_triangle(base, t, {u, v}, 0.2 + 0.1 * unit(random), amplitude);
      bump.shape_uv(0, 0) *= 1.0 + unit(random); // narrower along u: still inside the disc
      bumps.push_back(bump);
      (*centres)[static_cast<std::size_t>(t)].emplace_back(u, v);
    }
    surface.set_bumps(t, bumps);
  }
  return surface;
}

/// The float's bits, so that comparisons tell -0 from +0.
std::uint32_t bits(float x) {
  std::uint32_t b = 0;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

/// The bits of every float of a volume, so that comparisons tell -0 from +0.
std::vector<std::uint32_t> bits(const std::vector<float>& volume) {
  std::vector<std::uint32_t> out(volume.size());
  std::transform(volume.begin(), volume.end(), out.begin(), [](float x) { return bits(x); });
  return out;
}

/// Labels and fractions held densely, as the voxelizer first held them: per tissue, then the
/// background, a float for every voxel.
struct DenseTissues {
  std::vector<std::int32_t> labels;
  std::vector<std::vector<float>> fractions; ///< tissue_count + 1 volumes, the background's last
  std::size_t supersampled_voxels = 0;
};

/// Every tissue's fraction volume of `v`, then the background's.
std::vector<std::vector<float>> dense_fractions(const TissueVolumes& v) {
  std::vector<std::vector<float>> out;
  for (int t = 0; t <= v.tissue_count; ++t)
    out.push_back(v.fraction_volume(t));
  return out;
}

/// `v` holds the bytes of `expected`: its labels, and its fractions read back densely bit for
/// bit; only voxels sampled near a surface (or copied from another state) are stored.
void expect_same_bytes(const TissueVolumes& v, const DenseTissues& expected) {
  EXPECT_EQ(v.labels, expected.labels);
  const std::vector<std::vector<float>> fractions = dense_fractions(v);
  ASSERT_EQ(fractions.size(), expected.fractions.size());
  for (std::size_t t = 0; t < fractions.size(); ++t)
    EXPECT_EQ(bits(fractions[t]), bits(expected.fractions[t])) << "tissue " << t;
}

/// voxelize_tissues as it was first written, for comparison: every voxel's centre probed in
/// every organ, and each supersample of a voxel near a surface probed in every organ near it.
DenseTissues probe_every_sample(const ImageGrid& grid, const std::vector<VoxelizedOrgan>& organs,
                                int tissue_count, int n) {
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  DenseTissues out;
  out.labels.assign(count, 0);
  out.fractions.assign(static_cast<std::size_t>(tissue_count) + 1, std::vector<float>(count, 0.0f));
  std::vector<float>& background_fraction = out.fractions.back();
  std::vector<LevelSet::Probe> probes;
  for (const VoxelizedOrgan& organ : organs)
    probes.emplace_back(*organ.level_set);
  const double half_diagonal = 0.5 * grid.spacing_mm.norm();
  const Eigen::Matrix3d axes = grid.world_from_voxel.topLeftCorner<3, 3>();
  std::vector<double> centre_distance(organs.size()), share(organs.size());
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const std::size_t index = voxel_index(grid.dims, i, j, k);
        const Eigen::Vector3d centre = grid.world_from_index(Eigen::Vector3d(i, j, k));
        bool decided = true;
        for (std::size_t o = 0; o < organs.size(); ++o) {
          centre_distance[o] = probes[o](centre);
          decided = decided && std::abs(centre_distance[o]) >= half_diagonal;
        }
        const auto deepest = [&](auto&& inside) {
          int best = -1;
          for (std::size_t o = 0; o < organs.size(); ++o)
            if (inside(o) && (best < 0 || organs[o].depth >= organs[static_cast<std::size_t>(best)].depth))
              best = static_cast<int>(o);
          return best;
        };
        std::fill(share.begin(), share.end(), 0.0);
        double background = 0.0;
        if (decided) {
          const int owner = deepest([&](std::size_t o) { return centre_distance[o] < 0.0; });
          (owner < 0 ? background : share[static_cast<std::size_t>(owner)]) = 1.0;
        } else {
          ++out.supersampled_voxels;
          for (int c = 0; c < n; ++c)
            for (int b = 0; b < n; ++b)
              for (int a = 0; a < n; ++a) {
                const Eigen::Vector3d x =
                    centre +
                    axes * Eigen::Vector3d((a + 0.5) / n - 0.5, (b + 0.5) / n - 0.5, (c + 0.5) / n - 0.5);
                const int owner = deepest([&](std::size_t o) {
                  return std::abs(centre_distance[o]) >= half_diagonal ? centre_distance[o] < 0.0
                                                                       : probes[o](x) < 0.0;
                });
                (owner < 0 ? background : share[static_cast<std::size_t>(owner)]) += 1.0 / (n * n * n);
              }
        }
        int label = 0;
        double largest = background, empty = background;
        for (std::size_t o = 0; o < organs.size(); ++o) {
          if (organs[o].tissue < 0)
            empty += share[o];
          else
            out.fractions[static_cast<std::size_t>(organs[o].tissue)][index] += static_cast<float>(share[o]);
          if (share[o] > largest) {
            largest = share[o];
            label = organs[o].label;
          }
        }
        background_fraction[index] = static_cast<float>(empty);
        out.labels[index] = label;
      }
  return out;
}

} // namespace

// Level sets straight from a patch surface: the fractions' volume against the exact enclosed
// volume (printed beside the tessellated path's), and the distance near zero on the surface.
TEST(PatchLevelSet, FractionsGiveTheVolumeAndTheDistanceIsNearZeroOnTheSurface) {
  const PatchSurface surface = bumpy_sphere();
  const double exact = surface.volume();
  for (double h : {1.0, 0.5}) {
    const LevelSet direct(surface, h);
    const double direct_error = std::abs(fraction_volume(direct, h, 50.0) / exact - 1.0);
    const double tessellated_error =
        std::abs(fraction_volume(LevelSet(surface.tessellate(0.2), h), h, 50.0) / exact - 1.0);
    std::printf("bumpy sphere, voxel %g mm: volume error %.2e direct, %.2e tessellated within 0.2 mm\n", h,
                direct_error, tessellated_error);
    // Bumps a few voxels wide: the trilinear samples of the exact distance round their crests
    // off (measured 1.2e-3 at 1 mm, 2.6e-4 at 0.5 mm; on the head, whose bumps are wider, the
    // error is below the tessellated path's, README).
    EXPECT_LT(direct_error, h > 0.75 ? 2e-3 : 5e-4);
    const LevelSet::Probe probe(direct);
    double worst = 0.0;
    for (Eigen::Index t = 0; t < surface.patch_count(); t += 7)
      for (const Eigen::Vector2d& uv : {Eigen::Vector2d(1.0 / 3.0, 1.0 / 3.0), Eigen::Vector2d(0.4, 0.2)})
        worst = std::max(worst, std::abs(probe(surface.surface_point(t, uv.x(), uv.y()))));
    std::printf("largest |distance| on the surface: %.3f mm\n", worst);
    EXPECT_LT(worst, 0.15 * h);
  }
}

class ShapeVolume : public ::testing::TestWithParam<Eigen::Vector3d> {};

TEST_P(ShapeVolume, FractionsGiveTheVolumeWithinHalfAPercentAtOneMillimetreAndConverge) {
  const Eigen::Vector3d radii = GetParam();
  const TriangleMesh mesh = ellipsoid_mesh(radii);
  const double exact = enclosed_volume(mesh);
  const double extent = 2.0 * radii.maxCoeff() + 8.0;
  std::vector<double> errors;
  for (double h : {2.0, 1.0, 0.5}) {
    const double error = std::abs(fraction_volume(LevelSet(mesh, h), h, extent) / exact - 1.0);
    std::printf("radii (%g, %g, %g) voxel %g mm: relative volume error %.2e\n", radii.x(), radii.y(),
                radii.z(), h, error);
    errors.push_back(error);
  }
  EXPECT_LT(errors[1], 5e-3);
  // Observed order over the two halvings (mean of log2 ratios).
  const double order = 0.5 * (std::log2(errors[0] / errors[1]) + std::log2(errors[1] / errors[2]));
  std::printf("observed order %.2f\n", order);
  EXPECT_GT(order, 1.7); // observed 2.0: the surface error of the sampling falls with h^2
}

INSTANTIATE_TEST_SUITE_P(SphereAndEllipsoid, ShapeVolume,
                         ::testing::Values(Eigen::Vector3d(20, 20, 20), Eigen::Vector3d(24, 17, 12)));

TEST(LevelSet, SignedDistanceGradientHasLengthOneInTheNarrowBand) {
  const TriangleMesh mesh = ellipsoid_mesh({20, 20, 20});
  const LevelSet level_set(mesh, 1.0);
  const LevelSet::Probe probe(level_set);
  const TriangleMesh directions = unit_icosphere(2);
  for (Eigen::Index d = 0; d < directions.vertex_count(); ++d) {
    for (double offset : {-1.5, -0.7, 0.0, 0.6, 1.4}) { // mm from the surface, inside the 3-voxel band
      const Eigen::Vector3d x = (20.0 + offset) * directions.vertex(d);
      const Eigen::Vector3d g = central_difference_gradient(probe, x, 0.5);
      EXPECT_NEAR(g.norm(), 1.0, 0.01) << x.transpose();
      EXPECT_NEAR(probe(x), offset, 0.05) << x.transpose();
    }
  }
  // The band stores the shell within half_width of the surface: about its volume in voxels.
  const double w = level_set.half_width_mm();
  const double shell_voxels = 4.0 / 3.0 * M_PI * (std::pow(20.0 + w, 3) - std::pow(20.0 - w, 3));
  std::printf("narrow band: %zu active voxels, shell of half width %g mm: %.0f voxels\n",
              level_set.active_voxel_count(), w, shell_voxels);
  EXPECT_NEAR(static_cast<double>(level_set.active_voxel_count()) / shell_voxels, 1.0, 0.05);
}

// LevelSet::Probe reads stencils within one leaf straight from it and tiles from one lookup:
// its value must be OpenVDB's own trilinear sample bit for bit, at random points (inside, in the
// band, across leaf boundaries, in tiles deep inside and outside) and on the lattice itself.
TEST(LevelSet, ProbeIsOpenVdbsTrilinearSampleBitForBit) {
  const PatchSurface surface = bumpy_sphere();
  const LevelSet level_set(surface, 0.7);
  const auto& grid = *static_cast<const openvdb::FloatGrid*>(level_set.grid());
  const openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(grid);
  const LevelSet::Probe probe(level_set);
  std::mt19937 random(17);
  std::uniform_real_distribution<double> coordinate(-30.0, 30.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 200000; ++i)
    points.emplace_back(coordinate(random), coordinate(random), coordinate(random));
  for (int i = -40; i <= 40; ++i)
    for (int j = -40; j <= 40; j += 3)
      points.emplace_back(0.7 * i, 0.7 * j, 0.7 * ((i * j) % 17)); // lattice points, leaf edges included
  // Clusters of 4^3 samples a voxel apart, as the tissue fractions take them: most share the
  // previous sample's stencil, which the probe keeps.
  for (int c = 0; c < 3000; ++c) {
    const Eigen::Vector3d centre(coordinate(random), coordinate(random), coordinate(random));
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        for (int d = 0; d < 4; ++d)
          points.push_back(centre + 0.25 * Eigen::Vector3d(a - 1.5, b - 1.5, d - 1.5));
  }
  int in_band = 0;
  for (const Eigen::Vector3d& x : points) {
    const double expected = static_cast<double>(sampler.wsSample(openvdb::Vec3d(x.x(), x.y(), x.z())));
    ASSERT_EQ(probe(x), expected) << x.transpose();
    in_band += std::abs(expected) < level_set.half_width_mm();
  }
  EXPECT_GT(in_band, 10000); // the band itself was sampled, not only tiles
}

// LevelSet::Probe::lattice reads a lattice's stencils once and interpolates axis by axis; each
// value must be the probe's at that point bit for bit, and lattice_inside (which skips the
// interpolation where every corner has one sign) the probe's sign. Lattices of 1 to 6 points a
// side, spaced from a tenth of a voxel to two voxels (stencils spanning up to 12 cells), in the
// band, across leaf boundaries, in tiles deep inside and outside, and reaching beyond the blocks.
TEST(LevelSet, LatticeIsTheProbeAtEachPointBitForBit) {
  const PatchSurface surface = bumpy_sphere();
  const LevelSet level_set(surface, 0.7);
  const LevelSet::Probe probe(level_set), lattice_probe(level_set);
  std::mt19937 random(23);
  std::uniform_real_distribution<double> coordinate(-32.0, 32.0), spacing(0.07, 1.4), radius(17.0, 23.0);
  std::uniform_int_distribution<int> side(1, 6);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int compared = 0, in_band = 0, inside = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    Eigen::Vector3d origin(coordinate(random), coordinate(random), coordinate(random));
    if (trial % 2) // half of them near the surface
      origin = radius(random) * Eigen::Vector3d(unit(random), unit(random), unit(random)).normalized();
    const int n[3] = {side(random), side(random), side(random)};
    std::vector<double> axis[3];
    for (int a = 0; a < 3; ++a) {
      const double step = spacing(random);
      for (int i = 0; i < n[a]; ++i)
        axis[a].push_back(origin[a] + step * (i - 0.5 * (n[a] - 1)));
    }
    const std::size_t count = static_cast<std::size_t>(n[0] * n[1] * n[2]);
    std::vector<float> values(count);
    std::vector<std::uint8_t> signs(count);
    lattice_probe.lattice(axis[0].data(), n[0], axis[1].data(), n[1], axis[2].data(), n[2], values.data());
    lattice_probe.lattice_inside(axis[0].data(), n[0], axis[1].data(), n[1], axis[2].data(), n[2],
                                 signs.data());
    for (int c = 0; c < n[2]; ++c)
      for (int b = 0; b < n[1]; ++b)
        for (int a = 0; a < n[0]; ++a) {
          const Eigen::Vector3d x(axis[0][static_cast<std::size_t>(a)], axis[1][static_cast<std::size_t>(b)],
                                  axis[2][static_cast<std::size_t>(c)]);
          const double expected = probe(x);
          const std::size_t at = static_cast<std::size_t>(a + n[0] * (b + n[1] * c));
          ASSERT_EQ(bits(values[at]), bits(static_cast<float>(expected))) << x.transpose();
          ASSERT_EQ(signs[at] != 0, expected < 0.0) << x.transpose();
          ++compared;
          in_band += std::abs(expected) < level_set.half_width_mm();
          inside += expected < 0.0;
        }
  }
  EXPECT_GT(in_band, 50000);
  EXPECT_GT(inside, 50000);
  EXPECT_GT(compared - inside, 50000);
}

// Many bumps on every patch, off centre and elongated, as fitted anatomy carries them (there,
// 27 per patch): the level set built from the patches, whose heights sum only the bumps that
// reach the point's cell of the patch, is near zero on the surface, over the crests and between
// them. (A bump left out where it reaches would leave an error of its amplitude, 0.3 to 0.6 mm.)
TEST(PatchLevelSet, ManyBumpsPerPatchAreAllOnTheSurface) {
  std::vector<std::vector<Eigen::Vector2d>> centres;
  const PatchSurface surface = many_bumps_surface(&centres);
  std::mt19937 random(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double h = 0.25;
  const LevelSet level_set(surface, h);
  const LevelSet::Probe probe(level_set);
  double worst = 0.0;
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t) {
    std::vector<Eigen::Vector2d> uvs = centres[static_cast<std::size_t>(t)];
    for (int i = 0; i < 200; ++i) {
      const double u = unit(random), v = unit(random);
      if (u + v < 1.0) uvs.emplace_back(u, v);
    }
    for (const Eigen::Vector2d& uv : uvs)
      worst = std::max(worst, std::abs(probe(surface.surface_point(t, uv.x(), uv.y()))));
  }
  std::printf("largest |distance| on the surface: %.3f mm\n", worst);
  EXPECT_LT(worst, 0.3 * h);
}

/// The many-bumps surface's level set at 0.25 mm voxels beside the signed distance to a
/// tessellation of the surface within 0.005 mm: the reference for the values stored in the band.
struct ManyBumpsBand {
  static SignedDistanceMesh fine_signed_distance(const PatchSurface& surface) {
    const TriangleMesh fine = surface.tessellate(0.005);
    SignedDistanceMesh exact(fine.faces);
    exact.update(fine.vertices);
    exact.build_search_tree();
    return exact;
  }
  std::vector<std::vector<Eigen::Vector2d>> centres;
  const PatchSurface surface = many_bumps_surface(&centres);
  const double h = 0.25;
  const LevelSet level_set{surface, h};
  const SignedDistanceMesh exact = fine_signed_distance(surface);
  const openvdb::FloatGrid& grid = *static_cast<const openvdb::FloatGrid*>(level_set.grid());
};

// The values the level set stores in its band are the signed distance to the patch surface, not
// only their sign: against the distance to a tessellation within 0.005 mm, at every stored voxel
// of the many-bumps surface within 2 voxels of it (narrow, elongated bumps 0.3 to 0.6 mm high
// on 1.5 to 2.5 mm wide supports, the hardest case for the closest-point search on a patch).
TEST(PatchLevelSet, BandValuesAreTheDistanceToTheSurface) {
  const ManyBumpsBand band;
  const double h = band.h;
  std::vector<double> errors;
  for (auto it = band.grid.cbeginValueOn(); it; ++it) {
    if (std::abs(*it) > 2.0 * h) continue;
    const openvdb::Coord c = it.getCoord();
    const Eigen::Vector3d x = h * Eigen::Vector3d(c.x(), c.y(), c.z());
    errors.push_back(std::abs(static_cast<double>(*it) - band.exact.signed_distance(x)));
  }
  ASSERT_GT(errors.size(), 10000u);
  std::sort(errors.begin(), errors.end());
  const double p99 = errors[errors.size() * 99 / 100], worst = errors.back();
  std::size_t far = 0;
  for (double e : errors)
    far += e > 0.02 ? 1 : 0;
  std::printf("%zu band voxels: distance error median %.4f, 99th percentile %.4f, largest %.4f mm; "
              "%zu over 0.02 mm\n",
              errors.size(), errors[errors.size() / 2], p99, worst, far);
  // Measured: 99th percentile 0.0016 mm, largest 0.037 mm (a point whose closest surface point
  // lies on a neighbouring patch: each voxel is measured to the patch of its closest base
  // triangle). Newton steps from the start instead of after two Gauss-Newton steps: largest
  // 0.18 mm, a farther local minimum of the distance to a bump.
  EXPECT_LT(p99, 0.005);
  EXPECT_LT(worst, 0.2 * h);
}

// The test above picks voxels by the value the level set stores; this one by their true distance,
// so a voxel near the surface that stores too large a value is found too. Voxels along the
// normals of the many-bumps surface's patches (every base triangle, random points, 1.5 mm each
// side), those within 2 voxels of the fine tessellation: each must hold its distance. A voxel
// high above a bump's foot but beside its flank lies a band width or more above the surface
// point below it while the flank is nearer: a value taken along the normal there is the band
// width, clamped, where the distance is a voxel or less (measured that way: largest error 0.42 mm,
// 83 voxels over a fifth of a voxel; on the Colin head's scalp, whose patches bend far from their
// base, about 800 label voxels of a population subject then changed with the band's width, 16
// with the distance measured to the patch).
TEST(PatchLevelSet, EveryVoxelNearTheSurfaceHoldsItsDistance) {
  const ManyBumpsBand band;
  const double h = band.h;
  const PatchSurface& surface = band.surface;
  const auto accessor = band.grid.getConstAccessor();
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<openvdb::Coord> voxels;
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t) {
    const PatchFrame frame = surface.frame(t);
    for (int i = 0; i < 400; ++i) {
      const double u = unit(random), v = unit(random);
      if (u + v >= 1.0) continue;
      const Eigen::Vector3d base = frame.origin + u * frame.edge1 + v * frame.edge2;
      for (double offset = -1.5; offset <= 1.5; offset += 0.5 * h) {
        const Eigen::Vector3d x = (base + offset * frame.normal) / h;
        voxels.emplace_back(static_cast<int>(std::lround(x.x())), static_cast<int>(std::lround(x.y())),
                            static_cast<int>(std::lround(x.z())));
      }
    }
  }
  std::sort(voxels.begin(), voxels.end());
  voxels.erase(std::unique(voxels.begin(), voxels.end()), voxels.end());
  std::size_t near = 0, wrong = 0;
  double worst = 0.0;
  for (const openvdb::Coord& c : voxels) {
    const double d = band.exact.signed_distance(h * Eigen::Vector3d(c.x(), c.y(), c.z()));
    if (std::abs(d) > 2.0 * h) continue;
    ++near;
    const double error = std::abs(static_cast<double>(accessor.getValue(c)) - d);
    worst = std::max(worst, error);
    wrong += error > 0.2 * h ? 1 : 0;
  }
  std::printf("%zu voxels within 2 voxels of the surface: largest error %.4f mm, %zu over a fifth of a "
              "voxel\n",
              near, worst, wrong);
  ASSERT_GT(near, 15000u);
  EXPECT_EQ(wrong, 0u);
  EXPECT_LT(worst, 0.2 * h);
}

/// A cube of side 2 a centred on the origin, outward triangles, turned by `angle` about `axis`.
TriangleMesh turned_cube(double a, const Eigen::Vector3d& axis, double angle) {
  TriangleMesh cube;
  cube.vertices.resize(8, 3);
  for (int v = 0; v < 8; ++v)
    cube.vertices.row(v) = Eigen::Vector3d(v & 1 ? a : -a, v & 2 ? a : -a, v & 4 ? a : -a).transpose();
  cube.faces.resize(12, 3);
  cube.faces << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1,
      3, 5, 3, 7, 5;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  cube.vertices = cube.vertices * turn.transpose();
  return cube;
}

// The band's candidates must enclose the surface on every face, whatever its direction. A face
// whose normal is all but perpendicular to the x axis (x component 1e-10, as a flat cap fitted to
// labels cut by the grid can have) once marked no candidate at all: an integer conversion of a
// number far beyond int's range left a hole in the shell, and the flood fill carried the outside's
// sign through it, so the cube's inside read as outside (the Colin head's neck lost thousands of
// voxels so, up to 32 mm deep). Every voxel farther than half a voxel from the faces must take the
// sign of its side.
TEST(PatchLevelSet, EveryFaceEnclosesTheInsideWhateverItsDirection) {
  const double a = 10.0, h = 1.0;
  const std::vector<Eigen::Vector3d> axes{Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(),
                                          Eigen::Vector3d(1, 1, 0)};
  for (const Eigen::Vector3d& axis : axes) {
    for (const double angle : {0.0, 1e-12, 1e-10, 1e-8, 1e-5, 0.3}) {
      const TriangleMesh cube = turned_cube(a, axis, angle);
      const PatchSurface surface(cube, "cube");
      const LevelSet level_set(surface, h);
      const LevelSet::Probe probe(level_set);
      const Eigen::Matrix3d back = Eigen::AngleAxisd(-angle, axis.normalized()).toRotationMatrix();
      int wrong = 0, checked = 0;
      for (int k = -16; k <= 16; ++k)
        for (int j = -16; j <= 16; ++j)
          for (int i = -16; i <= 16; ++i) {
            const Eigen::Vector3d x(i + 0.25, j + 0.25, k + 0.25);
            const double inside_by = a - (back * x).cwiseAbs().maxCoeff(); // > 0 inside
            if (std::abs(inside_by) < 0.5 * h) continue;
            ++checked;
            if ((probe(x) < 0.0) != (inside_by > 0.0)) ++wrong;
          }
      EXPECT_EQ(wrong, 0) << "axis " << axis.transpose() << ", angle " << angle << ": " << wrong << " of "
                          << checked << " voxels on the wrong side";
    }
  }
}

// The tissue fractions read each organ at a block's voxel centres, and at a voxel's samples,
// as lattices where the grid's axes are the world's; they must be the bytes of probing every
// point one by one (probe_every_sample), on such grids and on oblique ones (point by point),
// with anisotropic voxels and 1 to 5 samples a side. Two overlapping organs at one depth
// (the later one wins) inside a third, and a gap organ (no tissue) within it.
TEST(TissueFractions, LatticesGiveTheBytesOfProbingEverySample) {
  const auto sphere = [](double radius, const Eigen::Vector3d& centre) {
    return sphere_level_set(radius, centre, 0.8);
  };
  const LevelSet outer = sphere(11.0, Eigen::Vector3d::Zero());
  const LevelSet left = sphere(4.5, Eigen::Vector3d(-2.5, 0.3, 0.0));
  const LevelSet right = sphere(4.0, Eigen::Vector3d(2.0, -0.4, 0.7));
  const LevelSet gap = sphere(2.0, Eigen::Vector3d(0.0, 6.0, 0.0));
  const std::vector<VoxelizedOrgan> organs{
      {&outer, 0, 1, 0}, {&left, 2, 2, 1}, {&right, 2, 3, 2}, {&gap, 1, 4, -1}};
  const Eigen::Matrix3d oblique =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(1.0, 2.0, 0.5).normalized()).toRotationMatrix();
  struct Case {
    Eigen::Vector3d spacing;
    bool rotated;
    int supersampling;
  };
  for (const Case& c :
       {Case{{0.8, 0.8, 0.8}, false, 4}, Case{{1.0, 0.7, 2.1}, false, 3}, Case{{0.5, 0.5, 0.5}, false, 5},
        Case{{0.9, 0.9, 0.9}, true, 4}, Case{{1.3, 0.6, 0.8}, false, 1}, Case{{0.8, 0.8, 1.6}, true, 2}}) {
    ImageGrid grid;
    grid.spacing_mm = c.spacing;
    grid.dims = (Eigen::Vector3d::Constant(26.0).cwiseQuotient(c.spacing)).cast<int>();
    const Eigen::Matrix3d axes = (c.rotated ? oblique : Eigen::Matrix3d::Identity()) * c.spacing.asDiagonal();
    grid.world_from_voxel.topLeftCorner<3, 3>() = axes;
    grid.world_from_voxel.topRightCorner<3, 1>() =
        -axes * (0.5 * grid.dims.cast<double>()) + Eigen::Vector3d(0.31, -0.17, 0.05);
    const DenseTissues expected = probe_every_sample(grid, organs, 3, c.supersampling);
    const TissueVolumes v = voxelize_tissues(grid, organs, 3, c.supersampling);
    SCOPED_TRACE(::testing::Message() << "spacing " << c.spacing.transpose() << (c.rotated ? ", oblique" : "")
                                      << ", " << c.supersampling << "^3 samples");
    expect_same_bytes(v, expected);
    EXPECT_EQ(v.supersampled_voxels, expected.supersampled_voxels);
    // Only sampled voxels can be partial, and the dense fractions compacted are what is held.
    EXPECT_LE(v.partial_voxels.size(), v.supersampled_voxels);
    EXPECT_EQ(v.label_tissues, (std::vector<int>{-1, 0, 1, 2, -1}));
    const TissueVolumes compacted =
        compact_tissue_volumes(expected.labels, v.label_tissues, expected.fractions);
    EXPECT_EQ(v.partial_voxels, compacted.partial_voxels);
    EXPECT_EQ(bits(v.partial_fractions), bits(compacted.partial_fractions));
    EXPECT_GT(expected.supersampled_voxels, 1000u);
    for (int label = 1; label <= 4; ++label)
      EXPECT_GT(std::count(v.labels.begin(), v.labels.end(), label), 5) << label;
  }
}

// Outside every box of LevelSet::block_reach_mm a probe reads constant tiles: exactly the band
// width, negative inside. The tissue fractions rely on it to read an organ once per block.
TEST(LevelSet, OutsideEveryBlockReachTheProbeIsTheBandWidth) {
  const PatchSurface surface = bumpy_sphere();
  const LevelSet level_set(surface, 0.7);
  const std::vector<Eigen::AlignedBox3d> reach = level_set.block_reach_mm();
  ASSERT_FALSE(reach.empty());
  const LevelSet::Probe probe(level_set);
  const auto band = static_cast<double>(static_cast<float>(level_set.half_width_mm()));
  std::mt19937 random(5);
  std::uniform_real_distribution<double> coordinate(-30.0, 30.0);
  int inside = 0, outside = 0;
  for (int i = 0; i < 100000; ++i) {
    const Eigen::Vector3d x(coordinate(random), coordinate(random), coordinate(random));
    if (std::any_of(reach.begin(), reach.end(), [&](const Eigen::AlignedBox3d& b) { return b.contains(x); }))
      continue;
    const double value = probe(x);
    ASSERT_EQ(std::abs(value), band) << x.transpose();
    // The side: the sphere's radius is 20 mm, its bumps 0.6 mm high.
    EXPECT_EQ(value < 0.0, x.norm() < 20.0) << x.transpose();
    (value < 0.0 ? inside : outside) += 1;
  }
  EXPECT_GT(inside, 1000);
  EXPECT_GT(outside, 10000);
}

// The deformed state reuses the reference's voxels where no organ differs: an outer organ that
// stays (one level set for both states), an inner one that moves, and the gap it leaves. The
// result must be the bytes of sampling every voxel again, and fewer voxels are sampled.
TEST(TissueFractions, ReusingTheOtherStatesVoxelsGivesTheSameBytes) {
  const auto sphere = [](double radius, const Eigen::Vector3d& centre) {
    return sphere_level_set(radius, centre, 1.0);
  };
  const LevelSet outer = sphere(25.0, Eigen::Vector3d::Zero());
  const LevelSet inner = sphere(6.0, Eigen::Vector3d(-2.0, 0.0, 0.0));
  const LevelSet inner_moved = sphere(6.0, Eigen::Vector3d(2.0, 1.0, 0.0));
  ImageGrid grid;
  grid.dims = {64, 60, 62};
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(-31.7, -29.4, -30.5);
  // depth, label, tissue: the outer organ at depth 0, the inner at 2, the gap between them.
  const std::vector<VoxelizedOrgan> reference_organs{{&outer, 0, 1, 0}, {&inner, 2, 2, 1}};
  const std::vector<VoxelizedOrgan> deformed_organs{
      {&outer, 0, 1, 0}, {&inner_moved, 2, 2, 1}, {&inner, 1, 3, 2}};
  const TissueVolumes reference = voxelize_tissues(grid, reference_organs, 3, 4);
  const TissueVolumes fresh = voxelize_tissues(grid, deformed_organs, 3, 4);
  const TissueVolumes reused = voxelize_tissues(grid, deformed_organs, 3, 4, {&reference, &reference_organs});
  EXPECT_EQ(reused.labels, fresh.labels);
  EXPECT_EQ(reused.label_tissues, fresh.label_tissues);
  EXPECT_EQ(reused.partial_voxels, fresh.partial_voxels);
  EXPECT_EQ(bits(reused.partial_fractions), bits(fresh.partial_fractions));
  EXPECT_GT(reused.partial_voxels.size(), reused.supersampled_voxels); // partial voxels copied too
  EXPECT_NE(fresh.labels, reference.labels);                           // the inner organ moved and left a gap
  EXPECT_GT(std::count(fresh.labels.begin(), fresh.labels.end(), 3), 100);
  std::printf("voxels sampled: %zu fresh, %zu with the reference's reused; %zu partial voxels\n",
              fresh.supersampled_voxels, reused.supersampled_voxels, reused.partial_voxels.size());
  EXPECT_LT(10 * reused.supersampled_voxels,
            7 * fresh.supersampled_voxels); // most of the outer surface copied
}
