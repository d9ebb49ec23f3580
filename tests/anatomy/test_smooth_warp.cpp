// Seeded variation of label volumes and meshes (anatomy/smooth_warp.hpp): a bounded, one-to-one
// warp, the same for every organ, so nested labels stay nested; a function of the seed alone.

#include "anatomy/smooth_warp.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include <random>
#include <set>

using namespace phantasm;

namespace {

/// A 2 mm label volume: a ball of label 2 (radius 20 mm) inside a ball of label 1 (radius 35 mm).
ShapeData nested_balls() {
  ShapeData data;
  ImageGrid grid;
  grid.dims = Eigen::Vector3i(48, 48, 48);
  grid.spacing_mm = Eigen::Vector3d::Constant(2.0);
  grid.world_from_voxel = Eigen::Matrix4d::Identity();
  grid.world_from_voxel.topLeftCorner<3, 3>() *= 2.0;
  grid.world_from_voxel.topRightCorner<3, 1>() = Eigen::Vector3d::Constant(-47.0);
  std::vector<std::int32_t> labels(static_cast<std::size_t>(grid.voxel_count()), 0);
  for (int k = 0; k < 48; ++k)
    for (int j = 0; j < 48; ++j)
      for (int i = 0; i < 48; ++i) {
        const double r = grid.world_from_index(Eigen::Vector3d(i, j, k)).norm();
        labels[voxel_index(grid.dims, i, j, k)] = r < 20.0 ? 2 : r < 35.0 ? 1 : 0;
      }
  data.label_grid = grid;
  data.labels = std::make_shared<const std::vector<std::int32_t>>(std::move(labels));
  data.source = "nested balls";
  return data;
}

} // namespace

TEST(SmoothWarp, BoundedOneToOneAndZeroOutsideItsWindow) {
  const SmoothWarp warp(7, 4.0, Eigen::Vector3d::Constant(-50.0), Eigen::Vector3d::Constant(50.0));
  ASSERT_FALSE(warp.identity());
  EXPECT_GT(warp.amplitude_mm(), 1.0);
  EXPECT_LE(warp.amplitude_mm(), 4.0);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> coordinate(-60.0, 60.0);
  double largest = 0.0, largest_gradient = 0.0;
  for (int n = 0; n < 2000; ++n) {
    const Eigen::Vector3d x(coordinate(random), coordinate(random), coordinate(random));
    const Eigen::Vector3d d = warp.displacement(x);
    largest = std::max(largest, d.norm());
    if ((x.array().abs() >= 50.0).any()) {
      EXPECT_EQ(d, Eigen::Vector3d::Zero()) << x.transpose();
    }
    Eigen::Matrix3d gradient;
    const double h = 1e-4;
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d step = Eigen::Vector3d::Unit(a) * h;
      gradient.col(a) = (warp.displacement(x + step) - warp.displacement(x - step)) / (2.0 * h);
    }
    largest_gradient = std::max(largest_gradient, gradient.operatorNorm());
    EXPECT_GT((Eigen::Matrix3d::Identity() + gradient).determinant(), 0.0) << x.transpose();
  }
  EXPECT_LE(largest, warp.amplitude_mm() + 1e-12);
  EXPECT_GT(largest, 0.2 * warp.amplitude_mm()); // it does move things
  EXPECT_LT(largest_gradient, 0.5);
  EXPECT_TRUE(SmoothWarp().identity());
}

TEST(SmoothWarp, LabelVolumesVaryBySeedAndStayNested) {
  std::map<std::string, ShapeData> files{{"outer", nested_balls()}, {"inner", nested_balls()}};
  files["inner"].labels = files["outer"].labels; // one volume, two organs
  EXPECT_TRUE(draw_shape_warp(files, 0.0, 1).identity());
  const auto warp1 = draw_shape_warp(files, 0.05, 1);
  const auto warp2 = draw_shape_warp(files, 0.05, 2);
  const auto a = warped_shapes(files, warp1);
  const auto a_again = warped_shapes(files, draw_shape_warp(files, 0.05, 1));
  const auto b = warped_shapes(files, warp2);
  EXPECT_EQ(a.at("inner").labels, a.at("outer").labels); // still one volume
  EXPECT_EQ(*a.at("outer").labels, *a_again.at("outer").labels);
  EXPECT_NE(*a.at("outer").labels, *files.at("outer").labels);
  EXPECT_NE(*a.at("outer").labels, *b.at("outer").labels);
  const ImageGrid& grid = *files.at("outer").label_grid;
  for (const auto* warped : {&a, &b}) {
    const std::vector<std::int32_t>& labels = *warped->at("outer").labels;
    std::map<std::int32_t, std::size_t> count, before;
    for (std::int32_t l : labels)
      ++count[l];
    for (std::int32_t l : *files.at("outer").labels)
      ++before[l];
    for (std::int32_t l : {1, 2}) {
      EXPECT_NEAR(static_cast<double>(count[l]), static_cast<double>(before[l]), 0.25 * before[l]) << l;
    }
    // Nested: no voxel of the inner ball touches the outside (label 0) across a face.
    std::size_t touching = 0;
    for (int k = 1; k < 47; ++k)
      for (int j = 1; j < 47; ++j)
        for (int i = 1; i < 47; ++i) {
          if (labels[voxel_index(grid.dims, i, j, k)] != 2) continue;
          for (const Eigen::Vector3i& n :
               {Eigen::Vector3i(i - 1, j, k), Eigen::Vector3i(i + 1, j, k), Eigen::Vector3i(i, j - 1, k),
                Eigen::Vector3i(i, j + 1, k), Eigen::Vector3i(i, j, k - 1), Eigen::Vector3i(i, j, k + 1)})
            touching += labels[voxel_index(grid.dims, n.x(), n.y(), n.z())] == 0;
        }
    EXPECT_EQ(touching, 0u);
    // The volume's faces stay empty (a label on the edge is refused).
    for (int j = 0; j < 48; ++j)
      for (int i = 0; i < 48; ++i) {
        EXPECT_EQ(labels[voxel_index(grid.dims, i, j, 0)], 0);
        EXPECT_EQ(labels[voxel_index(grid.dims, i, j, 47)], 0);
      }
  }
}

TEST(SmoothWarp, MeshVerticesMoveByTheWarp) {
  std::map<std::string, ShapeData> files;
  ShapeData mesh;
  mesh.mesh.emplace();
  mesh.mesh->vertices.resize(4, 3);
  mesh.mesh->vertices << 0, 0, 0, 30, 0, 0, 0, 30, 0, 0, 0, 30;
  mesh.mesh->faces.resize(4, 3);
  mesh.mesh->faces << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  files["tet"] = mesh;
  const SmoothWarp warp = draw_shape_warp(files, 0.05, 4);
  ASSERT_FALSE(warp.identity());
  const auto moved = warped_shapes(files, warp);
  double largest = 0.0;
  for (Eigen::Index v = 0; v < 4; ++v) {
    const Eigen::Vector3d x = files.at("tet").mesh->vertex(v);
    EXPECT_EQ(moved.at("tet").mesh->vertex(v), x - warp.displacement(x));
    largest = std::max(largest, warp.displacement(x).norm());
  }
  EXPECT_GT(largest, 0.0);
  EXPECT_EQ(moved.at("tet").mesh->faces, files.at("tet").mesh->faces);
}
