// Tet meshes of nested shapes (mesh_nested_solid): tissue per tet, interfaces as faces, subdomain
// volumes against the analytic ones, repeatability and quality.
#include "anatomy/phantom.hpp"
#include "anatomy/structured_mesh.hpp"
#include "anatomy/tet_mesh.hpp"
#include "core/grid.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <vector>

using namespace phantasm;

namespace {

constexpr double k_outer_mm = 20.0;
constexpr double k_inner_mm = 12.0;
const Eigen::Vector3d k_inner_centre(2.0, -1.0, 1.5);

/// A ball of radius 20 mm holding a ball of radius 12 mm off its centre.
struct TwoSpheres {
  std::unique_ptr<ImplicitShape> outer = make_ellipsoid(
      Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(k_outer_mm), Eigen::Matrix3d::Identity());
  std::unique_ptr<ImplicitShape> inner =
      make_ellipsoid(k_inner_centre, Eigen::Vector3d::Constant(k_inner_mm), Eigen::Matrix3d::Identity());
  NestedShapes nested{{outer.get(), inner.get()}, {-1, 0}};
};

Eigen::Vector3d centroid(const TetMesh& mesh, Eigen::Index t) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k)
    c += 0.25 * mesh.vertices.row(mesh.tets(t, k)).transpose();
  return c;
}

/// Volume of each subdomain's tets, mm^3.
std::vector<double> subdomain_volumes(const TetMesh& mesh, std::size_t shapes) {
  std::vector<double> volume(shapes, 0.0);
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    volume[static_cast<std::size_t>(mesh.subdomains[t])] += tet_volume(mesh, t);
  return volume;
}

TEST(NestedTetMesh, EveryTetTakesTheShapeThatHoldsItsCentroid) {
  const TwoSpheres spheres;
  const TetMesh mesh = mesh_nested_solid(spheres.nested, criteria_for_tet_size(3.0), 7);
  ASSERT_EQ(mesh.subdomains.size(), mesh.tets.rows());
  int per_shape[2] = {0, 0};
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    ASSERT_GT(tet_volume(mesh, t), 0.0);
    EXPECT_EQ(mesh.subdomains[t], spheres.nested.innermost(centroid(mesh, t))) << "tet " << t;
    ++per_shape[mesh.subdomains[t]];
  }
  EXPECT_GT(per_shape[0], 0);
  EXPECT_GT(per_shape[1], 0);
}

