// The sliver repair by flips inside one subdomain (flip_slivers): 2-3 face flips and edge
// removals of 3 to 7 tets around an edge, kept when they fill the same volume and raise the
// smallest dihedral angle; interfaces and the boundary keep their triangles.
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

/// A flip: the tets it removes and the tets it makes in their place.
struct Flip {
  std::vector<int> old;
  std::vector<Eigen::Vector4i> made;
  double gain = 0.0; ///< smallest angle of the new tets less that of the old, degrees
};

/// The mesh's tets as the flips change them: each tet's subdomain and whether it is still in the
/// mesh, the tets on each face and around each vertex.
class FlipRepair {
public:
  explicit FlipRepair(TetMesh& mesh)
      : m_mesh(mesh), m_labelled(mesh.subdomains.size() == mesh.tets.rows()),
        m_star(static_cast<std::size_t>(mesh.vertices.rows())) {
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
      m_tets.push_back(mesh.tets.row(t).transpose());
      m_region.push_back(m_labelled ? mesh.subdomains[t] : 0);
    }
    m_alive.assign(m_tets.size(), 1);
    for (std::size_t t = 0; t < m_tets.size(); ++t)
      enter(static_cast<int>(t));
  }

  /// One pass over the tets under bound_deg: each takes the best of its flips; returns how many.
  int pass(double bound_deg) {
    int flips = 0;
    for (std::size_t t = 0; t < m_tets.size(); ++t) {
      if (!m_alive[t] || quality(m_tets[t]) >= bound_deg) continue;
      Flip best, candidate;
      for (int k = 0; k < 4; ++k)
        if (face_flip(static_cast<int>(t), k, candidate) && candidate.gain > best.gain) best = candidate;
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j)
          if (edge_flip(static_cast<int>(t), m_tets[t][i], m_tets[t][j], candidate) &&
              candidate.gain > best.gain)
            best = candidate;
      if (best.made.empty()) continue;
      apply(best, m_region[t]);
      ++flips;
    }
    return flips;
  }

  /// The mesh's tets (and subdomains) replaced by those still alive, in order.
  void write_back() const {
    const auto count = static_cast<Eigen::Index>(std::count(m_alive.begin(), m_alive.end(), 1));
    m_mesh.tets.resize(count, 4);
    if (m_labelled) m_mesh.subdomains.resize(count);
    Eigen::Index next = 0;
    for (std::size_t t = 0; t < m_tets.size(); ++t) {
      if (!m_alive[t]) continue;
      m_mesh.tets.row(next) = m_tets[t].transpose();
      if (m_labelled) m_mesh.subdomains[next] = m_region[t];
      ++next;
    }
  }

