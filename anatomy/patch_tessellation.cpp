// Adaptive, watertight tessellation of a patch surface.

#include "anatomy/patch_surface.hpp"
#include "core/cancellation.hpp"

#include <algorithm>
#include <atomic>
#include <map>

namespace phantasm {
namespace {

// 2^8 segments per base edge; a patch that needs more reports its remaining deviation.
constexpr int k_max_level = 8;

int grid_index(int i, int j, int n) {
  // Row j holds n + 1 - j points; rows before j hold sum_{r<j} (n + 1 - r).
  return j * (n + 1) - j * (j - 1) / 2 + i;
}

} // namespace

int PatchSurface::level_for(Eigen::Index t, double max_deviation_mm, double* deviation,
                            std::vector<Eigen::Vector3d>* grid) const {
  *deviation = 0.0;
  if (m_perturbations[static_cast<std::size_t>(t)].empty()) return 0;
  // The grid of one level is the corner grid of the next: each level evaluates its points once.
  auto corners = patch_grid_points(t, 0);
  for (int level = 0; level <= k_max_level; ++level) {
    // Deviation of the level-`level` interpolation, measured at the midpoints of its edges.
    const int fine = 2 << level;
    // The next level's grid: its even points are this level's (i / n = 2i / 2n exactly), only
    // the others are new.
    std::vector<Eigen::Vector3d> points(static_cast<std::size_t>((fine + 1) * (fine + 2) / 2));
    for (int j = 0; j <= fine; ++j) {
      for (int i = 0; i + j <= fine; ++i) {
        points[static_cast<std::size_t>(grid_index(i, j, fine))] =
            i % 2 == 0 && j % 2 == 0 ? corners[static_cast<std::size_t>(grid_index(i / 2, j / 2, fine / 2))]
                                     : surface_point(t, double(i) / fine, double(j) / fine);
      }
    }
    double worst = 0.0;
    for (int j = 0; j <= fine; ++j) {
      for (int i = 0; i + j <= fine; ++i) {
        if (i % 2 == 0 && j % 2 == 0) continue;
        int ai, aj, bi, bj;
        if (j % 2 == 0) {
          ai = i - 1, aj = j, bi = i + 1, bj = j;
        } else if (i % 2 == 0) {
          ai = i, aj = j - 1, bi = i, bj = j + 1;
        } else {
          ai = i + 1, aj = j - 1, bi = i - 1, bj = j + 1;
        }
        const Eigen::Vector3d mid = 0.5 * (points[static_cast<std::size_t>(grid_index(ai, aj, fine))] +
                                           points[static_cast<std::size_t>(grid_index(bi, bj, fine))]);
        worst = std::max(worst, (points[static_cast<std::size_t>(grid_index(i, j, fine))] - mid).norm());
      }
    }
    // Edge midpoints miss bumps that sit inside a sub-triangle (all of them at level 0, where
    // the midpoints lie on the base edges): check the centroids too.
    const int n = 1 << level;
    auto check_centroid = [&](int ai, int aj, int bi, int bj, int ci, int cj) {
      const Eigen::Vector3d mean = (corners[static_cast<std::size_t>(grid_index(ai, aj, n))] +
                                    corners[static_cast<std::size_t>(grid_index(bi, bj, n))] +
                                    corners[static_cast<std::size_t>(grid_index(ci, cj, n))]) /
                                   3.0;
      const Eigen::Vector3d actual = surface_point(t, (ai + bi + ci) / (3.0 * n), (aj + bj + cj) / (3.0 * n));
      worst = std::max(worst, (actual - mean).norm());
    };
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i + j < n; ++i) {
        check_centroid(i, j, i + 1, j, i, j + 1);
        if (i + j < n - 1) check_centroid(i + 1, j, i + 1, j + 1, i, j + 1);
      }
    }
    *deviation = worst;
    if (worst <= max_deviation_mm) {
      if (grid) *grid = std::move(corners);
      return level;
    }
    corners = std::move(points);
  }
  return k_max_level; // the finest level; *deviation tells how far it still is
}

double PatchSurface::area(double max_deviation_mm) const {
  return surface_area(tessellate(max_deviation_mm));
}