TEST(NestedTetMesh, InterfaceFacesLieOnTheInnerSphereWithinTheFacetDistance) {
  const TwoSpheres spheres;
  const TetMeshCriteria criteria = criteria_for_tet_size(3.0);
  const TetMesh mesh = mesh_nested_solid(spheres.nested, criteria, 7);
  const Eigen::MatrixX3i interface = subdomain_interface_faces(mesh);
  ASSERT_GT(interface.rows(), 50);
  double area = 0.0;
  for (Eigen::Index f = 0; f < interface.rows(); ++f) {
    Eigen::Vector3d corner[3];
    for (int k = 0; k < 3; ++k) {
      corner[k] = mesh.vertices.row(interface(f, k)).transpose();
      EXPECT_NEAR((corner[k] - k_inner_centre).norm(), k_inner_mm, 1e-3) << "face " << f;
    }
    const Eigen::Vector3d middle = (corner[0] + corner[1] + corner[2]) / 3.0;
    EXPECT_LE(k_inner_mm - (middle - k_inner_centre).norm(), criteria.facet_distance_mm) << "face " << f;
    // Oriented outward of the inner ball (subdomain 0 is the outer shell, so outward of it is
    // toward the inner ball's centre).
    area += 0.5 *
            (corner[1] - corner[0]).cross(corner[2] - corner[0]).dot((middle - k_inner_centre).normalized());
  }
  // Closed: the faces cover the sphere (area within 3 %), all facing one way.
  EXPECT_NEAR(std::abs(area), 4.0 * M_PI * k_inner_mm * k_inner_mm,
              0.03 * 4.0 * M_PI * k_inner_mm * k_inner_mm);
  // The boundary is the outer sphere's only.
  for (Eigen::Index f = 0; f < mesh.boundary_faces.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(mesh.vertices.row(mesh.boundary_faces(f, k)).norm(), k_outer_mm, 1e-3);
}

TEST(NestedTetMesh, SubdomainVolumesConvergeToTheAnalyticOnesAsTetsShrink) {
  const TwoSpheres spheres;
  const double inner = 4.0 / 3.0 * M_PI * std::pow(k_inner_mm, 3);
  const double shell = 4.0 / 3.0 * M_PI * std::pow(k_outer_mm, 3) - inner;
  double previous[2] = {1.0, 1.0};
  for (double size : {8.0, 4.0, 2.0}) {
    const TetMesh mesh = mesh_nested_solid(spheres.nested, criteria_for_tet_size(size), 3);
    const std::vector<double> volume = subdomain_volumes(mesh, 2);
    const double error[2] = {std::abs(volume[0] - shell) / shell, std::abs(volume[1] - inner) / inner};
    for (int k = 0; k < 2; ++k) {
      EXPECT_LT(error[k], previous[k]) << "tet size " << size << " subdomain " << k;
      previous[k] = error[k];
    }
  }
  EXPECT_LT(previous[0], 0.02);
  EXPECT_LT(previous[1], 0.02);
}

TEST(NestedTetMesh, AThinLayerGetsTetsOfItsOwnAndItsVolumeOnceTetsAreAsThin) {
  // A 3 mm ellipsoidal shell: the interfaces are meshed, so at 8 mm tets the layer already has
  // tets of its own (though too few: tets that would span it are left out), and at tets of its
  // thickness its volume is within 6 % (0.3 % at 2 mm, measured).
  const auto outer =
      make_ellipsoid(Eigen::Vector3d::Zero(), Eigen::Vector3d(40, 35, 30), Eigen::Matrix3d::Identity());
  const auto inner =
      make_ellipsoid(Eigen::Vector3d::Zero(), Eigen::Vector3d(37, 32, 27), Eigen::Matrix3d::Identity());
  const NestedShapes nested{{outer.get(), inner.get()}, {-1, 0}};
  const double layer = 4.0 / 3.0 * M_PI * (40.0 * 35.0 * 30.0 - 37.0 * 32.0 * 27.0);
  const TetMesh coarse = mesh_nested_solid(nested, criteria_for_tet_size(8.0), 11);
  EXPECT_GT(subdomain_volumes(coarse, 2)[0], 0.5 * layer);
  const TetMesh fine = mesh_nested_solid(nested, criteria_for_tet_size(3.0), 11);
  EXPECT_NEAR(subdomain_volumes(fine, 2)[0], layer, 0.06 * layer);
  EXPECT_GE(min_dihedral_angle_deg(fine), 10.0);
}

TEST(NestedTetMesh, TheSameSeedGivesTheSameMeshBitForBit) {
  const TwoSpheres spheres;
  const TetMesh a = mesh_nested_solid(spheres.nested, criteria_for_tet_size(4.0), 5);
  const TetMesh b = mesh_nested_solid(spheres.nested, criteria_for_tet_size(4.0), 5);
  ASSERT_EQ(a.vertices.rows(), b.vertices.rows());
  ASSERT_EQ(a.tets.rows(), b.tets.rows());
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.tets, b.tets);
  EXPECT_EQ(a.subdomains, b.subdomains);
  EXPECT_EQ(a.boundary_faces, b.boundary_faces);
}

TEST(NestedTetMesh, NoDihedralAngleIsBelowTheQualityBound) {
  const TwoSpheres spheres;
  for (double size : {6.0, 3.0}) {
    const TetMesh mesh = mesh_nested_solid(spheres.nested, criteria_for_tet_size(size), 9);
    EXPECT_GE(min_dihedral_angle_deg(mesh), 10.0) << "tet size " << size;
  }
}

