#include "anatomy/structured_mesh.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <map>

namespace phantasm {

Eigen::MatrixX3i boundary_faces_of(const Eigen::MatrixX3d& vertices, const Eigen::MatrixX4i& tets) {
  struct Face {
    std::array<int, 3> corners;
    int opposite;
    int count;
  };
  std::map<std::array<int, 3>, Face> faces;
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> f = {tets(t, (k + 1) % 4), tets(t, (k + 2) % 4), tets(t, (k + 3) % 4)};
      std::array<int, 3> key = f;
      std::sort(key.begin(), key.end());
      auto [it, inserted] = faces.try_emplace(key, Face{f, tets(t, k), 0});
      ++it->second.count;
    }
  }
  std::vector<Eigen::Vector3i> boundary;
  for (const auto& [key, face] : faces) {
    if (face.count != 1) continue;
    Eigen::Vector3i f(face.corners[0], face.corners[1], face.corners[2]);
    const Eigen::Vector3d a = vertices.row(f[0]).transpose();
    const Eigen::Vector3d normal =
        (vertices.row(f[1]).transpose() - a).cross(vertices.row(f[2]).transpose() - a);
    if (normal.dot(vertices.row(face.opposite).transpose() - a) > 0.0) std::swap(f[1], f[2]);
    boundary.push_back(f);
  }
  Eigen::MatrixX3i result(static_cast<Eigen::Index>(boundary.size()), 3);
  for (std::size_t i = 0; i < boundary.size(); ++i)
    result.row(static_cast<Eigen::Index>(i)) = boundary[i].transpose();
  return result;
}

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
  mesh.boundary_faces = boundary_faces_of(mesh.vertices, mesh.tets);
  return mesh;
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
