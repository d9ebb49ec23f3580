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

namespace {

/// A split of the edge (p, q): the ring's tets with q replaced by the new vertex, then with p.
struct Split {
  int p = -1, q = -1;
  std::vector<int> ring;
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
  double gain = 0.0;
};

/// Where a split's new vertex may go: anywhere (no separating faces around the edge), or on the
/// surface between the labels `lower` and `upper` whose unit normal (from lower to upper) is
/// `normal`.
struct EdgeSurface {
  int separating = 0;
  int lower = 0, upper = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

double smallest_angle(const std::array<Eigen::Vector3d, 4>& p) {
  const std::array<double, 6> angles = dihedral_angles_deg(p);
  return *std::min_element(angles.begin(), angles.end());
}

/// The edge splits of a labelled mesh, with the tets around each vertex.
class SplitRepair {
public:
  SplitRepair(TetMesh& mesh, const std::function<int(const Eigen::Vector3d&)>& label)
      : m_mesh(mesh), m_label(label), m_star(static_cast<std::size_t>(mesh.vertices.rows())) {
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
      for (int k = 0; k < 4; ++k)
        m_star[static_cast<std::size_t>(mesh.tets(t, k))].push_back(static_cast<int>(t));
  }

  /// Tet t's best split of one of its edges, when it is a sliver and a split raises its smallest angle.
  bool best_split(Eigen::Index t, Split& best) const {
    if (!(smallest_angle(corners_with(static_cast<int>(t), -1, Eigen::Vector3d::Zero())) < k_sliver_deg))
      return false;
    Split candidate;
    bool any = false;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        if (try_edge(static_cast<int>(t), m_mesh.tets(t, i), m_mesh.tets(t, j), candidate) &&
            (!any || candidate.gain > best.gain)) {
          best = candidate;
          any = true;
        }
    return any;
  }

  /// Makes the split: a new vertex, each tet of the ring cut in two, and the boundary triangles
  /// on the edge cut at the new vertex.
  void apply(const Split& best) {
    TetMesh& mesh = m_mesh;
    const int m = static_cast<int>(mesh.vertices.rows());
    mesh.vertices.conservativeResize(m + 1, 3);
    mesh.vertices.row(m) = best.at.transpose();
    m_star.emplace_back();
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
      std::vector<int>& at_q = m_star[static_cast<std::size_t>(best.q)];
      *std::find(at_q.begin(), at_q.end(), u) = w;
      m_star[static_cast<std::size_t>(m)].push_back(u);
      m_star[static_cast<std::size_t>(m)].push_back(w);
      for (int k = 0; k < 4; ++k)
        if (mesh.tets(w, k) != m && mesh.tets(w, k) != best.q)
          m_star[static_cast<std::size_t>(mesh.tets(w, k))].push_back(w);
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
  }

private:
  std::array<Eigen::Vector3d, 4> corners_with(int t, int from, const Eigen::Vector3d& x) const {
    std::array<Eigen::Vector3d, 4> c;
    for (int k = 0; k < 4; ++k)
      c[static_cast<std::size_t>(k)] =
          m_mesh.tets(t, k) == from ? x : Eigen::Vector3d(m_mesh.vertices.row(m_mesh.tets(t, k)).transpose());
    return c;
  }

  /// The faces around the edge (p, q) that separate two sides: boundary faces (one tet) and
  /// faces between regions. None: the edge lies inside one region and the new vertex is free.
  /// Two, and two sides: the edge lies on that surface and the new vertex stays on it. Else (false): no
  /// split.
  bool edge_surface(int t, int p, int q, const std::vector<int>& ring, EdgeSurface& s) const {
    const TetMesh& mesh = m_mesh;
    std::map<int, std::vector<int>> holding; // ring vertex -> the ring's tets holding it
    std::set<int> regions;
    for (const int u : ring) {
      regions.insert(mesh.subdomains[u]);
      for (int k = 0; k < 4; ++k)
        if (mesh.tets(u, k) != p && mesh.tets(u, k) != q) holding[mesh.tets(u, k)].push_back(u);
    }
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
    s.separating = separating;
    s.lower = s.upper = mesh.subdomains[t];
    if (separating == 0) return ring.size() >= 3 && regions.size() == 1;
    if (separating != 2 || !(normal.norm() > 0.0)) return false;
    std::set<int> sides = regions;
    if (holding.size() != ring.size()) sides.insert(-1); // an open ring: the boundary
    if (sides.size() != 2) return false;
    s.lower = *sides.begin();
    s.upper = *sides.rbegin();
    s.normal = normal.normalized();
    return true;
  }

