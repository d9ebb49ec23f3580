#include "anatomy/bump_lattice.hpp"

#include "anatomy/patch_surface.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>

namespace phantasm {
namespace {

/// The least d^T S d over the rectangle [low, high] (d = p - c, S symmetric positive definite):
/// 0 when c lies inside, else the least of the four edges' minima (each a clamped 1D quadratic).
double least_form_over_box(const Eigen::Matrix2d& S, const Eigen::Vector2d& c, const Eigen::Vector2d& low,
                           const Eigen::Vector2d& high) {
  if ((c.array() >= low.array()).all() && (c.array() <= high.array()).all()) return 0.0;
  double least = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 2; ++a) {
    const int b = 1 - a;
    for (const double fixed : {low[a], high[a]}) {
      // On the edge p_a = fixed: d_a is fixed, d_b free in [low_b - c_b, high_b - c_b].
      const double da = fixed - c[a];
      const double db = std::clamp(-S(a, b) * da / S(b, b), low[b] - c[b], high[b] - c[b]);
      least = std::min(least, S(a, a) * da * da + 2.0 * S(a, b) * da * db + S(b, b) * db * db);
    }
  }
  return least;
}

} // namespace

BumpLattice::BumpLattice(const std::vector<PatchBump>& bumps) {
  constexpr std::size_t k_lists = static_cast<std::size_t>(k_cells) * k_cells + 1;
  static_assert(k_lists - 1 <= 64, "a bump's cells are the bits of one 64-bit word");
  const auto cell_of = [](double x) {
    return static_cast<int>(std::clamp(std::floor(x * k_cells), 0.0, k_cells - 1.0));
  };
  // Each bump's cells as the bits of a word, and each list's length: the lists are then laid out
  // once, in two arrays, instead of growing a list per cell (65 allocations a patch, millions on
  // the Colin head, where reading the anatomy from the cache builds a lattice per patch).
  std::vector<std::uint64_t> cells_of(bumps.size(), 0);
  std::uint32_t lengths[k_lists] = {};
  for (std::size_t n = 0; n < bumps.size(); ++n) {
    const PatchBump& bump = bumps[n];
    const Eigen::Matrix2d S = 0.5 * (bump.shape_uv + bump.shape_uv.transpose());
    const double det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
    const Eigen::Vector2d& c = bump.center_uv;
    // Well conditioned (det S / (S_uu S_vv) = 1 - rho^2 >= 1e-6) and of moderate size: then
    // d^T S d is computed, either way, to far within the margin of 1e-6.
    const bool cull = c.allFinite() && S(0, 0) > 0.0 && S(1, 1) > 0.0 && S(0, 0) < 1e6 && S(1, 1) < 1e6 &&
                      det > 1e-6 * S(0, 0) * S(1, 1);
    int first[2] = {0, 0}, last[2] = {k_cells - 1, k_cells - 1};
    if (cull) {
      // The support lies within c +- (sqrt((S^-1)_uu), sqrt((S^-1)_vv)).
      const Eigen::Vector2d half(std::sqrt(S(1, 1) / det), std::sqrt(S(0, 0) / det));
      for (int a = 0; a < 2; ++a) {
        const double margin = 1e-6 * half[a] + 1e-9;
        first[a] = cell_of(c[a] - half[a] - margin);
        last[a] = cell_of(c[a] + half[a] + margin);
      }
    }
    for (int j = first[1]; j <= last[1]; ++j) {
      for (int i = first[0]; i <= last[0]; ++i) {
        const Eigen::Vector2d low(double(i) / k_cells, double(j) / k_cells);
        const Eigen::Vector2d high(double(i + 1) / k_cells, double(j + 1) / k_cells);
        if (cull && least_form_over_box(S, c, low, high) > 1.0 + 1e-6) continue;
        const int cell = j * k_cells + i;
        cells_of[n] |= std::uint64_t{1} << cell;
        ++lengths[cell];
      }
    }
    ++lengths[k_lists - 1];
  }
  m_first.resize(k_lists + 1);
  m_first[0] = 0;
  for (std::size_t c = 0; c < k_lists; ++c)
    m_first[c + 1] = m_first[c] + lengths[c];
  m_bumps.resize(m_first[k_lists]);
  // Bumps in ascending order into each of their cells' lists, then into the list of every bump.
  std::uint32_t next[k_lists];
  std::copy(m_first.begin(), m_first.end() - 1, next);
  for (std::size_t n = 0; n < bumps.size(); ++n) {
    for (std::uint64_t bits = cells_of[n]; bits != 0; bits &= bits - 1) // lowest cell first
      m_bumps[next[__builtin_ctzll(bits)]++] = static_cast<std::uint32_t>(n);
    m_bumps[next[k_lists - 1]++] = static_cast<std::uint32_t>(n);
  }
}

BumpLattice::Bumps BumpLattice::cell(int i, int j) const {
  return cell_entry(static_cast<std::size_t>(j * k_cells + i));
}

} // namespace phantasm
