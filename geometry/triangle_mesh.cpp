#include "geometry/triangle_mesh.hpp"

#include "core/error.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

namespace phantasm {
namespace {

std::string triangle_name(const std::string& what, Eigen::Index t) {
  return what + ": triangle " + std::to_string(t);
}

} // namespace

void check_closed_manifold(const TriangleMesh& mesh, const std::string& what) {
  const Eigen::Index nv = mesh.vertex_count();
  if (mesh.face_count() < 4) {
    throw InputError(what + ": expected a closed surface of at least 4 triangles, found " +
                     std::to_string(mesh.face_count()));
  }
  if (!mesh.vertices.allFinite())
    throw InputError(what + ": expected finite vertex positions, found NaN or Inf");
  const double scale = mean_edge_length(mesh);
  // Directed edge (a, b) -> triangles using it in that direction.
  std::map<std::pair<int, int>, std::vector<Eigen::Index>> directed;
  for (Eigen::Index t = 0; t < mesh.face_count(); ++t) {
    const Eigen::Vector3i f = mesh.faces.row(t);
    for (int k = 0; k < 3; ++k) {
      if (f[k] < 0 || f[k] >= nv) {
        throw InputError(triangle_name(what, t) + ": expected vertex indices in [0, " +
                         std::to_string(nv - 1) + "], found " + std::to_string(f[k]));
      }
    }
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
      throw InputError(triangle_name(what, t) +
                       ": expected three distinct vertices, found a repeated vertex (degenerate)");
    }
    const Eigen::Vector3d a = mesh.vertex(f[0]), b = mesh.vertex(f[1]), c = mesh.vertex(f[2]);
    const double area = 0.5 * (b - a).cross(c - a).norm();
    if (area <= 1e-12 * scale * scale) {
      throw InputError(triangle_name(what, t) +
                       ": expected a triangle with area, found a degenerate one (area " +
                       std::to_string(area) + " mm^2)");
    }
    for (int k = 0; k < 3; ++k)
      directed[{f[k], f[(k + 1) % 3]}].push_back(t);
  }
  for (const auto& [edge, triangles] : directed) {
    const std::string edge_name =
        "edge (" + std::to_string(edge.first) + ", " + std::to_string(edge.second) + ")";
    if (triangles.size() > 1) {
      const auto reverse = directed.find({edge.second, edge.first});
      const std::size_t total = triangles.size() + (reverse == directed.end() ? 0 : reverse->second.size());
      if (total > 2) {
        throw InputError(what + ": " + edge_name + ": expected at most two triangles per edge, found " +
                         std::to_string(total) + " (non-manifold)");
      }
      throw InputError(what + ": " + edge_name + ": expected neighbouring triangles " +
                       std::to_string(triangles[0]) + " and " + std::to_string(triangles[1]) +
                       " to traverse their shared edge in opposite directions, found the same direction "
                       "(inconsistent orientation)");
    }
    const auto reverse = directed.find({edge.second, edge.first});
    if (reverse == directed.end()) {
      throw InputError(what + ": " + edge_name + " of triangle " + std::to_string(triangles[0]) +
                       ": expected a closed surface, found an open edge (boundary)");
    }
    if (reverse->second.size() > 1) {
      throw InputError(what + ": " + edge_name + ": expected at most two triangles per edge, found " +
                       std::to_string(1 + reverse->second.size()) + " (non-manifold)");
    }
  }
  // Each vertex's triangles must form one fan: walk around the vertex through shared edges.
  std::vector<std::vector<Eigen::Index>> vertex_triangles(static_cast<std::size_t>(nv));
  for (Eigen::Index t = 0; t < mesh.face_count(); ++t) {
    for (int k = 0; k < 3; ++k)
      vertex_triangles[static_cast<std::size_t>(mesh.faces(t, k))].push_back(t);
  }
  for (Eigen::Index v = 0; v < nv; ++v) {
    const auto& around = vertex_triangles[static_cast<std::size_t>(v)];
    if (around.empty()) continue; // unused vertices are harmless
    // From triangle (v, a, b) the next triangle around v is the one holding directed edge (v, b)... i.e. (b,
    // v)'s twin.
    std::size_t visited = 0;
    Eigen::Index t = around.front();
    do {
      const Eigen::Vector3i f = mesh.faces.row(t);
      int k = 0;
      while (f[k] != v)
        ++k;
      const int next_vertex = f[(k + 2) % 3]; // the edge (next_vertex -> v) is in t
      t = directed.at({static_cast<int>(v), next_vertex}).front();
      ++visited;
    } while (t != around.front() && visited <= around.size());
    if (visited != around.size()) {
      throw InputError(what + ": vertex " + std::to_string(v) + ": expected its " +
                       std::to_string(around.size()) +
                       " triangles to form one fan, found several (non-manifold vertex)");
    }
  }
  const double volume = enclosed_volume(mesh);
  if (volume <= 0.0) {
    throw InputError(what +
                     ": expected triangles ordered counter-clockwise seen from outside, found an inward "
                     "orientation (enclosed volume " +
                     std::to_string(volume) + " mm^3)");
  }
}

