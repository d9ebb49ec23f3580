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
#include <set>
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

namespace {

using Face = std::array<int, 3>;

Face sorted_face(int a, int b, int c) {
  Face face{a, b, c};
  std::sort(face.begin(), face.end());
  return face;
}

/// The faces that belong to one tet only, as sorted triples.
std::set<Face> faces_of_one_tet(const TetMesh& mesh) {
  std::map<Face, int> count;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k) {
      int v[3], m = 0;
      for (int j = 0; j < 4; ++j)
        if (j != k) v[m++] = mesh.tets(t, j);
      ++count[sorted_face(v[0], v[1], v[2])];
    }
  std::set<Face> once;
  for (const auto& [face, n] : count)
    if (n == 1) once.insert(face);
  return once;
}

std::set<Face> boundary_face_set(const TetMesh& mesh) {
  std::set<Face> faces;
  for (Eigen::Index f = 0; f < mesh.boundary_faces.rows(); ++f)
    faces.insert(
        sorted_face(mesh.boundary_faces(f, 0), mesh.boundary_faces(f, 1), mesh.boundary_faces(f, 2)));
  return faces;
}

std::set<Face> interface_face_set(const TetMesh& mesh) {
  const Eigen::MatrixX3i faces = subdomain_interface_faces(mesh);
  std::set<Face> set;
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    set.insert(sorted_face(faces(f, 0), faces(f, 1), faces(f, 2)));
  return set;
}

double total_volume(const TetMesh& mesh) {
  double volume = 0.0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    volume += tet_volume(mesh, t);
  return volume;
}

/// The volume the boundary faces enclose (divergence theorem): the tets' volume when they are a
/// closed surface oriented outward.
double enclosed_volume(const TetMesh& mesh) {
  double volume = 0.0;
  for (Eigen::Index f = 0; f < mesh.boundary_faces.rows(); ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.boundary_faces(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.boundary_faces(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.boundary_faces(f, 2));
    volume += a.dot(b.cross(c)) / 6.0;
  }
  return volume;
}

/// Tets from rows of vertex indices, each turned positive.
TetMesh mesh_of(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector4i>& tets,
                const std::vector<int>& subdomains) {
  TetMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (std::size_t v = 0; v < points.size(); ++v)
    mesh.vertices.row(static_cast<Eigen::Index>(v)) = points[v].transpose();
  mesh.tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
  mesh.subdomains.resize(static_cast<Eigen::Index>(tets.size()));
  for (std::size_t t = 0; t < tets.size(); ++t) {
    const auto row = static_cast<Eigen::Index>(t);
    mesh.tets.row(row) = tets[t].transpose();
    if (tet_volume(mesh, row) < 0.0) std::swap(mesh.tets(row, 0), mesh.tets(row, 1));
    mesh.subdomains[row] = subdomains[t];
  }
  // Boundary faces, outward: the faces of one tet, oriented away from its fourth vertex.
  const std::set<Face> once = faces_of_one_tet(mesh);
  std::vector<Eigen::Vector3i> boundary;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k) {
      int v[3], m = 0;
      for (int j = 0; j < 4; ++j)
        if (j != k) v[m++] = mesh.tets(t, j);
      if (!once.count(sorted_face(v[0], v[1], v[2]))) continue;
      const Eigen::Vector3d a = mesh.vertices.row(v[0]), b = mesh.vertices.row(v[1]),
                            c = mesh.vertices.row(v[2]);
      const Eigen::Vector3d apex = mesh.vertices.row(mesh.tets(t, k));
      if ((b - a).cross(c - a).dot(apex - a) > 0.0) std::swap(v[1], v[2]);
      boundary.emplace_back(v[0], v[1], v[2]);
    }
  mesh.boundary_faces.resize(static_cast<Eigen::Index>(boundary.size()), 3);
  for (std::size_t f = 0; f < boundary.size(); ++f)
    mesh.boundary_faces.row(static_cast<Eigen::Index>(f)) = boundary[f].transpose();
  return mesh;
}

