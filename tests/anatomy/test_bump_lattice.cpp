// BumpLattice: the bumps it leaves out of a point's cell are zero there as computed, so the sums
// over a cell's bumps (patch function, gradient, height) are bit for bit the sums over every bump.

#include "anatomy/bump_lattice.hpp"
#include "anatomy/patch_surface.hpp"
#include "geometry/triangle_mesh.hpp"
#include "tests/support/patch_bumps.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

using namespace phantasm;
using namespace phantasm::testing;

namespace {

/// 1-30 random bumps of both signs: round and elongated, wide and very narrow (the eigenvalues
/// of S from 4 to 4e5), centred anywhere in the triangle, some at its edges and corners.
std::vector<PatchBump> random_bumps(std::mt19937& random, int count) {
  return phantasm::testing::random_bumps(random, count, 4.0, 1e5, -1.5, 2.5);
}

/// Q as the level sets compute it (PatchBump::add_height, S made symmetric).
double q_of_heights(const PatchBump& b, const Eigen::Vector2d& uv) {
  const Eigen::Matrix2d S = 0.5 * (b.shape_uv + b.shape_uv.transpose());
  const Eigen::Vector2d d = uv - b.center_uv;
  return 1.0 - d.dot(S * d);
}

/// The fitting basis of anatomy/patch_fit on every triangle of a sphere: the incircles of the
/// sub-triangles of levels 0-2 (21 nested discs per patch) with random amplitudes.
PatchSurface fitted_sphere() {
  TriangleMesh mesh = unit_icosphere(1);
  mesh.vertices *= 30.0;
  PatchSurface surface(mesh, "fitted sphere");
  std::mt19937 random(3);
  std::uniform_real_distribution<double> amplitude(-0.8, 0.8);
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t) {
    std::vector<PatchBump> bumps;
    for (const BasisDisc& disc : fitting_basis_discs(2))
      bumps.push_back(disc_in_triangle(surface.base_mesh(), t, disc.center_uv, 0.9 / disc.subdivisions,
                                       amplitude(random)));
    surface.set_bumps(t, bumps);
  }
  return surface;
}

} // namespace

TEST(BumpLattice, ABumpLeftOutOfAPointsCellIsZeroThereAsComputed) {
  std::mt19937 random(17);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> cell_line(0, BumpLattice::k_cells);
  std::size_t listed = 0, checked = 0;
  for (int patch = 0; patch < 200; ++patch) {
    const std::vector<PatchBump> bumps = random_bumps(random, 1 + patch % 30);
    const BumpLattice lattice(bumps);
    for (int sample = 0; sample < 400; ++sample) {
      // Random points, a quarter of them on cell lines (where rounding decides the cell).
      Eigen::Vector2d uv(unit(random), unit(random));
      if (sample % 4 == 0) uv.x() = double(cell_line(random)) / BumpLattice::k_cells;
      if (sample % 4 == 1) uv.y() = double(cell_line(random)) / BumpLattice::k_cells;
      const BumpLattice::Bumps near = lattice.at(uv.x(), uv.y());
      ASSERT_TRUE(std::is_sorted(near.begin(), near.end()));
      listed += near.size();
      checked += bumps.size();
      for (std::uint32_t n = 0; n < bumps.size(); ++n) {
        if (std::binary_search(near.begin(), near.end(), n)) continue;
        const PatchBump& b = bumps[n];
        ASSERT_LE(q_of_heights(b, uv), 0.0) << "patch " << patch << " bump " << n << " at " << uv.transpose();
        ASSERT_LE(b.shape_value(uv), 0.0) << "patch " << patch << " bump " << n;
        ASSERT_LE(b.quadric().value(Eigen::Vector3d(uv.x(), uv.y(), unit(random) - 0.5)), 0.0)
            << "patch " << patch << " bump " << n;
      }
    }
  }
  // Narrow bumps reach few cells: a cell lists under a third of its patch's bumps on average.
  EXPECT_LT(static_cast<double>(listed), checked / 3.0);
}