namespace {

/// Every undirected base edge split into as many segments as its finer neighbour needs. Its
/// points are computed once, from the lower vertex index, so both sides share them exactly;
/// bumps vanish on base edges, so the surface there is the straight edge.
class EdgeSplits {
public:
  /// The splits of the edges of `base` (whose triangle across edge k of t is neighbours(t, k)),
  /// their inner points appended to `points`.
  EdgeSplits(const TriangleMesh& base, const Eigen::MatrixX3i& neighbours, const std::vector<int>& level,
             std::vector<Eigen::Vector3d>& points) {
    for (Eigen::Index t = 0; t < base.face_count(); ++t) {
      for (int k = 0; k < 3; ++k) {
        const auto key = std::minmax(base.faces(t, k), base.faces(t, (k + 1) % 3));
        if (m_edges.count(key)) continue;
        const int finer =
            std::max(level[static_cast<std::size_t>(t)], level[static_cast<std::size_t>(neighbours(t, k))]);
        const int segments = 1 << finer;
        m_edges[key] = {segments, static_cast<int>(points.size())};
        const Eigen::Vector3d a = base.vertex(key.first), b = base.vertex(key.second);
        for (int s = 1; s < segments; ++s)
          points.push_back(a + (double(s) / segments) * (b - a));
      }
    }
  }

  /// The segments of the edge (from, to).
  int segments(int from, int to) const { return m_edges.at(std::minmax(from, to)).segments; }

  /// The point at fraction numerator/denominator along the directed edge (from, to).
  int point(int from, int to, int numerator, int denominator) const {
    if (numerator == 0) return from;
    if (numerator == denominator) return to;
    const EdgeSplit& e = m_edges.at(std::minmax(from, to));
    const int steps = numerator * (e.segments / denominator);
    return e.first_point + (from < to ? steps : e.segments - steps) - 1;
  }

private:
  struct EdgeSplit {
    int segments;
    int first_point;
  };
  std::map<std::pair<int, int>, EdgeSplit> m_edges;
};

/// The triangles of base triangle t at level n = 2^level: its grid's points (those inside it
/// from `grid` when given, else evaluated; those on its edges from the edges' splits) appended to
/// `points`, its sub-triangles to `triangles`, fanned from their centre where a finer neighbour
/// splits an edge further.
void tessellate_patch(const PatchSurface& surface, Eigen::Index t, int n, const EdgeSplits& edges,
                      const std::vector<Eigen::Vector3d>& grid, std::vector<Eigen::Vector3d>& points,
                      std::vector<Eigen::Vector3i>& triangles) {
  const TriangleMesh& base = surface.base_mesh();
  const int f0 = base.faces(t, 0), f1 = base.faces(t, 1), f2 = base.faces(t, 2);
  std::vector<int> id(static_cast<std::size_t>((n + 1) * (n + 2) / 2));
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i + j <= n; ++i) {
      int global;
      if (j == 0) {
        global = edges.point(f0, f1, i, n);
      } else if (i == 0) {
        global = edges.point(f0, f2, j, n);
      } else if (i + j == n) {
        global = edges.point(f1, f2, j, n);
      } else {
        global = static_cast<int>(points.size());
        points.push_back(grid.empty() ? surface.surface_point(t, double(i) / n, double(j) / n)
                                      : grid[static_cast<std::size_t>(grid_index(i, j, n))]);
      }
      id[static_cast<std::size_t>(grid_index(i, j, n))] = global;
    }
  }
  // The finer points of a base edge between two consecutive grid points (exclusive), in order.
  auto between = [&](int ia, int ja, int ib, int jb) {
    std::vector<int> inner;
    int from, to, na, nb;
    if (ja == 0 && jb == 0) {
      from = f0, to = f1, na = ia, nb = ib;
    } else if (ia == 0 && ib == 0) {
      from = f0, to = f2, na = ja, nb = jb;
    } else if (ia + ja == n && ib + jb == n) {
      from = f1, to = f2, na = ja, nb = jb;
    } else {
      return inner;
    }
    const int segments = edges.segments(from, to);
    const int m = segments / n;
    const int direction = nb > na ? 1 : -1;
    for (int s = 1; s < m; ++s)
      inner.push_back(edges.point(from, to, na * m + direction * s, segments));
    return inner;
  };
  auto emit = [&](std::array<std::pair<int, int>, 3> corners) {
    std::vector<int> polygon;
    for (int k = 0; k < 3; ++k) {
      const auto [ia, ja] = corners[static_cast<std::size_t>(k)];
      const auto [ib, jb] = corners[static_cast<std::size_t>((k + 1) % 3)];
      polygon.push_back(id[static_cast<std::size_t>(grid_index(ia, ja, n))]);
      for (int p : between(ia, ja, ib, jb))
        polygon.push_back(p);
    }
    if (polygon.size() == 3) {
      triangles.push_back({polygon[0], polygon[1], polygon[2]});
      return;
    }
    // A fan from the sub-triangle's centre keeps the finer edge points of the neighbour.
    double cu = 0.0, cv = 0.0;
    for (const auto& [i, j] : corners)
      cu += i, cv += j;
    const int centre = static_cast<int>(points.size());
    points.push_back(surface.surface_point(t, cu / (3.0 * n), cv / (3.0 * n)));
    for (std::size_t k = 0; k < polygon.size(); ++k) {
      triangles.push_back({polygon[k], polygon[(k + 1) % polygon.size()], centre});
    }
  };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i + j < n; ++i) {
      emit({{{i, j}, {i + 1, j}, {i, j + 1}}});
      if (i + j < n - 1) emit({{{i + 1, j}, {i + 1, j + 1}, {i, j + 1}}});
    }
  }
}

} // namespace

