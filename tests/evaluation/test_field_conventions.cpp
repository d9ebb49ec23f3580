// Field conventions, the tetrahedral folding test and the misreading warnings on analytic fields:
// every convention written and read back is the same field; a fold between two voxels that
// central differences miss is measured; each usual misreading of a smooth field is named.

#include "core/error.hpp"
#include "evaluation/digital_jacobian.hpp"
#include "evaluation/field_conventions.hpp"
#include "evaluation/score_task.hpp"
#include "tests/support/files.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <set>

using namespace phantasm;

namespace {

/// A grid with anisotropic voxels and a rotated, non-RAS orientation (so that voxels, RAS and LPS
/// differ on every axis).
ImageGrid oblique_grid(const Eigen::Vector3i& dims) {
  ImageGrid grid;
  grid.dims = dims;
  grid.spacing_mm = Eigen::Vector3d(2.0, 1.5, 3.0);
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(1.0, 2.0, 0.5).normalized()).toRotationMatrix();
  grid.world_from_voxel.topLeftCorner<3, 3>() = rotation * grid.spacing_mm.asDiagonal();
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(-20.0, 7.0, 3.0);
  return grid;
}

/// A smooth bump in the middle of the grid, up to `amplitude` voxels along (1, 0.5, -0.3).
DisplacementField bump(const ImageGrid& grid, double amplitude) {
  std::vector<Eigen::Vector3d> ras(static_cast<std::size_t>(grid.voxel_count()));
  const Eigen::Vector3d centre = 0.5 * (grid.dims.cast<double>() - Eigen::Vector3d::Ones());
  const Eigen::Matrix3d ras_from_index = grid.world_from_voxel.topLeftCorner<3, 3>();
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const double r2 = (Eigen::Vector3d(i, j, k) - centre).squaredNorm();
        const Eigen::Vector3d u_index = amplitude * std::exp(-r2 / 18.0) * Eigen::Vector3d(1.0, 0.5, -0.3);
        ras[voxel_index(grid.dims, i, j, k)] = ras_from_index * u_index;
      }
  return field_from_ras(grid, ras);
}

std::vector<bool> everywhere(const ImageGrid& grid) {
  return std::vector<bool>(static_cast<std::size_t>(grid.voxel_count()), true);
}

} // namespace

TEST(FieldConventions, EveryConventionReadsBackTheFieldItWrote) {
  const ImageGrid grid = oblique_grid({9, 8, 7});
  const DisplacementField field = bump(grid, 2.0);
  const auto folder = phantasm::testing::fresh_folder("field-conventions");
  for (const FieldConventionType* type : field_convention_types()) {
    const FieldConvention c = type->convention;
    const auto path = folder / (to_string(c) + ".nii.gz");
    write_field(path, field, c);
    const DisplacementField back = read_field(path, c, grid);
    double worst = 0.0;
    for (std::size_t v = 0; v < field.lps_mm.size(); ++v)
      worst = std::max(worst, (back.lps_mm[v] - field.lps_mm[v]).norm());
    EXPECT_LT(worst, 1e-4) << to_string(c); // float32 on disk
    EXPECT_EQ(field_convention_from_string(to_string(c), "--convention"), c);
  }
  // Read in another convention, the same file is another field (the conventions differ).
  const DisplacementField misread =
      read_field(folder / "learn2reg.nii.gz", FieldConvention::mrtrix_displacement, grid);
  double largest = 0.0;
  for (std::size_t v = 0; v < field.lps_mm.size(); ++v)
    largest = std::max(largest, (misread.lps_mm[v] - field.lps_mm[v]).norm());
  EXPECT_GT(largest, 0.5);
  EXPECT_THROW(field_convention_from_string("ants", "--convention"), InputError);
}