/// An equilateral triangle of unit circumradius in the plane z = 0, and two apexes on the line
/// through `foot` (a point of that plane) at z = -height and +height.
std::vector<Eigen::Vector3d> triangle_and_apexes(const Eigen::Vector3d& foot, double height) {
  return {Eigen::Vector3d(1.0, 0.0, 0.0), Eigen::Vector3d(-0.5, std::sqrt(3.0) / 2.0, 0.0),
          Eigen::Vector3d(-0.5, -std::sqrt(3.0) / 2.0, 0.0), foot - height * Eigen::Vector3d::UnitZ(),
          foot + height * Eigen::Vector3d::UnitZ()};
}

} // namespace

TEST(SliverRepair, AFlatTetOnTheBoundaryIsPeeledOffAndTheBoundaryStaysClosed) {
  TetMesh cube = structured_box(Eigen::Vector3d::Constant(4.0), Eigen::Vector3i::Constant(4),
                                Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  cube.subdomains = Eigen::VectorXi::Zero(cube.tets.rows());
  // Two boundary faces on the top (z = 2) sharing an edge (a, b) inside the top face: a and b are
  // lowered by 0.05 mm, and the valley above them filled by the flat tet (a, b, c, d).
  int a = -1, b = -1, c = -1, d = -1;
  const auto on_top_inside = [&](int v) {
    return std::abs(cube.vertices(v, 2) - 2.0) < 1e-9 &&
           cube.vertices.row(v).head<2>().cwiseAbs().maxCoeff() < 1.9;
  };
  for (Eigen::Index f = 0; f < cube.boundary_faces.rows() && a < 0; ++f)
    for (Eigen::Index g = f + 1; g < cube.boundary_faces.rows() && a < 0; ++g) {
      std::vector<int> shared, other;
      for (int i = 0; i < 3; ++i) {
        const int v = cube.boundary_faces(f, i);
        if ((cube.boundary_faces.row(g).array() == v).any())
          shared.push_back(v);
        else
          other.push_back(v);
      }
      if (shared.size() != 2 || !on_top_inside(shared[0]) || !on_top_inside(shared[1])) continue;
      for (int i = 0; i < 3; ++i)
        if (!(cube.boundary_faces.row(f).array() == cube.boundary_faces(g, i)).any())
          d = cube.boundary_faces(g, i);
      a = shared[0];
      b = shared[1];
      c = other[0];
    }
  ASSERT_GE(a, 0);
  cube.vertices(a, 2) -= 0.05;
  cube.vertices(b, 2) -= 0.05;
  const TetMesh before = cube;
  TetMesh mesh;
  {
    // The cube with the flat tet added last.
    std::vector<Eigen::Vector3d> points;
    for (Eigen::Index v = 0; v < cube.vertices.rows(); ++v)
      points.push_back(cube.vertices.row(v).transpose());
    std::vector<Eigen::Vector4i> tets;
    for (Eigen::Index t = 0; t < cube.tets.rows(); ++t)
      tets.push_back(cube.tets.row(t).transpose());
    tets.emplace_back(a, b, c, d);
    mesh = mesh_of(points, tets, std::vector<int>(tets.size(), 0));
  }
  const Eigen::Index flat = mesh.tets.rows() - 1;
  ASSERT_GT(tet_volume(mesh, flat), 0.0);
  ASSERT_LT(min_dihedral_angle_deg(mesh), 10.0);
  EXPECT_NEAR(enclosed_volume(mesh), total_volume(mesh), 1e-9);

  EXPECT_EQ(peel_boundary_slivers(mesh, 10.0), 1);
  EXPECT_EQ(mesh.tets, before.tets); // the cube's tets, in their order
  EXPECT_EQ(mesh.subdomains.size(), before.tets.rows());
  EXPECT_EQ(boundary_face_set(mesh), boundary_face_set(before));
  EXPECT_EQ(boundary_face_set(mesh), faces_of_one_tet(mesh));
  EXPECT_NEAR(enclosed_volume(mesh), total_volume(mesh), 1e-9); // closed, oriented outward
  EXPECT_EQ(peel_boundary_slivers(mesh, 10.0), 0);              // nothing flat is left there
}

TEST(SliverRepair, AFlatTetWhoseRemovalWouldPinchTheBoundaryStays) {
  // The flat tet (0, 1, 2, 3) (apex 3 0.05 mm under the triangle) has two boundary faces, (0, 1, 2)
  // and (0, 1, 3); its inner faces (0, 2, 3) and (1, 2, 3) lie on the tets (0, 2, 3, 5) and
  // (1, 2, 3, 6), whose faces (2, 3, 5) and (2, 3, 6) are boundary: peeling it would leave four
  // boundary faces at the edge (2, 3).
  std::vector<Eigen::Vector3d> points = triangle_and_apexes(Eigen::Vector3d::Zero(), 0.05);
  points.emplace_back(0.0, -3.0, -0.5); // 5, beyond the side (0, 2)
  points.emplace_back(-3.0, 0.0, -0.5); // 6, beyond the side (1, 2)
  const std::vector<Eigen::Vector4i> open = {Eigen::Vector4i(0, 1, 2, 3), Eigen::Vector4i(0, 2, 3, 5),
                                             Eigen::Vector4i(1, 2, 3, 6)};
  TetMesh mesh = mesh_of(points, open, {0, 0, 0});
  ASSERT_LT(min_dihedral_angle_deg(mesh), 10.0);
  EXPECT_EQ(peel_boundary_slivers(mesh, 10.0), 0);
  EXPECT_EQ(mesh.tets.rows(), 3);
  // With the tet (2, 3, 5, 6) closing the ring around the edge (2, 3), the edge is inside and
  // the flat tet comes off.
  std::vector<Eigen::Vector4i> closed = open;
  closed.emplace_back(2, 3, 5, 6);
  TetMesh ring = mesh_of(points, closed, {0, 0, 0, 0});
  for (Eigen::Index t = 0; t < ring.tets.rows(); ++t)
    ASSERT_GT(tet_volume(ring, t), 0.0) << t;
  ASSERT_NEAR(enclosed_volume(ring), total_volume(ring), 1e-9);
  EXPECT_EQ(peel_boundary_slivers(ring, 10.0), 1);
  EXPECT_EQ(ring.tets.rows(), 3);
  EXPECT_EQ(boundary_face_set(ring), faces_of_one_tet(ring));
  EXPECT_NEAR(enclosed_volume(ring), total_volume(ring), 1e-9);
}

TEST(SliverRepair, ALoneFlatTetBetweenAnotherRegionsTetsTakesTheirRegion) {
  // The flat tet (0, 1, 2, 3) (apex 3 0.05 mm under the triangle) in region 0, with a region-1 tet
  // on each of its four faces: above the triangle, and beyond each of its three sides.
  std::vector<Eigen::Vector3d> points = triangle_and_apexes(Eigen::Vector3d::Zero(), 0.05);
  points.emplace_back(0.0, -3.0, -0.5); // 5, beyond the side (0, 2)
  points.emplace_back(-3.0, 0.0, -0.5); // 6, beyond the side (1, 2)
  points.emplace_back(2.0, 2.5, -0.5);  // 7, beyond the side (0, 1)
  TetMesh mesh =
      mesh_of(points,
              {Eigen::Vector4i(0, 1, 2, 3), Eigen::Vector4i(0, 1, 2, 4), Eigen::Vector4i(0, 2, 3, 5),
               Eigen::Vector4i(1, 2, 3, 6), Eigen::Vector4i(0, 1, 3, 7)},
              {0, 1, 1, 1, 1});
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    ASSERT_GT(tet_volume(mesh, t), 0.0) << t;
  const std::array<double, 6> angles = tet_dihedral_angles_deg(mesh, 0);
  ASSERT_LT(*std::min_element(angles.begin(), angles.end()), 10.0);
  const TetMesh before = mesh;
  EXPECT_EQ(relabel_stranded_slivers(mesh, 10.0), 1);
  EXPECT_EQ(mesh.subdomains[0], 1);
  EXPECT_EQ(mesh.tets, before.tets);
  EXPECT_EQ(mesh.vertices, before.vertices);
  // A flat tet that shares as many faces with its own region as with another keeps its region.
  TetMesh half = before;
  half.subdomains << 0, 1, 0, 0, 1;
  relabel_stranded_slivers(half, 10.0); // (the outer tets, flat too, may change: one inner face each)
  EXPECT_EQ(half.subdomains[0], 0);
}

TEST(SliverRepair, TwoFlatTetsSharingAFaceBecomeThreeAroundTheEdgeThroughIt) {
  // Apexes 0.05 mm off the triangle: tets (0, 1, 2, 3) and (0, 1, 2, 4) of 5.7 degrees; the three
  // around the edge (3, 4) have 11.4.
  TetMesh mesh = mesh_of(triangle_and_apexes(Eigen::Vector3d::Zero(), 0.05),
                         {Eigen::Vector4i(0, 1, 2, 3), Eigen::Vector4i(0, 1, 2, 4)}, {0, 0});
  ASSERT_LT(min_dihedral_angle_deg(mesh), 6.0);
  const TetMesh before = mesh;
  TetMesh again = mesh;
  EXPECT_EQ(flip_slivers(mesh, 10.0), 1);
  ASSERT_EQ(mesh.tets.rows(), 3);
  EXPECT_GT(min_dihedral_angle_deg(mesh), 11.0);
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    EXPECT_TRUE((mesh.tets.row(t).array() == 3).any() && (mesh.tets.row(t).array() == 4).any());
  EXPECT_NEAR(total_volume(mesh), total_volume(before), 1e-12);
  EXPECT_EQ(faces_of_one_tet(mesh), faces_of_one_tet(before)); // the hull keeps its triangles
  EXPECT_EQ(boundary_face_set(mesh), boundary_face_set(before));
  flip_slivers(again, 10.0);
  EXPECT_EQ(again.tets, mesh.tets); // the same mesh gives the same result
}

TEST(SliverRepair, ThreeTetsAroundAnEdgeNearlyInAFaceBecomeTwo) {
  // The edge (3, 4) crosses the triangle near its side (0, 1): the tet (0, 1, 3, 4) is flat (4.4
  // degrees); the two tets on the triangle have 54.
  const Eigen::Vector3d foot = 0.9 * Eigen::Vector3d(0.25, std::sqrt(3.0) / 4.0, 0.0);
  const std::vector<Eigen::Vector3d> points = triangle_and_apexes(foot, 1.0);
  const std::vector<Eigen::Vector4i> ring = {Eigen::Vector4i(0, 1, 3, 4), Eigen::Vector4i(1, 2, 3, 4),
                                             Eigen::Vector4i(2, 0, 3, 4)};
  TetMesh mesh = mesh_of(points, ring, {0, 0, 0});
  ASSERT_LT(min_dihedral_angle_deg(mesh), 5.0);
  const TetMesh before = mesh;
  EXPECT_GE(flip_slivers(mesh, 10.0), 1);
  EXPECT_EQ(mesh.tets.rows(), 2);
  EXPECT_GT(min_dihedral_angle_deg(mesh), 50.0);
  EXPECT_NEAR(total_volume(mesh), total_volume(before), 1e-12);
  EXPECT_EQ(faces_of_one_tet(mesh), faces_of_one_tet(before));

  // With one of the three in another region, the faces between the regions stay faces: no flip
  // may cross them, and each region keeps its volume.
  TetMesh mixed = mesh_of(points, ring, {0, 0, 1});
  const TetMesh mixed_before = mixed;
  flip_slivers(mixed, 10.0);
  EXPECT_EQ(interface_face_set(mixed), interface_face_set(mixed_before));
  EXPECT_EQ(faces_of_one_tet(mixed), faces_of_one_tet(mixed_before));
  double region_one = 0.0, region_one_before = 0.0;
  for (Eigen::Index t = 0; t < mixed.tets.rows(); ++t)
    if (mixed.subdomains[t] == 1) region_one += tet_volume(mixed, t);
  for (Eigen::Index t = 0; t < mixed_before.tets.rows(); ++t)
    if (mixed_before.subdomains[t] == 1) region_one_before += tet_volume(mixed_before, t);
  EXPECT_NEAR(region_one, region_one_before, 1e-12);
}

namespace {

/// Every face on at most two tets, the boundary faces exactly those on one (closed, outward: the
/// volume they enclose is the tets'), every tet positive, every vertex in a tet.
void expect_valid_mesh(const TetMesh& mesh) {
  std::map<Face, int> count;
  std::vector<int> used(static_cast<std::size_t>(mesh.vertices.rows()), 0);
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    EXPECT_GT(tet_volume(mesh, t), 0.0) << "tet " << t;
    for (int k = 0; k < 4; ++k) {
      ++used[static_cast<std::size_t>(mesh.tets(t, k))];
      int v[3], m = 0;
      for (int j = 0; j < 4; ++j)
        if (j != k) v[m++] = mesh.tets(t, j);
      ++count[sorted_face(v[0], v[1], v[2])];
    }
  }
  for (const auto& [face, n] : count)
    EXPECT_LE(n, 2) << face[0] << " " << face[1] << " " << face[2];
  EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0) << "a vertex in no tet";
  EXPECT_EQ(boundary_face_set(mesh), faces_of_one_tet(mesh));
  EXPECT_NEAR(enclosed_volume(mesh), total_volume(mesh), 1e-9 * std::max(1.0, total_volume(mesh)));
}

