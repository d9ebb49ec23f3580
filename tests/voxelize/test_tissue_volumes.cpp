// How TissueVolumes holds the fractions: dense labels, and the fractions only of the voxels
// that are not whole. Every accessor must give back the dense fractions bit for bit, and a
// voxelization's fractions must sum to 1 in every voxel.

#include "tests/support/sphere_level_set.hpp"
#include "voxelize/tissue_volumes.hpp"
#include "voxelize/voxelized_phantom.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

using namespace phantasm;
using namespace phantasm::testing;

namespace {

std::uint32_t float_bits(float x) {
  std::uint32_t b = 0;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

/// Every voxel's row (every tissue's fraction, then the background's) as for_each_voxel()
/// passes it over [first, last), checking that it visits each voxel once, in order.
std::vector<std::vector<float>> visited_rows(const TissueVolumes& v, std::size_t first, std::size_t last) {
  std::vector<std::vector<float>> rows;
  std::size_t next = first;
  v.for_each_voxel(first, last, [&](std::size_t voxel, const float* fractions) {
    EXPECT_EQ(voxel, next);
    ++next;
    rows.emplace_back(fractions, fractions + v.fractions_per_voxel());
  });
  EXPECT_EQ(next, last);
  return rows;
}

} // namespace

// A hand-made volume: whole voxels of each label (two labels of one tissue, a gap of air with no
// tissue, the background) are not stored; mixed voxels, a voxel whose one tissue is not its
// label's, and a -0 (the same value, other bits) are. Every accessor reads the dense values.
TEST(TissueVolumes, CompactFractionsReadBackAsTheDenseOnes) {
  // Labels 1 and 3 hold tissue 0, label 2 tissue 1, label 4 (a gap of air) and 0 none.
  const std::vector<int> label_tissues{-1, 0, 1, 0, -1};
  const std::vector<std::int32_t> labels{0, 1, 2, 3, 4, 1, 0, 1, 2, 4, 2, 1};
  // Per voxel: tissue 0, tissue 1, background.
  const std::vector<std::vector<float>> rows{{0.0f, 0.0f, 1.0f},   {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f},
                                             {1.0f, 0.0f, 0.0f},   {0.0f, 0.0f, 1.0f}, {0.75f, 0.25f, 0.0f},
                                             {0.25f, 0.0f, 0.75f}, {0.0f, 1.0f, 0.0f}, {-0.0f, 1.0f, 0.0f},
                                             {0.0f, 0.5f, 0.5f},   {0.0f, 1.0f, 0.0f}, {0.5f, 0.25f, 0.25f}};
  std::vector<std::vector<float>> dense(3, std::vector<float>(labels.size()));
  for (std::size_t voxel = 0; voxel < labels.size(); ++voxel)
    for (std::size_t t = 0; t < 3; ++t)
      dense[t][voxel] = rows[voxel][t];
  const TissueVolumes v = compact_tissue_volumes(labels, label_tissues, dense);
  EXPECT_EQ(v.tissue_count, 2);
  EXPECT_EQ(v.fractions_per_voxel(), 3u);
  EXPECT_EQ(v.labels, labels);
  EXPECT_EQ(v.partial_voxels, (std::vector<std::size_t>{5, 6, 7, 8, 9, 11}));
  ASSERT_EQ(v.partial_fractions.size(), 3 * v.partial_voxels.size());
  for (std::size_t voxel = 0; voxel < labels.size(); ++voxel) {
    for (int t = 0; t <= v.tissue_count; ++t)
      EXPECT_EQ(float_bits(v.fraction(t, voxel)), float_bits(rows[voxel][static_cast<std::size_t>(t)]))
          << "voxel " << voxel << ", tissue " << t;
    EXPECT_EQ(float_bits(v.background(voxel)), float_bits(rows[voxel][2])) << voxel;
    EXPECT_EQ(v.whole(labels[voxel], rows[voxel].data()),
              !std::binary_search(v.partial_voxels.begin(), v.partial_voxels.end(), voxel))
        << voxel;
  }
  for (int t = 0; t <= v.tissue_count; ++t) {
    const std::vector<float> volume = v.fraction_volume(t);
    ASSERT_EQ(volume.size(), labels.size());
    double sum = 0.0;
    for (std::size_t voxel = 0; voxel < labels.size(); ++voxel) {
      EXPECT_EQ(float_bits(volume[voxel]), float_bits(dense[static_cast<std::size_t>(t)][voxel]));
      sum += dense[static_cast<std::size_t>(t)][voxel];
    }
    EXPECT_EQ(v.fraction_sum(t), sum) << t;
  }
  // Every range, partial voxels at its ends or not.
  for (std::size_t first = 0; first <= labels.size(); ++first)
    for (std::size_t last = first; last <= labels.size(); ++last) {
      const std::vector<std::vector<float>> visited = visited_rows(v, first, last);
      ASSERT_EQ(visited.size(), last - first);
      for (std::size_t n = 0; n < visited.size(); ++n)
        for (std::size_t t = 0; t < 3; ++t)
          EXPECT_EQ(float_bits(visited[n][t]), float_bits(rows[first + n][t]))
              << "voxel " << first + n << " of [" << first << ", " << last << "), tissue " << t;
    }
}

// A voxelization's fractions: every tissue's and the background's sum to 1 within float
// rounding in every voxel, and the accessors agree with each other: fraction(), background(),
// fraction_volume() and the traversal. Two organs of one tissue, one nested, and a gap of air.
TEST(TissueVolumes, VoxelizedFractionsSumToOneAndEveryAccessorAgrees) {
  constexpr double voxel_mm = 0.9;
  // Centres and radii (mm): an outer sphere holding two of one tissue and a gap of air.
  const LevelSet spheres[] = {sphere_level_set(10.0, Eigen::Vector3d::Zero(), voxel_mm),
                              sphere_level_set(4.0, Eigen::Vector3d(-4.0, 0.2, 0.0), voxel_mm),
                              sphere_level_set(3.5, Eigen::Vector3d(4.0, -0.3, 0.5), voxel_mm),
                              sphere_level_set(2.0, Eigen::Vector3d(0.0, 6.0, 0.0), voxel_mm)};
  // depth, label, tissue: labels 2 and 3 hold one tissue; the gap (label 4) holds none.
  const std::vector<VoxelizedOrgan> organs{
      {&spheres[0], 0, 1, 0}, {&spheres[1], 2, 2, 1}, {&spheres[2], 2, 3, 1}, {&spheres[3], 1, 4, -1}};
  ImageGrid grid;
  grid.dims = {26, 24, 25};
  grid.spacing_mm = Eigen::Vector3d::Constant(voxel_mm);
  grid.world_from_voxel.topLeftCorner<3, 3>() = voxel_mm * Eigen::Matrix3d::Identity();
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d(-11.3, -10.1, -10.9);
  const TissueVolumes v = voxelize_tissues(grid, organs, 2, 4);
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  ASSERT_EQ(v.labels.size(), count);
  EXPECT_EQ(v.label_tissues, (std::vector<int>{-1, 0, 1, 1, -1}));
  EXPECT_GT(v.partial_voxels.size(), 500u);
  EXPECT_LT(v.partial_voxels.size(), count / 4); // most voxels are whole: not stored
  EXPECT_TRUE(std::is_sorted(v.partial_voxels.begin(), v.partial_voxels.end()));
  EXPECT_EQ(std::adjacent_find(v.partial_voxels.begin(), v.partial_voxels.end()), v.partial_voxels.end());
  std::vector<std::vector<float>> volumes;
  for (int t = 0; t <= v.tissue_count; ++t)
    volumes.push_back(v.fraction_volume(t));
  const std::vector<std::vector<float>> rows = visited_rows(v, 0, count);
  ASSERT_EQ(rows.size(), count);
  std::size_t partial = 0;
  for (std::size_t voxel = 0; voxel < count; ++voxel) {
    double sum = 0.0;
    for (int t = 0; t <= v.tissue_count; ++t) {
      const float f = v.fraction(t, voxel);
      ASSERT_EQ(float_bits(f), float_bits(rows[voxel][static_cast<std::size_t>(t)])) << voxel;
      ASSERT_EQ(float_bits(f), float_bits(volumes[static_cast<std::size_t>(t)][voxel])) << voxel;
      EXPECT_GE(f, 0.0f);
      sum += f;
    }
    EXPECT_EQ(float_bits(v.background(voxel)), float_bits(rows[voxel].back())) << voxel;
    EXPECT_NEAR(sum, 1.0, 4 * FLT_EPSILON) << voxel;
    // A whole voxel holds its label's tissue alone; a stored one does not.
    const bool stored = std::binary_search(v.partial_voxels.begin(), v.partial_voxels.end(), voxel);
    EXPECT_NE(stored, v.whole(v.labels[voxel], rows[voxel].data())) << voxel;
    partial += stored ? 1 : 0;
  }
  EXPECT_EQ(partial, v.partial_voxels.size());
  for (int label = 1; label <= 4; ++label)
    EXPECT_GT(std::count(v.labels.begin(), v.labels.end(), label), 5) << label;
}

// No organ in the grid (a scene of open sheets): every voxel is whole background, read through
// every accessor.
TEST(TissueVolumes, AGridWithoutOrgansIsWholeBackground) {
  ImageGrid grid;
  grid.dims = {9, 8, 7};
  const TissueVolumes v = voxelize_tissues(grid, {}, 2, 4);
  EXPECT_EQ(v.label_tissues, std::vector<int>{-1});
  EXPECT_TRUE(v.partial_voxels.empty());
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  EXPECT_EQ(v.fraction_volume(2), std::vector<float>(count, 1.0f));
  EXPECT_EQ(v.fraction_volume(0), std::vector<float>(count, 0.0f));
  EXPECT_EQ(v.fraction_sum(2), static_cast<double>(count));
  for (std::size_t voxel = 0; voxel < count; ++voxel) {
    EXPECT_EQ(v.background(voxel), 1.0f);
    EXPECT_EQ(v.fraction(1, voxel), 0.0f);
  }
}