TEST(FieldConventions, EveryMemberHasItsOwnNameHelpAndBothDirections) {
  std::set<std::string> names;
  const std::string help = field_convention_help(FieldConvention::learn2reg);
  EXPECT_EQ(help.find("Convention of the result fields: learn2reg (default), "), 0u) << help;
  for (const FieldConventionType* type : field_convention_types()) {
    EXPECT_TRUE(names.insert(type->name).second) << type->name;
    EXPECT_EQ(&field_convention_type(type->convention), type);
    EXPECT_EQ(to_string(type->convention), type->name);
    EXPECT_GT(std::string(type->description).size(), 10u) << type->name;
    EXPECT_NE(type->stored, nullptr) << type->name;
    EXPECT_NE(type->displacement, nullptr) << type->name;
    EXPECT_NE(help.find(type->name), std::string::npos) << help;
  }
}

TEST(FieldConventions, AFileReadInAConventionItIsConfusedWithIsAnotherField) {
  const ImageGrid grid = oblique_grid({9, 8, 7});
  const DisplacementField field = bump(grid, 2.0);
  const auto folder = phantasm::testing::fresh_folder("field-confusions");
  for (const FieldConventionType* type : field_convention_types()) {
    const auto path = folder / (std::string(type->name) + ".nii.gz");
    write_field(path, field, type->convention);
    // A file of the 4-D layout can be read in any 4-D convention: each names what it is taken for.
    if (type->components_in_fourth_dimension) EXPECT_FALSE(type->confusions.empty()) << type->name;
    for (const FieldConfusion& confusion : type->confusions) {
      EXPECT_NE(confusion.with, type->convention) << type->name;
      EXPECT_FALSE(std::string(confusion.mistake).empty()) << type->name;
      const DisplacementField misread = read_field(path, confusion.with, grid);
      double largest = 0.0;
      for (std::size_t v = 0; v < field.lps_mm.size(); ++v)
        largest = std::max(largest, (misread.lps_mm[v] - field.lps_mm[v]).norm());
      EXPECT_GT(largest, 0.5) << type->name << " read as " << to_string(confusion.with);
    }
  }
}

TEST(FieldConventions, AFieldOfAnotherGridOrWithNanIsRefusedNamingTheFile) {
  const ImageGrid grid = oblique_grid({6, 5, 4});
  const auto folder = phantasm::testing::fresh_folder("field-conventions-bad");
  write_field(folder / "small.nii.gz", bump(oblique_grid({5, 5, 4}), 1.0), FieldConvention::learn2reg);
  try {
    read_field(folder / "small.nii.gz", FieldConvention::learn2reg, grid);
    FAIL() << "a field of another grid was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("small.nii.gz: expected a field on the fixed grid (6 x 5 x 4"),
              std::string::npos)
        << e.what();
  }
  DisplacementField nan = bump(grid, 1.0);
  nan.lps_mm[voxel_index(grid.dims, 2, 3, 1)].x() = std::nan("");
  write_field(folder / "nan.nii.gz", nan, FieldConvention::learn2reg);
  try {
    read_field(folder / "nan.nii.gz", FieldConvention::learn2reg, grid);
    FAIL() << "a NaN field was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nan.nii.gz: expected finite"), std::string::npos) << e.what();
  }
  // A 5-D ITK file read as Learn2Reg (4-D) names the layout it expected.
  write_field(folder / "itk.nii.gz", bump(grid, 1.0), FieldConvention::itk);
  EXPECT_THROW(read_field(folder / "itk.nii.gz", FieldConvention::learn2reg, grid), InputError);
}