double region_volume(const TetMesh& mesh, int region) {
  double volume = 0.0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    if (mesh.subdomains[t] == region) volume += tet_volume(mesh, t);
  return volume;
}

} // namespace

TEST(SliverRepair, ASplitEdgeGetsAVertexThatThickensItsSlivers) {
  // The two-region cube with its interface vertex moved next to a neighbour (slivers on both
  // sides of the plane z = 0).
  SliverCube cube;
  const Eigen::Index v = cube.vertex_at(Eigen::Vector3d::Zero());
  ASSERT_GE(v, 0);
  cube.mesh.vertices.row(v) = Eigen::RowVector3d(0.8, 0.1, 0.0);
  const Eigen::Index before = tets_with_dihedral_below(cube.mesh, 10.0);
  const double smallest = min_dihedral_angle_deg(cube.mesh);
  ASSERT_GT(before, 0);
  const TetMesh original = cube.mesh;
  const int splits = split_slivers(cube.mesh, cube.label);
  EXPECT_GT(splits, 0);
  EXPECT_EQ(cube.mesh.vertices.rows(), original.vertices.rows() + splits);
  EXPECT_LT(tets_with_dihedral_below(cube.mesh, 10.0), before);
  EXPECT_GT(min_dihedral_angle_deg(cube.mesh), smallest);
  expect_valid_mesh(cube.mesh);
  // New vertices on the interface stay on it: each region keeps its volume.
  EXPECT_NEAR(region_volume(cube.mesh, 0), region_volume(original, 0), 1e-6);
  EXPECT_NEAR(region_volume(cube.mesh, 1), region_volume(original, 1), 1e-6);
  for (Eigen::Index t = 0; t < cube.mesh.tets.rows(); ++t)
    EXPECT_EQ(cube.label(centroid(cube.mesh, t)), cube.mesh.subdomains[t]) << t;
  TetMesh again = original;
  split_slivers(again, cube.label);
  EXPECT_EQ(again.vertices, cube.mesh.vertices); // the same mesh gives the same result
  EXPECT_EQ(again.tets, cube.mesh.tets);
}