/// Label volumes as the Colin head has them: a container (label 1) holding two boxes whose labels
/// touch along the plane x = -0.5 mm (labels 2 and 3), each shape smoothed by 1 mm, each
/// container's labels the union of its own and those nested in it.
struct TouchingLabels {
  ImageGrid grid = make_centered_grid(Eigen::Vector3d::Constant(41.0), Eigen::Vector3d::Ones(),
                                      Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity());
  std::vector<std::int32_t> labels;
  std::unique_ptr<ImplicitShape> container, left, right;
  NestedShapes nested;
  TouchingLabels() {
    labels.assign(static_cast<std::size_t>(grid.voxel_count()), 0);
    for (int k = 0; k < grid.dims.z(); ++k)
      for (int j = 0; j < grid.dims.y(); ++j)
        for (int i = 0; i < grid.dims.x(); ++i) {
          const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
          std::int32_t label = 0;
          if (x.cwiseAbs().maxCoeff() <= 15.0) label = 1;
          if (std::abs(x.y()) <= 8.0 && std::abs(x.z()) <= 8.0 && x.x() >= -10.0 && x.x() <= 9.0)
            label = x.x() < 0.0 ? 2 : 3;
          labels[static_cast<std::size_t>((std::int64_t{k} * grid.dims.y() + j) * grid.dims.x() + i)] = label;
        }
    container = make_label_shape(grid, labels, {1, 2, 3}, 1.0, "container");
    left = make_label_shape(grid, labels, {2}, 1.0, "left");
    right = make_label_shape(grid, labels, {3}, 1.0, "right");
    nested = NestedShapes{{container.get(), left.get(), right.get()}, {-1, 0, 0}};
  }
};

TEST(NestedTetMesh, TouchingLabelsMeetWithoutASliverOfTheirContainerBetweenThem) {
  const TouchingLabels shapes;
  ASSERT_TRUE(shapes.left->smoothed_indicator());
  // On the plane where the labels meet, each smoothed indicator is about 1/2 and neither
  // shape's own inside test holds; the point goes to one of the two, never to the container.
  int left = 0, right = 0;
  for (double dx : {-0.05, 0.0, 0.05})
    for (double y = -5.0; y <= 5.0; y += 0.5)
      for (double z = -5.0; z <= 5.0; z += 0.5) {
        const Eigen::Vector3d x(-0.5 + dx, y, z);
        const int holder = shapes.nested.innermost(x);
        EXPECT_NE(holder, 0) << x.transpose() << ": left " << shapes.left->value(x) << ", right "
                             << shapes.right->value(x) << ", container " << shapes.container->value(x);
        left += holder == 1;
        right += holder == 2;
      }
  EXPECT_GT(left, 0);
  EXPECT_GT(right, 0);
  // Well inside each shape and in the container's own layer, the shapes' own tests decide.
  EXPECT_EQ(shapes.nested.innermost(Eigen::Vector3d(-5, 0, 0)), 1);
  EXPECT_EQ(shapes.nested.innermost(Eigen::Vector3d(5, 0, 0)), 2);
  EXPECT_EQ(shapes.nested.innermost(Eigen::Vector3d(12, 0, 0)), 0);
  EXPECT_EQ(shapes.nested.innermost(Eigen::Vector3d(0, 12, 0)), 0);
  EXPECT_EQ(shapes.nested.innermost(Eigen::Vector3d(0, 0, 18)), -1);
}

TEST(NestedTetMesh, TouchingLabelsAreMeshedWithAFaceBetweenThemAndTheirVolumes) {
  const TouchingLabels shapes;
  const TetMesh mesh = mesh_nested_solid(shapes.nested, criteria_for_tet_size(4.0, 0.75), 3);
  // Faces between the two boxes' tets, and no container tet where they meet.
  std::map<std::array<int, 3>, int> region_of_face;
  int shared = 0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    ASSERT_GT(tet_volume(mesh, t), 0.0);
    const Eigen::Vector3d c = centroid(mesh, t);
    if (mesh.subdomains[t] == 0) {
      EXPECT_FALSE(std::abs(c.x() + 0.5) < 0.75 && std::abs(c.y()) < 6.0 && std::abs(c.z()) < 6.0)
          << "a container tet between the boxes at " << c.transpose();
    }
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> face;
      for (int j = 0, m = 0; j < 4; ++j)
        if (j != k) face[static_cast<std::size_t>(m++)] = mesh.tets(t, j);
      std::sort(face.begin(), face.end());
      const auto [found, inserted] = region_of_face.emplace(face, mesh.subdomains[t]);
      if (!inserted && found->second + mesh.subdomains[t] == 3 && found->second != 0 &&
          mesh.subdomains[t] != 0)
        ++shared;
    }
  }
  EXPECT_GT(shared, 20) << "faces between the two boxes";
  // Each box is 10 x 17 x 17 mm of labels (voxel faces at x = -10.5, -0.5, 9.5; y, z = +-8.5):
  // its subdomain's volume within the rounding of 1 mm of smoothing at its edges.
  const std::vector<double> volume = subdomain_volumes(mesh, 3);
  EXPECT_NEAR(volume[1] / (10.0 * 17.0 * 17.0), 1.0, 0.1);
  EXPECT_NEAR(volume[2] / (10.0 * 17.0 * 17.0), 1.0, 0.1);
  EXPECT_GT(volume[0], 0.0);
}

} // namespace