TEST(DigitalJacobian, AFoldBetweenVoxelsThatCentralDifferencesMissIsMeasured) {
  ImageGrid grid;
  grid.dims = Eigen::Vector3i(10, 4, 4);
  // x -> x + 1.5 at odd i: positions 0, 2.5, 2, 4.5, 4, ...: every cube from an odd to an even
  // index is turned inside out along i (width -0.5), the others are stretched (width 2.5).
  std::vector<Eigen::Vector3d> ras(static_cast<std::size_t>(grid.voxel_count()), Eigen::Vector3d::Zero());
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 1; i < 10; i += 2)
        ras[voxel_index(grid.dims, i, j, k)].x() = 1.5;
  const DisplacementField field = field_from_ras(grid, ras);
  std::vector<bool> region = everywhere(grid);
  const JacobianStatistics central = jacobian_statistics(field, region);
  const FoldingVolume ndv = non_diffeomorphic_volume(field, region);
  // Central differences see (x(i+1) - x(i-1)) / 2 = 1 inside and one-sided 2.5 at the borders:
  // no fold anywhere.
  EXPECT_EQ(central.folding_voxels, 0);
  // Cubes: 9 along i (4 of them odd -> even), 3 x 3 across: 36 folded of 81, each by volume 0.5.
  EXPECT_EQ(ndv.cubes, 81);
  EXPECT_EQ(ndv.folded_cubes, 36);
  EXPECT_NEAR(ndv.ndv_voxels, 36 * 0.5, 1e-9);
  EXPECT_NEAR(ndv.ndv_percent, 100.0 * 18.0 / 81.0, 1e-9);

  // A mirror image folds every cube by its whole volume; a smooth bump folds none.
  std::vector<Eigen::Vector3d> mirror(ras.size(), Eigen::Vector3d::Zero());
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 10; ++i)
        mirror[voxel_index(grid.dims, i, j, k)].x() = -2.0 * i;
  const FoldingVolume all = non_diffeomorphic_volume(field_from_ras(grid, mirror), region);
  EXPECT_EQ(all.folded_cubes, 81);
  EXPECT_NEAR(all.ndv_percent, 100.0, 1e-9);
  const ImageGrid oblique = oblique_grid({9, 8, 7});
  EXPECT_EQ(non_diffeomorphic_volume(bump(oblique, 1.0), everywhere(oblique)).folded_cubes, 0);
}

TEST(Misreadings, EachUsualMistakeIsNamedAndTheTruthDrawsNone) {
  const ImageGrid grid = oblique_grid({16, 15, 14});
  const DisplacementField truth = bump(grid, 2.0);
  const std::vector<bool> mask = everywhere(grid);
  EXPECT_TRUE(likely_misreadings(truth, truth, mask).empty());

  const std::vector<Eigen::Vector3d> t = ras_displacements(truth);
  const Eigen::Matrix3d ras_from_index = grid.world_from_voxel.topLeftCorner<3, 3>();
  const Eigen::Matrix3d index_from_ras = ras_from_index.inverse();
  auto in_voxels = [&](auto change) {
    std::vector<Eigen::Vector3d> r(t.size());
    for (std::size_t v = 0; v < t.size(); ++v)
      r[v] = ras_from_index * change(Eigen::Vector3d(index_from_ras * t[v]));
    return field_from_ras(grid, r);
  };
  auto named = [&](const DisplacementField& result) {
    const std::vector<Misreading> m = likely_misreadings(result, truth, mask);
    return m.empty() ? std::string("(none)") : m.front().mistake;
  };
  auto expect_named = [&](const DisplacementField& result, const std::string& fragment) {
    const std::string name = named(result);
    EXPECT_NE(name.find(fragment), std::string::npos) << "expected " << fragment << ", found " << name;
  };
  const Eigen::Vector3d spacing = grid.spacing_mm;
  expect_named(in_voxels([](Eigen::Vector3d u) { return Eigen::Vector3d(-u); }), "inverse direction");
  expect_named(in_voxels([&](Eigen::Vector3d u) { return Eigen::Vector3d(u.cwiseProduct(spacing)); }),
               "in mm where voxels are expected");
  expect_named(in_voxels([](Eigen::Vector3d u) { return Eigen::Vector3d(-u.x(), u.y(), u.z()); }),
               "component i reversed");
  expect_named(in_voxels([](Eigen::Vector3d u) { return Eigen::Vector3d(u.z(), u.y(), u.x()); }),
               "order (k, j, i)");
  expect_named(in_voxels([](Eigen::Vector3d u) { return Eigen::Vector3d(u + Eigen::Vector3d(0, 1, 0)); }),
               "constant offset of (0, 1, 0) voxels");
  // A field of another shape altogether is wrong but no misreading of the truth: no name.
  std::vector<Eigen::Vector3d> other(t.size(), ras_from_index * Eigen::Vector3d(0.3, -0.8, 0.5));
  EXPECT_EQ(named(field_from_ras(grid, other)), "(none)");
}
