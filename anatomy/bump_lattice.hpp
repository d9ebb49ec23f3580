// BumpLattice: which bumps of a patch may reach each part of its triangle, so that a height or
// patch function sums the few bumps near a point instead of every bump of the patch.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace phantasm {

struct PatchBump;

/// The bumps of one patch that may be non-zero in each cell of a k_cells^2 lattice over the
/// (u, v) unit square, in bump order. Fitted patches carry tens of narrow bumps side by side (27
/// per patch on the Colin head), of which a few cover any one point. A bump is listed in a cell
/// when its support's bounding box meets the cell and its ellipse {d^T S d < 1} comes within a
/// margin of it (the least d^T S d over the cell's rectangle is at most 1 + 1e-6): far beyond the
/// rounding of either way Q is computed (PatchBump::add_height, the patch quadric), so a bump
/// left out of a point's cell has Q <= 0 there as computed, and a sum over the cell's bumps in
/// their order is bit for bit the sum over every bump. Bumps whose shape is not positive definite,
/// ill conditioned or huge, are listed everywhere; so are all bumps for a point outside the unit
/// square or not a number.
class BumpLattice {
public:
  static constexpr int k_cells = 8;

  /// A range of bump indices, ascending.
  struct Bumps {
    const std::uint32_t* first = nullptr;
    const std::uint32_t* last = nullptr;
    const std::uint32_t* begin() const { return first; }
    const std::uint32_t* end() const { return last; }
    std::size_t size() const { return static_cast<std::size_t>(last - first); }
  };

  BumpLattice() = default;
  /// @param bumps a patch's bumps (S taken as its symmetric part)
  explicit BumpLattice(const std::vector<PatchBump>& bumps);

  /// The bumps that may be non-zero at (u, v).
  Bumps at(double u, double v) const {
    if (u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0) {
      const int i = u < 1.0 ? static_cast<int>(u * k_cells) : k_cells - 1; // u * k_cells < k_cells
      const int j = v < 1.0 ? static_cast<int>(v * k_cells) : k_cells - 1;
      return cell_entry(static_cast<std::size_t>(j * k_cells + i));
    }
    return all();
  }
  /// The bumps listed in cell (i, j) (i along u), for tests and statistics.
  Bumps cell(int i, int j) const;
  /// Every bump.
  Bumps all() const { return cell_entry(static_cast<std::size_t>(k_cells) * k_cells); }

private:
  Bumps cell_entry(std::size_t c) const {
    if (m_first.empty()) return {};
    return {m_bumps.data() + m_first[c], m_bumps.data() + m_first[c + 1]};
  }
  std::vector<std::uint32_t> m_bumps; ///< cell by cell, then every bump
  std::vector<std::uint32_t> m_first; ///< cell c's bumps: m_bumps[m_first[c], m_first[c + 1])
};

} // namespace phantasm
