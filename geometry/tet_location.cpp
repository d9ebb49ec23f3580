// Barycentric coordinates of points in tetrahedra and point location in tet meshes; see
// tet_location.hpp.
#include "geometry/tet_location.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>

namespace phantasm {

Eigen::Vector4d tet_barycentric(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  Eigen::Matrix3d D;
  D << b - a, c - a, d - a;
  const Eigen::Vector3d l = D.inverse() * (x - a);
  return {1.0 - l.sum(), l[0], l[1], l[2]};
}

TetMeshLocator::TetMeshLocator(const Eigen::MatrixX3d& x, const Eigen::MatrixX4i& tets) {
  const auto n = static_cast<std::size_t>(tets.rows());
  m_inverse.reserve(n);
  m_origin.reserve(n);
  m_tet_low.reserve(n);
  m_tet_high.reserve(n);
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    Eigen::Matrix3d D;
    Eigen::Vector3d low = x.row(tets(t, 0)).transpose(), high = low;
    for (int k = 0; k < 3; ++k) {
      D.col(k) = (x.row(tets(t, k + 1)) - x.row(tets(t, 0))).transpose();
      low = low.cwiseMin(x.row(tets(t, k + 1)).transpose());
      high = high.cwiseMax(x.row(tets(t, k + 1)).transpose());
    }
    m_inverse.push_back(D.inverse());
    m_origin.push_back(x.row(tets(t, 0)).transpose());
    m_tet_low.push_back(low);
    m_tet_high.push_back(high);
    m_low = m_low.cwiseMin(low);
    m_high = m_high.cwiseMax(high);
  }
  build_grid();
}

void TetMeshLocator::build_grid() {
  const std::size_t n = m_inverse.size();
  if (n == 0) return;
  // Cells about as large as a tet's box, and no more than 8 per tet (a mesh that fills little
  // of its box, a thin shell, gets larger cells).
  double mean_extent = 0.0;
  for (std::size_t t = 0; t < n; ++t) {
    const double extent = (m_tet_high[t] - m_tet_low[t]).maxCoeff();
    mean_extent += extent / static_cast<double>(n);
    m_largest_extent_mm = std::max(m_largest_extent_mm, extent);
  }
  m_grid_low = m_low.array() - k_grid_margin_mm;
  const Eigen::Vector3d size = (m_high - m_low).array() + 2.0 * k_grid_margin_mm;
  m_cell_mm = std::max({mean_extent, std::cbrt(size.prod() / (8.0 * static_cast<double>(n))), 1e-3});
  // One cell more than the box needs: a point on its upper faces lies in the last cell.
  for (int a = 0; a < 3; ++a)
    m_cells[a] = static_cast<int>(std::floor(size[a] / m_cell_mm)) + 1;
  const auto cell_range = [&](std::size_t t, Eigen::Array3i& first, Eigen::Array3i& last) {
    for (int a = 0; a < 3; ++a) {
      const auto at = [&](double x_mm) {
        return std::clamp(static_cast<int>(std::floor((x_mm - m_grid_low[a]) / m_cell_mm)), 0,
                          m_cells[a] - 1);
      };
      first[a] = at(m_tet_low[t][a] - k_grid_margin_mm);
      last[a] = at(m_tet_high[t][a] + k_grid_margin_mm);
    }
  };
  // Two passes over the tets in list order: count per cell, then fill (so each cell lists its
  // tets in list order).
  const std::size_t cells = static_cast<std::size_t>(m_cells.cast<std::int64_t>().prod());
  m_cell_start.assign(cells + 1, 0);
  Eigen::Array3i first, last;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<std::int64_t> next(m_cell_start.begin(), m_cell_start.end() - 1);
    for (std::size_t t = 0; t < n; ++t) {
      cell_range(t, first, last);
      for (int k = first[2]; k <= last[2]; ++k)
        for (int j = first[1]; j <= last[1]; ++j)
          for (int i = first[0]; i <= last[0]; ++i) {
            const auto c =
                static_cast<std::size_t>((static_cast<std::int64_t>(k) * m_cells[1] + j) * m_cells[0] + i);
            if (pass == 0)
              ++m_cell_start[c + 1];
            else
              m_cell_tets[static_cast<std::size_t>(next[c]++)] = static_cast<std::int32_t>(t);
          }
    }
    if (pass == 0) {
      for (std::size_t c = 0; c < cells; ++c)
        m_cell_start[c + 1] += m_cell_start[c];
      m_cell_tets.resize(static_cast<std::size_t>(m_cell_start.back()));
    }
  }
}

Eigen::Index TetMeshLocator::cell_of(const Eigen::Vector3d& x) const {
  if (m_cell_start.empty()) return -1;
  Eigen::Index cell = 0;
  for (int a = 2; a >= 0; --a) {
    const double at = std::floor((x[a] - m_grid_low[a]) / m_cell_mm);
    if (!(at >= 0.0 && at < m_cells[a])) return -1;
    cell = cell * m_cells[a] + static_cast<Eigen::Index>(at);
  }
  return cell;
}