double enclosed_volume(const TriangleMesh& mesh) {
  double six_volume = 0.0;
  for (Eigen::Index t = 0; t < mesh.face_count(); ++t) {
    const Eigen::Vector3d a = mesh.vertex(mesh.faces(t, 0)), b = mesh.vertex(mesh.faces(t, 1)),
                          c = mesh.vertex(mesh.faces(t, 2));
    six_volume += a.dot(b.cross(c));
  }
  return six_volume / 6.0;
}

double surface_area(const TriangleMesh& mesh) {
  double area = 0.0;
  for (Eigen::Index t = 0; t < mesh.face_count(); ++t) {
    const Eigen::Vector3d a = mesh.vertex(mesh.faces(t, 0)), b = mesh.vertex(mesh.faces(t, 1)),
                          c = mesh.vertex(mesh.faces(t, 2));
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

double mean_edge_length(const TriangleMesh& mesh) {
  double total = 0.0;
  Eigen::Index count = 0;
  for (Eigen::Index t = 0; t < mesh.face_count(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.faces(t, k), b = mesh.faces(t, (k + 1) % 3);
      if (a < 0 || b < 0 || a >= mesh.vertex_count() || b >= mesh.vertex_count()) continue;
      total += (mesh.vertex(a) - mesh.vertex(b)).norm();
      ++count;
    }
  }
  return count == 0 ? 0.0 : total / static_cast<double>(count);
}

TriangleMesh unit_icosphere(int level) {
  const double p = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0},
                                    {0, -1, p}, {0, 1, p}, {0, -1, -p}, {0, 1, -p},
                                    {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& x : v)
    x.normalize();
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> midpoint;
    auto middle = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto found = midpoint.find(key);
      if (found != midpoint.end()) return found->second;
      v.push_back((v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]).normalized());
      const int index = static_cast<int>(v.size()) - 1;
      midpoint[key] = index;
      return index;
    };
    std::vector<Eigen::Vector3i> finer;
    finer.reserve(f.size() * 4);
    for (const auto& t : f) {
      const int a = middle(t[0], t[1]), b = middle(t[1], t[2]), c = middle(t[2], t[0]);
      finer.push_back({t[0], a, c});
      finer.push_back({t[1], b, a});
      finer.push_back({t[2], c, b});
      finer.push_back({a, b, c});
    }
    f.swap(finer);
  }
  TriangleMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  mesh.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i)
    mesh.vertices.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  for (std::size_t i = 0; i < f.size(); ++i)
    mesh.faces.row(static_cast<Eigen::Index>(i)) = f[i].transpose();
  return mesh;
}

} // namespace phantasm
