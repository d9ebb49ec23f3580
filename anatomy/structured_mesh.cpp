#include "anatomy/structured_mesh.hpp"

#include "geometry/tet_boundary.hpp"

#include <Eigen/Geometry>

#include <array>
#include <utility>

namespace phantasm {

TetMesh structured_box(const Eigen::Vector3d& size_mm, const Eigen::Vector3i& cells,
                       const Eigen::Matrix3d& rotation, const Eigen::Vector3d& center_mm) {
  const int nx = cells.x(), ny = cells.y(), nz = cells.z();
  auto id = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  TetMesh mesh;
  mesh.vertices.resize((nx + 1) * (ny + 1) * (nz + 1), 3);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        const Eigen::Vector3d local((double(i) / nx - 0.5) * size_mm.x(),
                                    (double(j) / ny - 0.5) * size_mm.y(),
                                    (double(k) / nz - 0.5) * size_mm.z());
        mesh.vertices.row(id(i, j, k)) = (rotation * local + center_mm).transpose();
      }
  mesh.tets.resize(5 * nx * ny * nz, 4);
  Eigen::Index t = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        // Cube corners c[abc] at (i+a, j+b, k+c). Even cells cut off corners 001, 010, 100, 111
        // around the central tet (000, 110, 101, 011); odd cells use the mirror split, so the
        // face diagonals of neighbours agree.
        int c[2][2][2];
        for (int a = 0; a < 2; ++a)
          for (int b = 0; b < 2; ++b)
            for (int d = 0; d < 2; ++d)
              c[a][b][d] = id(i + a, j + b, k + d);
        const bool even = (i + j + k) % 2 == 0;
        std::array<Eigen::Vector4i, 5> split;
        if (even) {
          split = {Eigen::Vector4i(c[0][0][0], c[1][0][0], c[0][1][0], c[0][0][1]),
                   Eigen::Vector4i(c[1][1][0], c[0][1][0], c[1][0][0], c[1][1][1]),
                   Eigen::Vector4i(c[1][0][1], c[1][0][0], c[0][0][1], c[1][1][1]),
                   Eigen::Vector4i(c[0][1][1], c[0][0][1], c[0][1][0], c[1][1][1]),
                   Eigen::Vector4i(c[1][0][0], c[0][1][0], c[0][0][1], c[1][1][1])};
        } else {
          split = {Eigen::Vector4i(c[1][0][0], c[0][0][0], c[1][1][0], c[1][0][1]),
                   Eigen::Vector4i(c[0][1][0], c[1][1][0], c[0][0][0], c[0][1][1]),
                   Eigen::Vector4i(c[0][0][1], c[0][0][0], c[1][0][1], c[0][1][1]),
                   Eigen::Vector4i(c[1][1][1], c[1][0][1], c[1][1][0], c[0][1][1]),
                   Eigen::Vector4i(c[0][0][0], c[1][1][0], c[1][0][1], c[0][1][1])};
        }
        for (const auto& tet : split) {
          mesh.tets.row(t) = tet.transpose();
          if (tet_volume(mesh, t) < 0.0) std::swap(mesh.tets(t, 2), mesh.tets(t, 3));
          ++t;
        }
      }
  mesh.boundary_faces = tet_boundary_faces(mesh.vertices, mesh.tets);
  return mesh;
}

std::vector<std::vector<int>> structured_box_cells(const Eigen::Vector3i& cells) {
  std::vector<std::vector<int>> groups(static_cast<std::size_t>(cells.prod()));
  for (std::size_t c = 0; c < groups.size(); ++c)
    for (int k = 0; k < 5; ++k)
      groups[c].push_back(static_cast<int>(5 * c) + k);
  return groups;
}

TriangleMesh structured_sheet(const Eigen::Vector2d& size_mm, const Eigen::Vector2i& cells,
                              const Eigen::Matrix3d& rotation, const Eigen::Vector3d& center_mm) {
  const int nx = cells.x(), ny = cells.y();
  TriangleMesh mesh;
  mesh.vertices.resize((nx + 1) * (ny + 1), 3);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const Eigen::Vector3d local((double(i) / nx - 0.5) * size_mm.x(), (double(j) / ny - 0.5) * size_mm.y(),
                                  0.0);
      mesh.vertices.row(j * (nx + 1) + i) = (rotation * local + center_mm).transpose();
    }
  mesh.faces.resize(2 * nx * ny, 3);
  Eigen::Index f = 0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
      // Alternate the diagonal so the sheet has no preferred shear direction.
      if ((i + j) % 2 == 0) {
        mesh.faces.row(f++) = Eigen::RowVector3i(a, b, d);
        mesh.faces.row(f++) = Eigen::RowVector3i(a, d, c);
      } else {
        mesh.faces.row(f++) = Eigen::RowVector3i(a, b, c);
        mesh.faces.row(f++) = Eigen::RowVector3i(b, d, c);
      }
    }
  return mesh;
}

} // namespace phantasm