private:
  void enter(int t) {
    for (int k = 0; k < 4; ++k) {
      m_faces[face_key(m_tets[static_cast<std::size_t>(t)], k)].push_back(t);
      m_star[static_cast<std::size_t>(m_tets[static_cast<std::size_t>(t)][k])].push_back(t);
    }
  }
  void leave(int t) {
    for (int k = 0; k < 4; ++k) {
      const FaceKey key = face_key(m_tets[static_cast<std::size_t>(t)], k);
      std::vector<int>& around = m_faces[key];
      around.erase(std::find(around.begin(), around.end(), t));
      if (around.empty()) m_faces.erase(key);
      std::vector<int>& at = m_star[static_cast<std::size_t>(m_tets[static_cast<std::size_t>(t)][k])];
      at.erase(std::find(at.begin(), at.end(), t));
    }
  }
  double volume(const Eigen::Vector4i& tet) const {
    const std::array<Eigen::Vector3d, 4> p = tet_corners(m_mesh, tet);
    return signed_volume(p[0], p[1], p[2], p[3]);
  }
  double quality(const Eigen::Vector4i& tet) const {
    const std::array<double, 6> angles = dihedral_angles_deg(tet_corners(m_mesh, tet));
    return *std::min_element(angles.begin(), angles.end());
  }
  Eigen::Vector4i oriented(Eigen::Vector4i tet) const {
    if (volume(tet) < 0.0) std::swap(tet[0], tet[1]);
    return tet;
  }

  /// A flip is kept when its tets fill the old ones' volume (so none overlaps another or leaves
  /// a gap), none is flat, and the smallest angle rises.
  bool judge(Flip& flip) const {
    double before = 0.0, after = 0.0, old_quality = 180.0, new_quality = 180.0;
    int old_slivers = 0, new_slivers = 0;
    for (const int t : flip.old) {
      before += volume(m_tets[static_cast<std::size_t>(t)]);
      const double q = quality(m_tets[static_cast<std::size_t>(t)]);
      old_quality = std::min(old_quality, q);
      old_slivers += q < k_sliver_deg;
    }
    for (const Eigen::Vector4i& tet : flip.made) {
      const double v = volume(tet);
      if (!(v > 1e-9 * std::abs(before))) return false;
      after += v;
      const double q = quality(tet);
      new_quality = std::min(new_quality, q);
      new_slivers += q < k_sliver_deg;
    }
    if (!(std::abs(after - before) <= 1e-9 * std::abs(before)) || new_slivers > old_slivers) return false;
    flip.gain = new_quality - old_quality;
    return flip.gain > 1e-9;
  }

  /// The 2-3 flip of tet t's face opposite its vertex k.
  bool face_flip(int t, int k, Flip& flip) const {
    const Eigen::Vector4i& tet = m_tets[static_cast<std::size_t>(t)];
    const FaceKey key = face_key(tet, k);
    const auto found = m_faces.find(key);
    if (found == m_faces.end() || found->second.size() != 2) return false;
    const int u = found->second[0] == t ? found->second[1] : found->second[0];
    if (m_region[static_cast<std::size_t>(u)] != m_region[static_cast<std::size_t>(t)]) return false;
    const int d = tet[k];
    int e = -1;
    for (int j = 0; j < 4; ++j)
      if (std::find(key.begin(), key.end(), m_tets[static_cast<std::size_t>(u)][j]) == key.end())
        e = m_tets[static_cast<std::size_t>(u)][j];
    flip.old = {t, u};
    flip.made.clear();
    for (int i = 0; i < 3; ++i)
      flip.made.push_back(oriented(Eigen::Vector4i(key[static_cast<std::size_t>(i)],
                                                   key[static_cast<std::size_t>((i + 1) % 3)], d, e)));
    return judge(flip);
  }

  /// The ring of vertices around the inner edge (a, b) in order, given the tets around it
  /// (`ring`, all in tet t's subdomain); empty when the ring is not closed.
  std::vector<int> edge_ring(int t, int a, int b, const std::vector<int>& ring) const {
    std::map<int, std::vector<int>> holding; // ring vertex -> the ring's tets holding it
    for (const int u : ring) {
      if (m_region[static_cast<std::size_t>(u)] != m_region[static_cast<std::size_t>(t)]) return {};
      for (int j = 0; j < 4; ++j) {
        const int w = m_tets[static_cast<std::size_t>(u)][j];
        if (w != a && w != b) holding[w].push_back(u);
      }
    }
    // A closed ring: as many vertices as tets, each in two of them, each face around the edge
    // shared by two tets (inside, not boundary).
    if (holding.size() != ring.size()) return {};
    for (const auto& [w, held] : holding) {
      if (held.size() != 2) return {};
      FaceKey key{a, b, w};
      std::sort(key.begin(), key.end());
      const auto found = m_faces.find(key);
      if (found == m_faces.end() || found->second.size() != 2) return {};
    }
    // The ring's vertices in order around the edge.
    std::vector<int> polygon{holding.begin()->first};
    int through = holding.begin()->second[0];
    while (polygon.size() < ring.size()) {
      int next = -1;
      for (int j = 0; j < 4; ++j) {
        const int w = m_tets[static_cast<std::size_t>(through)][j];
        if (w != a && w != b && w != polygon.back()) next = w;
      }
      const std::vector<int>& held = holding[next];
      through = held[0] == through ? held[1] : held[0];
      polygon.push_back(next);
    }
    return polygon;
  }

  /// Edge removal: the n tets around an inner edge (a, b) (n from 3, the 3-2 flip, to 7) replaced
  /// by the 2(n - 2) tets joining a and b to a fan triangulation of the ring of their other
  /// vertices; the best of the n fans.
  bool edge_flip(int t, int a, int b, Flip& flip) const {
    std::vector<int> ring;
    for (const int u : m_star[static_cast<std::size_t>(a)])
      if ((m_tets[static_cast<std::size_t>(u)].array() == b).any()) ring.push_back(u);
    if (ring.size() < 3 || ring.size() > 7) return false;
    const std::vector<int> polygon = edge_ring(t, a, b, ring);
    if (polygon.empty()) return false;
    const auto n = static_cast<int>(polygon.size());
    bool found = false;
    Flip trial;
    trial.old = ring;
    for (int apex = 0; apex < n; ++apex) {
      trial.made.clear();
      for (int j = 1; j + 1 < n; ++j) {
        const int p = polygon[static_cast<std::size_t>(apex)],
                  q = polygon[static_cast<std::size_t>((apex + j) % n)],
                  r = polygon[static_cast<std::size_t>((apex + j + 1) % n)];
        trial.made.push_back(oriented(Eigen::Vector4i(p, q, r, a)));
        trial.made.push_back(oriented(Eigen::Vector4i(p, q, r, b)));
      }
      if (judge(trial) && (!found || trial.gain > flip.gain)) {
        flip = trial;
        found = true;
      }
      if (n == 3) break; // one triangle: every apex gives it
    }
    return found;
  }

  /// Replaces the flip's old tets by its new ones, in subdomain `kept_region`: the old slots
  /// are reused first, in order; more are appended.
  void apply(const Flip& best, int kept_region) {
    for (const int u : best.old) {
      leave(u);
      m_alive[static_cast<std::size_t>(u)] = 0;
    }
    const std::vector<int>& slots = best.old;
    for (std::size_t m = 0; m < best.made.size(); ++m) {
      int slot;
      if (m < slots.size()) {
        slot = slots[m];
      } else {
        slot = static_cast<int>(m_tets.size());
        m_tets.emplace_back();
        m_region.push_back(kept_region);
        m_alive.push_back(0);
      }
      m_tets[static_cast<std::size_t>(slot)] = best.made[m];
      m_region[static_cast<std::size_t>(slot)] = kept_region;
      m_alive[static_cast<std::size_t>(slot)] = 1;
      enter(slot);
    }
  }

  TetMesh& m_mesh;
  bool m_labelled;
  std::vector<Eigen::Vector4i> m_tets;
  std::vector<int> m_region;
  std::vector<char> m_alive;
  std::map<FaceKey, std::vector<int>> m_faces;
  std::vector<std::vector<int>> m_star;
};

} // namespace

int flip_slivers(TetMesh& mesh, double bound_deg, int passes) {
  FlipRepair repair(mesh);
  int flips = 0;
  for (int pass = 0; pass < passes; ++pass) {
    const int flips_in_pass = repair.pass(bound_deg);
    flips += flips_in_pass;
    if (flips_in_pass == 0) break;
  }
  if (flips == 0) return 0;
  repair.write_back();
  return flips;
}

} // namespace phantasm