std::optional<TetLocation> TetMeshLocator::find(const Eigen::Vector3d& x, double weight_tolerance,
                                                double box_tolerance_mm) const {
  if ((x.array() < m_low.array() - box_tolerance_mm).any() ||
      (x.array() > m_high.array() + box_tolerance_mm).any())
    return std::nullopt;
  const auto holds = [&](std::size_t t) -> std::optional<TetLocation> {
    if ((x.array() < m_tet_low[t].array() - box_tolerance_mm).any() ||
        (x.array() > m_tet_high[t].array() + box_tolerance_mm).any())
      return std::nullopt;
    const Eigen::Vector4d w = barycentric(static_cast<Eigen::Index>(t), x);
    if (w.minCoeff() >= -weight_tolerance) return TetLocation{static_cast<Eigen::Index>(t), w};
    return std::nullopt;
  };
  if (box_tolerance_mm <= k_grid_margin_mm) {
    const Eigen::Index cell = cell_of(x);
    if (cell < 0) return std::nullopt;
    for (auto n = m_cell_start[static_cast<std::size_t>(cell)];
         n < m_cell_start[static_cast<std::size_t>(cell) + 1]; ++n)
      if (auto found = holds(static_cast<std::size_t>(m_cell_tets[static_cast<std::size_t>(n)])))
        return found;
    return std::nullopt;
  }
  for (std::size_t t = 0; t < m_inverse.size(); ++t) {
    if (auto found = holds(t)) return found;
  }
  return std::nullopt;
}

TetLocation TetMeshLocator::nearest(const Eigen::Vector3d& x) const {
  // Inside: the first tet of x's cell holding x is the first of the whole list (every tet
  // holding x meets the cell, and the cell lists them in list order).
  if (const Eigen::Index cell = cell_of(x); cell >= 0) {
    for (auto n = m_cell_start[static_cast<std::size_t>(cell)];
         n < m_cell_start[static_cast<std::size_t>(cell) + 1]; ++n) {
      const Eigen::Index t = m_cell_tets[static_cast<std::size_t>(n)];
      const Eigen::Vector4d w = barycentric(t, x);
      if (w.minCoeff() >= 0.0) return {t, w};
    }
  }
  return least_outside(x);
}

TetLocation TetMeshLocator::least_outside(const Eigen::Vector3d& x) const {
  double best = -std::numeric_limits<double>::infinity();
  TetLocation result;
  const auto consider = [&](Eigen::Index t) {
    const Eigen::Vector4d w = barycentric(t, x);
    const double smallest = w.minCoeff();
    if (smallest > best || (smallest == best && t < result.tet)) {
      best = smallest;
      result = {t, w};
    }
  };
  if (m_cell_start.empty()) {
    for (Eigen::Index t = 0; t < tet_count(); ++t)
      consider(t);
    return result;
  }
  // x's cell (outside the grid too) and the first ring of cells that meets the grid.
  Eigen::Array3i at;
  int ring = 0, last_ring = 0;
  for (int a = 0; a < 3; ++a) {
    const double cell = std::floor((x[a] - m_grid_low[a]) / m_cell_mm);
    at[a] = static_cast<int>(std::clamp(cell, -1e9, 1e9));
    ring = std::max({ring, -at[a], at[a] - (m_cells[a] - 1)});
    last_ring = std::max({last_ring, at[a], m_cells[a] - 1 - at[a]});
  }
  for (; ring <= last_ring; ++ring) {
    // A tet listed in no cell of the rings so far lies, along some axis, more than ring - 1
    // cells from x: its smallest weight is below -(ring - 1) cells / (3 largest extent), so
    // once that is below the best, no tet farther out can match it.
    if (-(ring - 1) * m_cell_mm / (3.0 * m_largest_extent_mm) < best) break;
    Eigen::Array3i low, high;
    for (int a = 0; a < 3; ++a) {
      low[a] = std::max(0, at[a] - ring);
      high[a] = std::min(m_cells[a] - 1, at[a] + ring);
    }
    for (int k = low[2]; k <= high[2]; ++k)
      for (int j = low[1]; j <= high[1]; ++j)
        for (int i = low[0]; i <= high[0]; ++i) {
          if (std::max({std::abs(i - at[0]), std::abs(j - at[1]), std::abs(k - at[2])}) != ring) continue;
          const auto c =
              static_cast<std::size_t>((static_cast<std::int64_t>(k) * m_cells[1] + j) * m_cells[0] + i);
          for (auto n = m_cell_start[c]; n < m_cell_start[c + 1]; ++n)
            consider(m_cell_tets[static_cast<std::size_t>(n)]);
        }
  }
  return result;
}

} // namespace phantasm