TEST(SliverRepair, AnEdgeFarShorterThanItsSliversIsCollapsed) {
  // An inner vertex of a one-region box moved to 0.05 mm from a neighbour: the tets around their
  // edge are flat needles.
  TetMesh box = structured_box(Eigen::Vector3d::Constant(4.0), Eigen::Vector3i::Constant(4),
                               Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  box.subdomains = Eigen::VectorXi::Zero(box.tets.rows());
  Eigen::Index inner = -1, neighbour = -1;
  for (Eigen::Index v = 0; v < box.vertices.rows(); ++v) {
    if ((box.vertices.row(v) - Eigen::RowVector3d(0.0, 0.0, 0.0)).norm() < 1e-9) inner = v;
    if ((box.vertices.row(v) - Eigen::RowVector3d(1.0, 0.0, 0.0)).norm() < 1e-9) neighbour = v;
  }
  ASSERT_GE(inner, 0);
  ASSERT_GE(neighbour, 0);
  bool joined = false; // the two share an edge of the structured box
  for (Eigen::Index t = 0; t < box.tets.rows(); ++t)
    joined |= (box.tets.row(t).array() == inner).any() && (box.tets.row(t).array() == neighbour).any();
  ASSERT_TRUE(joined);
  box.vertices.row(inner) = Eigen::RowVector3d(0.95, 0.0, 0.0);
  ASSERT_LT(min_dihedral_angle_deg(box), 10.0);
  const double volume = total_volume(box);
  const Eigen::Index vertices = box.vertices.rows();
  EXPECT_EQ(collapse_short_sliver_edges(box), 1);
  EXPECT_EQ(box.vertices.rows(), vertices - 1);
  EXPECT_EQ(tets_with_dihedral_below(box, 10.0), 0);
  EXPECT_NEAR(total_volume(box), volume, 1e-9);
  expect_valid_mesh(box);

  // A boundary vertex next to an inner one: the inner one goes onto it, never the reverse (the
  // boundary keeps its place).
  TetMesh edge = structured_box(Eigen::Vector3d::Constant(4.0), Eigen::Vector3i::Constant(4),
                                Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  edge.subdomains = Eigen::VectorXi::Zero(edge.tets.rows());
  Eigen::Index below = -1, top = -1;
  for (Eigen::Index v = 0; v < edge.vertices.rows(); ++v) {
    if ((edge.vertices.row(v) - Eigen::RowVector3d(0.0, 0.0, 1.0)).norm() < 1e-9) below = v;
    if ((edge.vertices.row(v) - Eigen::RowVector3d(0.0, 0.0, 2.0)).norm() < 1e-9) top = v;
  }
  ASSERT_GE(below, 0);
  ASSERT_GE(top, 0);
  edge.vertices.row(below) = Eigen::RowVector3d(0.0, 0.0, 1.95);
  const Eigen::RowVector3d top_at = edge.vertices.row(top);
  const std::set<Face> surface_before = boundary_face_set(edge);
  const double enclosed = enclosed_volume(edge);
  const Eigen::Index edge_vertices = edge.vertices.rows();
  EXPECT_EQ(collapse_short_sliver_edges(edge), 1);
  EXPECT_EQ(edge.vertices.rows(), edge_vertices - 1);
  // The top vertex is still there, the boundary where it was.
  bool kept = false;
  for (Eigen::Index v = 0; v < edge.vertices.rows(); ++v)
    kept |= edge.vertices.row(v) == top_at;
  EXPECT_TRUE(kept);
  EXPECT_EQ(boundary_face_set(edge).size(), surface_before.size());
  EXPECT_NEAR(enclosed_volume(edge), enclosed, 1e-9);
  expect_valid_mesh(edge);
}