  /// The directions from the edge's middle in which the new vertex is sought: the 26 of the
  /// cube (12 in the surface for a surface edge), and off the sliver t's faces.
  std::vector<Eigen::Vector3d> directions(int t, const EdgeSurface& s) const {
    std::vector<Eigen::Vector3d> directions;
    if (s.separating == 0) {
      for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j)
          for (int k = -1; k <= 1; ++k)
            if (i || j || k) directions.push_back(Eigen::Vector3d(i, j, k).normalized());
    } else {
      const Eigen::Vector3d u = s.normal.unitOrthogonal(), w = s.normal.cross(u);
      for (int d = 0; d < 12; ++d)
        directions.push_back(std::cos(2.0 * M_PI * d / 12.0) * u + std::sin(2.0 * M_PI * d / 12.0) * w);
    }
    const std::array<Eigen::Vector3d, 4> c = corners_with(t, -1, Eigen::Vector3d::Zero());
    for (int k = 0; k < 4; ++k) { // off the sliver's faces (within the surface for a surface edge)
      const Eigen::Vector3d o = c[static_cast<std::size_t>((k + 1) % 4)];
      Eigen::Vector3d n =
          (c[static_cast<std::size_t>((k + 2) % 4)] - o).cross(c[static_cast<std::size_t>((k + 3) % 4)] - o);
      if (s.separating > 0) n -= n.dot(s.normal) * s.normal;
      if (n.norm() > 0.0) {
        directions.push_back(n.normalized());
        directions.push_back(-n.normalized());
      }
    }
    return directions;
  }

  /// x moved onto the surface: bisection along the normal between its two sides; false when x
  /// is not between them.
  bool onto(Eigen::Vector3d& x, const EdgeSurface& s, double length) const {
    if (s.separating == 0) return true;
    double lo = -0.5 * length, hi = 0.5 * length;
    if (m_label(x + lo * s.normal) != s.lower || m_label(x + hi * s.normal) != s.upper) return false;
    for (int i = 0; i < 30; ++i) {
      const double mid = 0.5 * (lo + hi);
      (m_label(x + mid * s.normal) == s.lower ? lo : hi) = mid;
    }
    x += 0.5 * (lo + hi) * s.normal;
    return true;
  }

  /// The smallest angle of the ring's tets cut at x, and how many slivers they hold; false when
  /// a cut tet is inverted or leaves its region.
  bool cut_quality(const std::vector<int>& ring, int p, int q, const Eigen::Vector3d& x, double& quality,
                   int& slivers) const {
    quality = 180.0;
    slivers = 0;
    for (const int u : ring) {
      for (const int from : {q, p}) {
        const std::array<Eigen::Vector3d, 4> cut = corners_with(u, from, x);
        if (!(signed_volume(cut[0], cut[1], cut[2], cut[3]) > 0.0) ||
            m_label(0.25 * (cut[0] + cut[1] + cut[2] + cut[3])) != m_mesh.subdomains[u])
          return false;
        const double angle = smallest_angle(cut);
        quality = std::min(quality, angle);
        slivers += angle < k_sliver_deg;
      }
    }
    return true;
  }

  /// The best split of tet t's edge (p, q): the new vertex where the smallest angle of the tets
  /// around the edge is largest; false when no position raises it.
  bool try_edge(int t, int p, int q, Split& split) const {
    std::vector<int> ring;
    for (const int u : m_star[static_cast<std::size_t>(p)])
      if ((m_mesh.tets.row(u).array() == q).any()) ring.push_back(u);
    EdgeSurface s;
    if (!edge_surface(t, p, q, ring, s)) return false;
    double old_quality = 180.0;
    int old_slivers = 0;
    for (const int u : ring) {
      const double angle = smallest_angle(corners_with(u, -1, Eigen::Vector3d::Zero()));
      old_quality = std::min(old_quality, angle);
      old_slivers += angle < k_sliver_deg;
    }
    const Eigen::Vector3d a = m_mesh.vertices.row(p).transpose(), b = m_mesh.vertices.row(q).transpose();
    const Eigen::Vector3d middle = 0.5 * (a + b);
    const double length = (b - a).norm();
    const std::vector<Eigen::Vector3d> around = directions(t, s);
    bool found = false;
    for (const double step : {0.0, 0.05, 0.1, 0.2, 0.35, 0.5}) {
      for (const Eigen::Vector3d& d : around) {
        Eigen::Vector3d x = middle + step * length * d;
        if (!onto(x, s, length)) continue;
        double quality = 180.0;
        int slivers = 0;
        const bool valid = cut_quality(ring, p, q, x, quality, slivers);
        if (!valid || slivers > old_slivers || !(quality - old_quality > 1e-9)) continue;
        if (!found || quality - old_quality > split.gain) {
          split = Split{p, q, ring, x, quality - old_quality};
          found = true;
        }
        if (step == 0.0) break; // the midpoint: one position, whatever the direction
      }
    }
    return found;
  }

  TetMesh& m_mesh;
  const std::function<int(const Eigen::Vector3d&)>& m_label;
  std::vector<std::vector<int>> m_star;
};

} // namespace

int split_slivers(TetMesh& mesh, const std::function<int(const Eigen::Vector3d&)>& label) {
  if (mesh.subdomains.size() != mesh.tets.rows()) return 0;
  SplitRepair repair(mesh, label);
  int splits = 0;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    Split best;
    if (!repair.best_split(t, best)) continue;
    repair.apply(best);
    ++splits;
  }
  return splits;
}

} // namespace phantasm
