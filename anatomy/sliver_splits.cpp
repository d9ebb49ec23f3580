// The sliver repair by edge splits (split_slivers): a new vertex on one edge of a sliver, placed
// where the smallest angle of the tets around the edge is largest, within the interface or the
// boundary when the edge lies on one.
#include "anatomy/sliver_repairs.hpp"

#include "anatomy/sliver_faces.hpp"
#include "geometry/tet_quality.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <utility>
#include <vector>

namespace phantasm {

int split_slivers(TetMesh& mesh, const std::function<int(const Eigen::Vector3d&)>& label) {
  if (mesh.subdomains.size() != mesh.tets.rows()) return 0;
  std::vector<std::vector<int>> star(static_cast<std::size_t>(mesh.vertices.rows()));
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
    for (int k = 0; k < 4; ++k)
      star[static_cast<std::size_t>(mesh.tets(t, k))].push_back(static_cast<int>(t));
  const auto smallest = [](const std::array<Eigen::Vector3d, 4>& p) {
    const std::array<double, 6> angles = dihedral_angles_deg(p);
    return *std::min_element(angles.begin(), angles.end());
  };
  // A split of the edge (p, q): the ring's tets with q replaced by the new vertex, then with p.
  struct Split {
    int p = -1, q = -1;
    std::vector<int> ring;
    Eigen::Vector3d at = Eigen::Vector3d::Zero();
    double gain = 0.0;
  };
  const auto corners_with = [&](int t, int from, const Eigen::Vector3d& x) {
    std::array<Eigen::Vector3d, 4> c;
    for (int k = 0; k < 4; ++k)
      c[static_cast<std::size_t>(k)] =
          mesh.tets(t, k) == from ? x : Eigen::Vector3d(mesh.vertices.row(mesh.tets(t, k)).transpose());
    return c;
  };
  const auto centroid_of = [](const std::array<Eigen::Vector3d, 4>& c) {
    return 0.25 * (c[0] + c[1] + c[2] + c[3]);
  };
  const auto try_edge = [&](int t, int p, int q, Split& split) {
    std::vector<int> ring;
    for (const int u : star[static_cast<std::size_t>(p)])
      if ((mesh.tets.row(u).array() == q).any()) ring.push_back(u);
    std::map<int, std::vector<int>> holding; // ring vertex -> the ring's tets holding it
    std::set<int> regions;
    for (const int u : ring) {
      regions.insert(mesh.subdomains[u]);
      for (int k = 0; k < 4; ++k)
        if (mesh.tets(u, k) != p && mesh.tets(u, k) != q) holding[mesh.tets(u, k)].push_back(u);
    }
    // The faces around the edge that separate two sides: boundary faces (one tet) and faces
    // between regions. None: the edge lies inside one region and the new vertex is free. Two,
    // and two sides: the edge lies on that surface and the new vertex stays on it. Else: no split.
    Eigen::Vector3d normal = Eigen::Vector3d::Zero(); // from the lower label's side to the upper's
    int separating = 0;
    for (const auto& [w, held] : holding) {
      if (held.size() > 2) return false;
      const int u = held[0];
      const int other = held.size() == 2 ? mesh.subdomains[held[1]] : -1;
      if (other == mesh.subdomains[u]) continue;
      ++separating;
      const Eigen::Vector3d x0 = mesh.vertices.row(p), x1 = mesh.vertices.row(q), x2 = mesh.vertices.row(w);
      Eigen::Vector3d n = (x1 - x0).cross(x2 - x0);
      Eigen::Vector3d apex = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k)
        if (mesh.tets(u, k) != p && mesh.tets(u, k) != q && mesh.tets(u, k) != w)
          apex = mesh.vertices.row(mesh.tets(u, k)).transpose();
      if (n.dot(apex - x0) > 0.0) n = -n;     // out of u
      if (mesh.subdomains[u] > other) n = -n; // from the lower label to the upper
      normal += n;
    }
    int lower = mesh.subdomains[t], upper = lower;
    if (separating == 0) {
      if (ring.size() < 3 || regions.size() != 1) return false;
    } else {
      if (separating != 2 || !(normal.norm() > 0.0)) return false;
      std::set<int> sides = regions;
      if (holding.size() != ring.size()) sides.insert(-1); // an open ring: the boundary
      if (sides.size() != 2) return false;
      lower = *sides.begin();
      upper = *sides.rbegin();
      normal.normalize();
    }
    double old_quality = 180.0;
    int old_slivers = 0;
    for (const int u : ring) {
      const double angle = smallest(corners_with(u, -1, Eigen::Vector3d::Zero()));
      old_quality = std::min(old_quality, angle);
      old_slivers += angle < k_sliver_deg;
    }
    const Eigen::Vector3d a = mesh.vertices.row(p).transpose(), b = mesh.vertices.row(q).transpose();
    const Eigen::Vector3d middle = 0.5 * (a + b);
    const double length = (b - a).norm();
    std::vector<Eigen::Vector3d> directions;
    if (separating == 0) {
      for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j)
          for (int k = -1; k <= 1; ++k)
            if (i || j || k) directions.push_back(Eigen::Vector3d(i, j, k).normalized());
    } else {
      const Eigen::Vector3d u = normal.unitOrthogonal(), w = normal.cross(u);
      for (int d = 0; d < 12; ++d)
        directions.push_back(std::cos(2.0 * M_PI * d / 12.0) * u + std::sin(2.0 * M_PI * d / 12.0) * w);
    }
    const std::array<Eigen::Vector3d, 4> c = corners_with(t, -1, Eigen::Vector3d::Zero());
    for (int k = 0; k < 4; ++k) { // off the sliver's faces (within the surface for a surface edge)
      const Eigen::Vector3d o = c[static_cast<std::size_t>((k + 1) % 4)];
      Eigen::Vector3d n =
          (c[static_cast<std::size_t>((k + 2) % 4)] - o).cross(c[static_cast<std::size_t>((k + 3) % 4)] - o);
      if (separating > 0) n -= n.dot(normal) * normal;
      if (n.norm() > 0.0) {
        directions.push_back(n.normalized());
        directions.push_back(-n.normalized());
      }
    }
    // Onto the surface: bisection along the normal between its two sides.
    const auto onto = [&](Eigen::Vector3d& x) {
      if (separating == 0) return true;
      double lo = -0.5 * length, hi = 0.5 * length;
      if (label(x + lo * normal) != lower || label(x + hi * normal) != upper) return false;
      for (int i = 0; i < 30; ++i) {
        const double mid = 0.5 * (lo + hi);
        (label(x + mid * normal) == lower ? lo : hi) = mid;
      }
      x += 0.5 * (lo + hi) * normal;
      return true;
    };
    bool found = false;
    for (const double step : {0.0, 0.05, 0.1, 0.2, 0.35, 0.5}) {
      for (const Eigen::Vector3d& d : directions) {
        Eigen::Vector3d x = middle + step * length * d;
        if (!onto(x)) continue;
        double quality = 180.0;
        int slivers = 0;
        bool valid = true;
        for (const int u : ring) {
          for (const int from : {q, p}) {
            const std::array<Eigen::Vector3d, 4> cut = corners_with(u, from, x);
            if (!(signed_volume(cut[0], cut[1], cut[2], cut[3]) > 0.0) ||
                label(centroid_of(cut)) != mesh.subdomains[u]) {
              valid = false;
              break;
            }
            const double angle = smallest(cut);
            quality = std::min(quality, angle);
            slivers += angle < k_sliver_deg;
          }
          if (!valid) break;
        }
        if (!valid || slivers > old_slivers || !(quality - old_quality > 1e-9)) continue;
        if (!found || quality - old_quality > split.gain) {
          split = Split{p, q, ring, x, quality - old_quality};
          found = true;
        }
        if (step == 0.0) break; // the midpoint: one position, whatever the direction
      }
    }
    return found;
  };
  int splits = 0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    if (!(smallest(corners_with(static_cast<int>(t), -1, Eigen::Vector3d::Zero())) < k_sliver_deg)) continue;
    Split best, candidate;
    bool any = false;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        if (try_edge(static_cast<int>(t), mesh.tets(t, i), mesh.tets(t, j), candidate) &&
            (!any || candidate.gain > best.gain)) {
          best = candidate;
          any = true;
        }
    if (!any) continue;
    const int m = static_cast<int>(mesh.vertices.rows());
    mesh.vertices.conservativeResize(m + 1, 3);
    mesh.vertices.row(m) = best.at.transpose();
    star.emplace_back();
    const auto first_new = static_cast<int>(mesh.tets.rows());
    mesh.tets.conservativeResize(first_new + static_cast<Eigen::Index>(best.ring.size()), 4);
    mesh.subdomains.conservativeResize(mesh.tets.rows());
    for (std::size_t r = 0; r < best.ring.size(); ++r) {
      const int u = best.ring[r], w = first_new + static_cast<int>(r);
      mesh.tets.row(w) = mesh.tets.row(u);
      mesh.subdomains[w] = mesh.subdomains[u];
      for (int k = 0; k < 4; ++k) {
        if (mesh.tets(u, k) == best.q) mesh.tets(u, k) = m; // u keeps p
        if (mesh.tets(w, k) == best.p) mesh.tets(w, k) = m; // w keeps q
      }
      std::vector<int>& at_q = star[static_cast<std::size_t>(best.q)];
      *std::find(at_q.begin(), at_q.end(), u) = w;
      star[static_cast<std::size_t>(m)].push_back(u);
      star[static_cast<std::size_t>(m)].push_back(w);
      for (int k = 0; k < 4; ++k)
        if (mesh.tets(w, k) != m && mesh.tets(w, k) != best.q)
          star[static_cast<std::size_t>(mesh.tets(w, k))].push_back(w);
    }
    // Boundary triangles on the edge are cut in two at the new vertex, as the tets are.
    const Eigen::Index faces = mesh.boundary_faces.rows();
    for (Eigen::Index f = 0; f < faces; ++f) {
      const auto row = mesh.boundary_faces.row(f);
      if (!(row.array() == best.p).any() || !(row.array() == best.q).any()) continue;
      Eigen::RowVector3i second = row;
      for (int k = 0; k < 3; ++k) {
        if (mesh.boundary_faces(f, k) == best.q) mesh.boundary_faces(f, k) = m;
        if (second[k] == best.p) second[k] = m;
      }
      mesh.boundary_faces.conservativeResize(mesh.boundary_faces.rows() + 1, 3);
      mesh.boundary_faces.row(mesh.boundary_faces.rows() - 1) = second;
    }
    ++splits;
  }
  return splits;
}

} // namespace phantasm