TEST(BumpLattice, PointsOffTheSquareAndNotANumberGetEveryBump) {
  std::mt19937 random(5);
  const std::vector<PatchBump> bumps = random_bumps(random, 12);
  const BumpLattice lattice(bumps);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [u, v] : {std::pair{-0.5, 0.2}, std::pair{0.2, 1.5}, std::pair{nan, 0.3},
                             std::pair{0.3, nan}, std::pair{-1e-300, 0.0}}) {
    const BumpLattice::Bumps all = lattice.at(u, v);
    ASSERT_EQ(all.size(), bumps.size()) << u << ", " << v;
    for (std::uint32_t n = 0; n < bumps.size(); ++n)
      EXPECT_EQ(all.begin()[n], n);
  }
  EXPECT_EQ(BumpLattice().at(0.5, 0.5).size(), 0u);
  EXPECT_EQ(BumpLattice(std::vector<PatchBump>()).at(0.5, 0.5).size(), 0u);
}

TEST(BumpLattice, ABumpThatIsNotPositiveDefiniteIsListedEverywhere) {
  std::vector<PatchBump> bumps(3);
  bumps[0].center_uv = {0.31, 0.31};
  bumps[0].shape_uv << 400.0, 0.0, 0.0, 400.0; // narrow: a few cells
  bumps[1].shape_uv << 1.0, 2.0, 2.0, 1.0;     // indefinite
  bumps[2].shape_uv << 1.0, 1.0, 1.0, 1.0;     // singular
  const BumpLattice lattice(bumps);
  for (int j = 0; j < BumpLattice::k_cells; ++j) {
    for (int i = 0; i < BumpLattice::k_cells; ++i) {
      const BumpLattice::Bumps cell = lattice.cell(i, j);
      const bool narrow_listed = cell.size() == 3;
      ASSERT_GE(cell.size(), 2u);
      EXPECT_EQ(cell.end()[-1], 2u);
      EXPECT_EQ(cell.end()[-2], 1u);
      // Radius 0.05 around (0.31, 0.31): cell 2 (0.25-0.375) on both axes only.
      EXPECT_EQ(narrow_listed, i == 2 && j == 2) << i << ", " << j;
    }
  }
}

// The patch function, its gradient and the heights sum a cell's bumps only: the same terms in
// the same order as the sums over every bump, so the same bits.
TEST(PatchSurface, ValuesGradientsAndHeightsAreTheSumsOverEveryBumpBitForBit) {
  const PatchSurface surface = fitted_sphere();
  std::mt19937 random(23);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::size_t listed = 0, every = 0;
  for (Eigen::Index t = 0; t < surface.patch_count(); ++t) {
    const PatchFrame f = surface.frame(t);
    const std::vector<PatchBump>& bumps = surface.bumps(t);
    std::vector<Quadric> quadrics;
    for (const PatchBump& b : bumps)
      quadrics.push_back(b.quadric());
    for (int sample = 0; sample < 200; ++sample) {
      double u = unit(random), v = unit(random);
      if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
      const Eigen::Vector3d x = f.origin + u * f.edge1 + v * f.edge2 + (2.0 * unit(random) - 1.0) * f.normal;
      // value() and gradient() as written, over every bump.
      const Eigen::Vector3d uvw = surface.local_coordinates(t, x);
      double F = -f.length_scale * uvw.z();
      Eigen::Vector3d d_local(0.0, 0.0, -f.length_scale);
      for (std::size_t n = 0; n < bumps.size(); ++n) {
        const double q = quadrics[n].value(uvw);
        if (q <= 0.0) continue;
        F += bumps[n].amplitude_mm * q * q * q;
        d_local += 3.0 * bumps[n].amplitude_mm * q * q * quadrics[n].gradient(uvw);
      }
      const Eigen::Vector3d gradient = f.local_from_world.transpose() * d_local;
      ASSERT_EQ(surface.value(t, x), F) << "triangle " << t;
      ASSERT_EQ(surface.gradient(t, x), gradient) << "triangle " << t;
      // The height: g(0) = -0 + sum a Q(u, v)^3 (no quadric depends on w, so that is the root).
      double h = -0.0;
      for (std::size_t n = 0; n < bumps.size(); ++n) {
        const double q = quadrics[n].value(Eigen::Vector3d(u, v, 0.0));
        if (q > 0.0) h += bumps[n].amplitude_mm * q * q * q;
      }
      ASSERT_EQ(surface.height(t, u, v), h) << "triangle " << t;
      listed += surface.bump_lattice(t).at(u, v).size();
      every += bumps.size();
    }
  }
  // The fitting basis's 21 discs: a few reach any one cell.
  EXPECT_LT(static_cast<double>(listed), every / 2.0);
}
