// Closest points on a closed triangle mesh and the pseudonormal sign of the distance; see
// mesh_signed_distance.hpp.
#include "geometry/mesh_signed_distance.hpp"

#include "core/grid.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

namespace phantasm {
namespace {

double box_distance_squared(const Eigen::Vector3d& x, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return (lo - x).cwiseMax(x - hi).cwiseMax(0.0).squaredNorm();
}

/// Squared distance between the boxes [lo_a, hi_a] and [lo_b, hi_b] (0 where they overlap). For
/// a point x inside box a it is at most box_distance_squared(x, lo_b, hi_b), in floating point too
/// (rounding is monotone).
double box_box_distance_squared(const Eigen::Vector3d& lo_a, const Eigen::Vector3d& hi_a,
                                const Eigen::Vector3d& lo_b, const Eigen::Vector3d& hi_b) {
  return (lo_a - hi_b).cwiseMax(lo_b - hi_a).cwiseMax(0.0).squaredNorm();
}

/// 1e-9 of the scale of the coordinates (the query's and the mesh's): the rounding of a plane's
/// or a closest point's distance is about 1e-16 of it.
double rounding_margin(const Eigen::Vector3d& x, const Eigen::Vector3d& mesh_min,
                       const Eigen::Vector3d& mesh_max) {
  return 1e-9 * (1.0 + x.cwiseAbs().maxCoeff() +
                 std::max(mesh_min.cwiseAbs().maxCoeff(), mesh_max.cwiseAbs().maxCoeff()));
}

std::vector<std::array<int, 3>> triangle_list(const Eigen::MatrixX3i& faces) {
  std::vector<std::array<int, 3>> triangles(static_cast<std::size_t>(faces.rows()));
  for (Eigen::Index t = 0; t < faces.rows(); ++t)
    triangles[static_cast<std::size_t>(t)] = {faces(t, 0), faces(t, 1), faces(t, 2)};
  return triangles;
}

} // namespace

SignedDistanceMesh::SignedDistanceMesh(std::vector<std::array<int, 3>> triangles)
    : m_triangles(std::move(triangles)) {
  connect();
}

SignedDistanceMesh::SignedDistanceMesh(const Eigen::MatrixX3i& faces) : m_triangles(triangle_list(faces)) {
  connect();
}

void SignedDistanceMesh::connect() {
  // Vertices numbered by first use, edges by their vertex pair: the normals are summed per vertex
  // and per edge in triangle order, then read per corner and per triangle edge (the numbering
  // only names the sums, so any numbering gives the same normals). Each edge is found among the
  // half-edges of its lower-numbered vertex (a handful each), after a counting sort of the
  // half-edges by that vertex: linear in the triangles, where a map of vertex pairs cost about
  // a microsecond per half-edge on the millions of triangles of a fine tessellation.
  int largest = -1;
  for (const auto& t : m_triangles)
    largest = std::max({largest, t[0], t[1], t[2]});
  std::vector<int> local(static_cast<std::size_t>(largest + 1), -1);
  int vertices = 0;
  m_corner_vertex.resize(m_triangles.size());
  m_edge.resize(m_triangles.size());
  for (std::size_t t = 0; t < m_triangles.size(); ++t) {
    for (std::size_t k = 0; k < 3; ++k) {
      int& id = local[static_cast<std::size_t>(m_triangles[t][k])];
      if (id < 0) id = vertices++;
      m_corner_vertex[t][k] = id;
    }
  }
  // Half-edge h = 3 t + k runs from corner k to corner k + 1 of triangle t.
  const std::size_t half_edges = 3 * m_triangles.size();
  const auto ends = [&](std::size_t h) -> std::pair<int, int> {
    const std::array<int, 3>& c = m_corner_vertex[h / 3];
    const int a = c[h % 3], b = c[(h % 3 + 1) % 3];
    return {std::min(a, b), std::max(a, b)};
  };
  std::vector<std::size_t> first(static_cast<std::size_t>(vertices) + 1, 0);
  for (std::size_t h = 0; h < half_edges; ++h)
    ++first[static_cast<std::size_t>(ends(h).first) + 1];
  std::partial_sum(first.begin(), first.end(), first.begin());
  std::vector<std::size_t> by_lower(half_edges), next_slot(first.begin(), first.end() - 1);
  for (std::size_t h = 0; h < half_edges; ++h)
    by_lower[next_slot[static_cast<std::size_t>(ends(h).first)]++] = h;
  int edges = 0;
  for (std::size_t v = 0; v + 1 < first.size(); ++v) {
    for (std::size_t i = first[v]; i < first[v + 1]; ++i) {
      const std::size_t h = by_lower[i];
      const int upper = ends(h).second;
      int id = -1;
      for (std::size_t j = first[v]; j < i && id < 0; ++j)
        if (ends(by_lower[j]).second == upper) id = m_edge[by_lower[j] / 3][by_lower[j] % 3];
      m_edge[h / 3][h % 3] = id >= 0 ? id : edges++;
    }
  }
  m_vertex_normals.assign(static_cast<std::size_t>(vertices), Eigen::Vector3d::Zero());
  m_edge_normals.assign(static_cast<std::size_t>(edges), Eigen::Vector3d::Zero());
}

void SignedDistanceMesh::update(const Eigen::MatrixX3d& p) {
  const std::size_t n = m_triangles.size();
  m_corners.resize(n);
  m_face_normals.assign(n, Eigen::Vector3d::Zero());
  m_face_min.resize(n);
  m_face_max.resize(n);
  std::fill(m_vertex_normals.begin(), m_vertex_normals.end(), Eigen::Vector3d::Zero());
  std::fill(m_edge_normals.begin(), m_edge_normals.end(), Eigen::Vector3d::Zero());
  m_min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  m_max = -m_min;
  for (std::size_t t = 0; t < n; ++t) {
    const auto& v = m_triangles[t];
    auto& x = m_corners[t];
    for (std::size_t k = 0; k < 3; ++k)
      x[k] = p.row(v[k]).transpose();
    const Eigen::Vector3d normal = (x[1] - x[0]).cross(x[2] - x[0]);
    const double length = normal.norm();
    const Eigen::Vector3d unit = length > 0.0 ? Eigen::Vector3d(normal / length) : Eigen::Vector3d::Zero();
    m_face_normals[t] = unit;
    m_face_min[t] = x[0].cwiseMin(x[1]).cwiseMin(x[2]);
    m_face_max[t] = x[0].cwiseMax(x[1]).cwiseMax(x[2]);
    m_min = m_min.cwiseMin(m_face_min[t]);
    m_max = m_max.cwiseMax(m_face_max[t]);
    for (std::size_t k = 0; k < 3; ++k) {
      const Eigen::Vector3d e1 = x[(k + 1) % 3] - x[k], e2 = x[(k + 2) % 3] - x[k];
      // atan2 of |sin| and cos: accurate at every angle, unlike acos of the normalized dot product.
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      m_vertex_normals[static_cast<std::size_t>(m_corner_vertex[t][k])] += angle * unit;
      m_edge_normals[static_cast<std::size_t>(m_edge[t][k])] += unit;
    }
  }
  m_nodes.clear();
  m_tree_triangles.clear();
}

void SignedDistanceMesh::build_search_tree() {
  m_nodes.clear();
  m_order.resize(m_triangles.size());
  std::iota(m_order.begin(), m_order.end(), 0);
  if (m_triangles.empty()) return;
  std::vector<Eigen::Vector3d> centre(m_triangles.size());
  for (std::size_t t = 0; t < m_triangles.size(); ++t)
    centre[t] = 0.5 * (m_face_min[t] + m_face_max[t]);
  // Median splits along the longest side of the triangle centres' box, leaves of at most 4
  // triangles; built depth first with an explicit stack (node, range), children after parents.
  struct Pending {
    int node, begin, end;
  };
  std::vector<Pending> pending{{0, 0, static_cast<int>(m_triangles.size())}};
  m_nodes.emplace_back();
  while (!pending.empty()) {
    const Pending p = pending.back();
    pending.pop_back();
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    Eigen::Vector3d centre_lo = lo, centre_hi = hi;
    for (int i = p.begin; i < p.end; ++i) {
      const auto t = static_cast<std::size_t>(m_order[static_cast<std::size_t>(i)]);
      lo = lo.cwiseMin(m_face_min[t]);
      hi = hi.cwiseMax(m_face_max[t]);
      centre_lo = centre_lo.cwiseMin(centre[t]);
      centre_hi = centre_hi.cwiseMax(centre[t]);
    }
    m_nodes[static_cast<std::size_t>(p.node)].lo = lo;
    m_nodes[static_cast<std::size_t>(p.node)].hi = hi;
    if (p.end - p.begin <= 4) {
      m_nodes[static_cast<std::size_t>(p.node)].begin = p.begin;
      m_nodes[static_cast<std::size_t>(p.node)].end = p.end;
      continue;
    }
    int axis = 0;
    (centre_hi - centre_lo).maxCoeff(&axis);
    const int middle = p.begin + (p.end - p.begin) / 2;
    // Ties broken by triangle index: the same tree on every run.
    std::nth_element(m_order.begin() + p.begin, m_order.begin() + middle, m_order.begin() + p.end,
                     [&](int a, int b) {
                       const double ca = centre[static_cast<std::size_t>(a)][axis],
                                    cb = centre[static_cast<std::size_t>(b)][axis];
                       return ca < cb || (ca == cb && a < b);
                     });
    const auto first = static_cast<int>(m_nodes.size());
    m_nodes.emplace_back();
    m_nodes.emplace_back();
    m_nodes[static_cast<std::size_t>(p.node)].first_child = first;
    pending.push_back({first + 1, middle, p.end});
    pending.push_back({first, p.begin, middle});
  }
  // Each leaf's triangles side by side: a search reads them in this order.
  m_tree_triangles.resize(m_order.size());
  for (std::size_t i = 0; i < m_order.size(); ++i) {
    const auto t = static_cast<std::size_t>(m_order[i]);
    m_tree_triangles[i] = {m_corners[t], m_face_min[t], m_face_max[t], m_face_normals[t], m_order[i]};
  }
}

MeshClosestPoint SignedDistanceMesh::closest(const Eigen::Vector3d& x) const {
  return m_nodes.empty() ? scan(x) : search_tree(x, MeshClosestPoint{});
}

MeshClosestPoint SignedDistanceMesh::closest(const Eigen::Vector3d& x, int hint) const {
  if (m_nodes.empty() || hint < 0 || hint >= static_cast<int>(m_triangles.size())) return closest(x);
  // The hint's distance bounds the answer's, so every triangle at least as near (a tie of lower
  // index included) is still visited: the answer does not depend on the hint.
  const auto& v = m_corners[static_cast<std::size_t>(hint)];
  const TriangleClosestPoint c = closest_point_on_triangle(x, v[0], v[1], v[2]);
  return search_tree(x, MeshClosestPoint{hint, c, (c.point - x).squaredNorm()});
}

MeshClosestPoint SignedDistanceMesh::scan(const Eigen::Vector3d& x) const {
  MeshClosestPoint best;
  for (std::size_t t = 0; t < m_triangles.size(); ++t) {
    if (box_distance_squared(x, m_face_min[t], m_face_max[t]) >= best.distance_squared) continue;
    const auto& v = m_corners[t];
    const TriangleClosestPoint c = closest_point_on_triangle(x, v[0], v[1], v[2]);
    const double d = (x - c.point).squaredNorm();
    if (d < best.distance_squared) best = {static_cast<int>(t), c, d};
  }
  return best;
}

void SignedDistanceMesh::visit(const Eigen::Vector3d& x, const TreeTriangle& tt, double margin,
                               MeshClosestPoint& best) const {
  if (box_distance_squared(x, tt.lo, tt.hi) > best.distance_squared) return;
  // The plane's distance bounds the triangle's from below. A triangle is passed over only when
  // its plane lies farther than the best by a margin far above the rounding of both (`margin`):
  // ties and near ties, at any distance (a point on the surface has many), still go through the
  // closest point's own arithmetic.
  const double plane = std::abs(tt.normal.dot(x - tt.corners[0])) - margin;
  if (plane > 0.0 && plane * plane > best.distance_squared) return;
  const auto& v = tt.corners;
  const TriangleClosestPoint c = closest_point_on_triangle(x, v[0], v[1], v[2]);
  const double d = (c.point - x).squaredNorm();
  // Equal distances (a shared edge or vertex) keep the lower triangle index: the answer is
  // scan()'s whatever the visiting order.
  if (d < best.distance_squared || (d == best.distance_squared && tt.triangle < best.triangle))
    best = {tt.triangle, c, d};
}

MeshClosestPoint SignedDistanceMesh::search_tree(const Eigen::Vector3d& x, MeshClosestPoint best) const {
  // Branch and bound, nearer child first: a box farther than the best so far cannot hold a
  // closer point (one exactly as far may hold a tie of lower index, which wins as in scan()).
  // The cost grows with log #F, not with the distance to the surface.
  const double margin = rounding_margin(x, m_min, m_max);
  std::array<int, 128> stack{};
  int size = 0;
  stack[static_cast<std::size_t>(size++)] = 0;
  while (size > 0) {
    const SearchNode& node = m_nodes[static_cast<std::size_t>(stack[static_cast<std::size_t>(--size)])];
    if (box_distance_squared(x, node.lo, node.hi) > best.distance_squared) continue;
    if (node.first_child < 0) {
      for (int i = node.begin; i < node.end; ++i) {
        visit(x, m_tree_triangles[static_cast<std::size_t>(i)], margin, best);
      }
      continue;
    }
    const int a = node.first_child, b = node.first_child + 1;
    const double da = box_distance_squared(x, m_nodes[static_cast<std::size_t>(a)].lo,
                                           m_nodes[static_cast<std::size_t>(a)].hi),
                 db = box_distance_squared(x, m_nodes[static_cast<std::size_t>(b)].lo,
                                           m_nodes[static_cast<std::size_t>(b)].hi);
    // Pushed far child first, so the near one is searched first.
    stack[static_cast<std::size_t>(size++)] = da <= db ? b : a;
    stack[static_cast<std::size_t>(size++)] = da <= db ? a : b;
  }
  return best;
}

void SignedDistanceMesh::near_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                  NearTriangles& near) const {
  near.entries.clear();
  if (m_nodes.empty()) return;
  const MeshClosestPoint centre = search_tree(0.5 * (lo + hi), MeshClosestPoint{});
  const auto& v = m_corners[static_cast<std::size_t>(centre.triangle)];
  double reach_squared = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d x((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(),
                            (corner & 4) ? hi.z() : lo.z());
    reach_squared =
        std::max(reach_squared, (closest_point_on_triangle(x, v[0], v[1], v[2]).point - x).squaredNorm());
  }
  // Widened far beyond the rounding of the distances (a triangle more costs a box test).
  const double reach =
      std::sqrt(reach_squared) + rounding_margin(hi.cwiseAbs().cwiseMax(lo.cwiseAbs()), m_min, m_max);
  reach_squared = reach * reach;
  std::array<int, 128> stack{};
  int size = 0;
  stack[static_cast<std::size_t>(size++)] = 0;
  while (size > 0) {
    const SearchNode& node = m_nodes[static_cast<std::size_t>(stack[static_cast<std::size_t>(--size)])];
    if (box_box_distance_squared(lo, hi, node.lo, node.hi) > reach_squared) continue;
    if (node.first_child < 0) {
      for (int i = node.begin; i < node.end; ++i) {
        const TreeTriangle& tt = m_tree_triangles[static_cast<std::size_t>(i)];
        const double d = box_box_distance_squared(lo, hi, tt.lo, tt.hi);
        if (d <= reach_squared) near.entries.push_back({d, i});
      }
      continue;
    }
    stack[static_cast<std::size_t>(size++)] = node.first_child + 1;
    stack[static_cast<std::size_t>(size++)] = node.first_child;
  }
  std::sort(near.entries.begin(), near.entries.end(),
            [&](const NearTriangles::Entry& a, const NearTriangles::Entry& b) {
              return a.block_distance_squared < b.block_distance_squared ||
                     (a.block_distance_squared == b.block_distance_squared &&
                      m_tree_triangles[static_cast<std::size_t>(a.position)].triangle <
                          m_tree_triangles[static_cast<std::size_t>(b.position)].triangle);
            });
}