TriangleMesh PatchSurface::tessellate(double max_deviation_mm, TessellationStats* stats) const {
  const Eigen::Index nf = m_base.face_count();
  std::vector<int> level(static_cast<std::size_t>(nf));
  TessellationStats local_stats;
  // A cancelled run gets an empty mesh at once (a real organ's tessellation takes seconds; callers
  // may run inside OpenMP regions, which no exception may leave, and poll the flag before using it).
  // Each patch's level and the points of its grid at that level, which the triangles below take
  // as they are (the same evaluations as surface_point's), found in parallel.
  std::vector<std::vector<Eigen::Vector3d>> grids(static_cast<std::size_t>(nf));
  std::vector<double> deviations(static_cast<std::size_t>(nf), 0.0);
  std::atomic<bool> cancelled{false};
#pragma omp parallel for schedule(dynamic, 1)
  for (Eigen::Index t = 0; t < nf; ++t) {
    if (cancelled.load(std::memory_order_relaxed)) continue;
    if (cancellation_requested()) {
      cancelled = true;
      continue;
    }
    const auto f = static_cast<std::size_t>(t);
    level[f] = level_for(t, max_deviation_mm, &deviations[f], &grids[f]);
  }
  if (cancelled) return TriangleMesh();
  for (std::size_t f = 0; f < level.size(); ++f) {
    local_stats.max_level = std::max(local_stats.max_level, level[f]);
    local_stats.max_deviation_mm = std::max(local_stats.max_deviation_mm, deviations[f]);
  }
  if (stats) *stats = local_stats;

  std::vector<Eigen::Vector3d> points;
  for (Eigen::Index v = 0; v < m_base.vertex_count(); ++v)
    points.push_back(m_base.vertex(v));
  const EdgeSplits edges(m_base, m_neighbours, level, points);
  std::vector<Eigen::Vector3i> triangles;
  for (Eigen::Index t = 0; t < nf; ++t) {
    if (cancellation_requested()) return TriangleMesh();
    std::vector<Eigen::Vector3d>& grid = grids[static_cast<std::size_t>(t)];
    tessellate_patch(*this, t, 1 << level[static_cast<std::size_t>(t)], edges, grid, points, triangles);
    std::vector<Eigen::Vector3d>().swap(grid); // copied into points
  }

  TriangleMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i)
    mesh.vertices.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
  mesh.faces.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (std::size_t i = 0; i < triangles.size(); ++i)
    mesh.faces.row(static_cast<Eigen::Index>(i)) = triangles[i].transpose();
  return mesh;
}

} // namespace phantasm