/// A 4 mm cube of 1 mm cells in two subdomains, z < 0 (0) and z > 0 (1), their interface the
/// plane z = 0 made of faces; one vertex moved to make slivers.
struct SliverCube {
  TetMesh mesh = structured_box(Eigen::Vector3d::Constant(4.0), Eigen::Vector3i::Constant(4),
                                Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  std::function<int(const Eigen::Vector3d&)> label = [](const Eigen::Vector3d& x) {
    if (x.cwiseAbs().maxCoeff() > 2.0) return -1;
    return x.z() < 0.0 ? 0 : 1;
  };
  SliverCube() {
    mesh.subdomains.resize(mesh.tets.rows());
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
      mesh.subdomains[t] = centroid(mesh, t).z() < 0.0 ? 0 : 1;
  }
  Eigen::Index vertex_at(const Eigen::Vector3d& x) const {
    for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
      if ((mesh.vertices.row(v).transpose() - x).norm() < 1e-9) return v;
    return -1;
  }
};

TEST(SliverRemoval, AnInterfaceVertexMovesAlongItsInterfaceUntilNoSliverIsLeft) {
  SliverCube cube;
  const Eigen::Index v = cube.vertex_at(Eigen::Vector3d::Zero());
  ASSERT_GE(v, 0);
  cube.mesh.vertices.row(v) = Eigen::RowVector3d(0.8, 0.1, 0.0); // in the plane, near a neighbour
  for (Eigen::Index t = 0; t < cube.mesh.tets.rows(); ++t)
    ASSERT_GT(tet_volume(cube.mesh, t), 0.0);
  ASSERT_GT(tets_with_dihedral_below(cube.mesh, 10.0), 0);
  const Eigen::VectorXi subdomains = cube.mesh.subdomains;
  TetMesh again = cube.mesh;
  EXPECT_GT(improve_slivers(cube.mesh, cube.label, 10.0), 0);
  EXPECT_EQ(tets_with_dihedral_below(cube.mesh, 10.0), 0);
  EXPECT_NEAR(cube.mesh.vertices(v, 2), 0.0, 1e-6); // still on the interface
  EXPECT_EQ(cube.mesh.subdomains, subdomains);
  for (Eigen::Index t = 0; t < cube.mesh.tets.rows(); ++t) {
    EXPECT_GT(tet_volume(cube.mesh, t), 0.0);
    EXPECT_EQ(cube.label(centroid(cube.mesh, t)), cube.mesh.subdomains[t]);
  }
  improve_slivers(again, cube.label, 10.0); // the same mesh gives the same result
  EXPECT_EQ(again.vertices, cube.mesh.vertices);
}

TEST(SliverRemoval, AVertexInsideOneSubdomainMovesFreelyAndStaysInIt) {
  SliverCube cube;
  const Eigen::Index free = cube.vertex_at(Eigen::Vector3d(0.0, 0.0, -1.0)); // inside subdomain 0
  ASSERT_GE(free, 0);
  cube.mesh.vertices.row(free) = Eigen::RowVector3d(0.1, 0.1, -0.04); // nearly on the interface
  for (Eigen::Index t = 0; t < cube.mesh.tets.rows(); ++t)
    ASSERT_GT(tet_volume(cube.mesh, t), 0.0);
  const double before = min_dihedral_angle_deg(cube.mesh);
  ASSERT_LT(before, 10.0);
  improve_slivers(cube.mesh, cube.label, 10.0);
  EXPECT_GT(min_dihedral_angle_deg(cube.mesh), 10.0);
  EXPECT_LT(cube.mesh.vertices(free, 2), 0.0);
  for (Eigen::Index t = 0; t < cube.mesh.tets.rows(); ++t)
    EXPECT_GT(tet_volume(cube.mesh, t), 0.0);
}