MeshClosestPoint SignedDistanceMesh::closest(const Eigen::Vector3d& x, const NearTriangles& near) const {
  // Nothing gathered (no search tree): the answer of closest(x) itself.
  if (near.entries.empty()) return closest(x);
  // search_tree()'s tests on the same triangles (visit()).
  const double margin = rounding_margin(x, m_min, m_max);
  MeshClosestPoint best;
  for (const NearTriangles::Entry& e : near.entries) {
    // The rest lie at least as far from x as from the block that holds it.
    if (e.block_distance_squared > best.distance_squared) break;
    visit(x, m_tree_triangles[static_cast<std::size_t>(e.position)], margin, best);
  }
  return best;
}

Eigen::Vector3d SignedDistanceMesh::pseudonormal(const MeshClosestPoint& c) const {
  const auto t = static_cast<std::size_t>(c.triangle);
  const auto k = static_cast<std::size_t>(c.on_triangle.index);
  switch (c.on_triangle.feature) {
  case TriangleFeature::face: return m_face_normals[t];
  case TriangleFeature::edge: return m_edge_normals[static_cast<std::size_t>(m_edge[t][k])];
  case TriangleFeature::vertex: return m_vertex_normals[static_cast<std::size_t>(m_corner_vertex[t][k])];
  }
  return m_face_normals[t];
}

bool SignedDistanceMesh::inside(const Eigen::Vector3d& x, const MeshClosestPoint& c) const {
  return c.triangle >= 0 && (x - c.on_triangle.point).dot(pseudonormal(c)) < 0.0;
}

double SignedDistanceMesh::distance(const Eigen::Vector3d& x) const {
  return std::sqrt(closest(x).distance_squared);
}

double SignedDistanceMesh::signed_distance(const Eigen::Vector3d& x) const {
  const MeshClosestPoint c = closest(x);
  const double d = std::sqrt(c.distance_squared);
  return inside(x, c) ? -d : d;
}

} // namespace phantasm
