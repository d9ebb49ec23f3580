#include "voxelize/tissue_volumes.hpp"

#include "core/cancellation.hpp"
#include "core/progress.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>

namespace phantasm {
namespace {

constexpr int k_block = 8; ///< voxels along each edge of a block

/// Per block of k_block^3 voxels and per organ (organ fastest): whether the organ's level set
/// stores values near the block, and where it does not, its one value over the block (plus or
/// minus the band width: which side the block lies on).
struct BlockValues {
  Eigen::Vector3i blocks = Eigen::Vector3i::Zero();
  std::size_t organs = 0;
  std::vector<std::uint8_t> varies;
  std::vector<float> value;

  std::size_t block_of(int i, int j, int k) const {
    return static_cast<std::size_t>(i / k_block) +
           static_cast<std::size_t>(blocks.x()) *
               (static_cast<std::size_t>(j / k_block) +
                static_cast<std::size_t>(blocks.y()) * static_cast<std::size_t>(k / k_block));
  }
};

BlockValues block_values(const ImageGrid& grid, const std::vector<VoxelizedOrgan>& organs) {
  BlockValues out;
  out.blocks = (grid.dims.array() + k_block - 1) / k_block;
  out.organs = organs.size();
  const auto block_count = static_cast<std::size_t>(out.blocks.prod());
  out.varies.assign(block_count * organs.size(), 0);
  out.value.assign(block_count * organs.size(), 0.0f);
  const auto organ_count = static_cast<std::ptrdiff_t>(organs.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (std::ptrdiff_t n = 0; n < organ_count; ++n) {
    if (cancellation_requested()) continue; // no exception may leave an OpenMP region
    const auto o = static_cast<std::size_t>(n);
    // Every voxel whose cell (where its samples lie) meets a box's reach, in voxel indices: the
    // box's corners mapped onto the grid, widened by a voxel for the cell and rounding.
    for (const Eigen::AlignedBox3d& box : organs[o].level_set->block_reach_mm()) {
      Eigen::Vector3d low = Eigen::Vector3d::Constant(1e300), high = -low;
      for (int c = 0; c < 8; ++c) {
        const Eigen::Vector3d index =
            grid.index_from_world(box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)));
        low = low.cwiseMin(index);
        high = high.cwiseMax(index);
      }
      Eigen::Vector3i first, last;
      bool outside = false;
      for (int a = 0; a < 3; ++a) {
        const double lo = std::max(std::floor(low[a]) - 1.0, 0.0);
        const double hi = std::min(std::ceil(high[a]) + 1.0, static_cast<double>(grid.dims[a] - 1));
        if (lo > hi) outside = true;
        first[a] = static_cast<int>(lo) / k_block;
        last[a] = static_cast<int>(hi) / k_block;
      }
      if (outside) continue;
      for (int c = first.z(); c <= last.z(); ++c)
        for (int b = first.y(); b <= last.y(); ++b)
          for (int a = first.x(); a <= last.x(); ++a)
            out.varies[out.block_of(a * k_block, b * k_block, c * k_block) * organs.size() + o] = 1;
    }
    // Elsewhere one probe gives the block's value (any point of it: a constant tile).
    const LevelSet::Probe probe(*organs[o].level_set);
    for (int c = 0; c < out.blocks.z(); ++c)
      for (int b = 0; b < out.blocks.y(); ++b)
        for (int a = 0; a < out.blocks.x(); ++a) {
          const std::size_t at = out.block_of(a * k_block, b * k_block, c * k_block) * organs.size() + o;
          if (!out.varies[at])
            out.value[at] = static_cast<float>(
                probe(grid.world_from_index(Eigen::Vector3d(a * k_block, b * k_block, c * k_block))));
        }
  }
  throw_if_cancelled();
  return out;
}

/// Per block: whether every organ takes the same values there as in the other state, so that
/// the other state's voxels are this one's (TissuesToReuse).
std::vector<std::uint8_t> blocks_alike(const std::vector<VoxelizedOrgan>& organs, const BlockValues& values,
                                       const std::vector<VoxelizedOrgan>& other_organs,
                                       const BlockValues& other_values) {
  constexpr int none = -1;
  // The other state's organ of each organ (same label, depth and tissue), and the other way.
  std::vector<int> match(organs.size(), none), other_match(other_organs.size(), none);
  for (std::size_t o = 0; o < organs.size(); ++o)
    for (std::size_t p = 0; p < other_organs.size(); ++p)
      if (other_match[p] == none && organs[o].label == other_organs[p].label &&
          organs[o].depth == other_organs[p].depth && organs[o].tissue == other_organs[p].tissue) {
        match[o] = static_cast<int>(p);
        other_match[p] = static_cast<int>(o);
        break;
      }
  const auto block_count = static_cast<std::size_t>(values.blocks.prod());
  std::vector<std::uint8_t> alike(block_count, 1);
  for (std::size_t b = 0; b < block_count; ++b) {
    const auto outside = [](const BlockValues& v, std::size_t at) {
      return !v.varies[at] && v.value[at] > 0.0f;
    };
    bool same = true;
    for (std::size_t o = 0; o < organs.size() && same; ++o) {
      const std::size_t at = b * organs.size() + o;
      if (match[o] == none) {
        same = outside(values, at); // an organ of this state alone (a gap) must hold none of it
        continue;
      }
      const auto p = static_cast<std::size_t>(match[o]);
      const std::size_t other_at = b * other_organs.size() + p;
      same = organs[o].level_set == other_organs[p].level_set ||
             (!values.varies[at] && !other_values.varies[other_at] &&
              values.value[at] == other_values.value[other_at]);
    }
    for (std::size_t p = 0; p < other_organs.size() && same; ++p)
      if (other_match[p] == none) same = outside(other_values, b * other_organs.size() + p);
    alike[b] = same ? 1 : 0;
  }
  return alike;
}

/// The sample points of a voxel that a surface crosses: n^3 offsets in voxel units (a fastest,
/// then b, then c), each sample weighing 1 / n^3.
struct Supersampling {
  int n = 1;
  std::size_t samples = 1;
  std::vector<Eigen::Vector3d> offsets;
  double weight = 1.0;

  explicit Supersampling(int supersampling) : n(std::max(1, supersampling)) {
    samples = static_cast<std::size_t>(n) * static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
    offsets.reserve(samples);
    for (int c = 0; c < n; ++c)
      for (int b = 0; b < n; ++b)
        for (int a = 0; a < n; ++a)
          offsets.emplace_back((a + 0.5) / n - 0.5, (b + 0.5) / n - 0.5, (c + 0.5) / n - 0.5);
    weight = 1.0 / (n * n * n);
    int exponent = 0;
    exact_sums = std::frexp(weight, &exponent) == 0.5;
  }

  /// 0 plus `count` weights, added one at a time.
  double sum_of_weights(int count) const {
    if (exact_sums) return count * weight;
    double sum = 0.0;
    for (int s = 0; s < count; ++s)
      sum += weight;
    return sum;
  }

  /// The weight is a power of two (n is): every sum of weights up to 1 is then exact.
  bool exact_sums = false;
};

/// A slab's partial voxels (TissueVolumes::partial_voxels) and their fractions, as found.
struct SlabFound {
  std::vector<std::size_t> voxels;
  std::vector<float> fractions;
};

/// What voxelize_tissues() shares with every thread: the grid, the organs, their blocks' values,
/// the blocks copied from the other state, the sampling and the volumes being written.
struct TissueSampling {
  const ImageGrid& grid;
  const std::vector<VoxelizedOrgan>& organs;
  const BlockValues& blocks;
  const std::vector<std::uint8_t>& copied;
  const Supersampling& sampling;
  TissueVolumes& out;
};

/// One thread's work on the blocks of slabs: its probes of the organs' level sets and buffers.
class BlockSampler {
public:
  explicit BlockSampler(const TissueSampling& s)
      : m_s(s), m_organ_count(s.organs.size()), m_stride(s.out.fractions_per_voxel()), m_row(m_stride),
        m_centre_distance(m_organ_count), m_organ_share(m_organ_count), m_varies(m_organ_count),
        m_centres(k_block_voxels), m_centre_values(m_organ_count * k_block_voxels),
        m_points(s.sampling.samples), m_sample_inside(m_organ_count * s.sampling.samples),
        m_half_diagonal(0.5 * s.grid.spacing_mm.norm()),
        m_axes(s.grid.world_from_voxel.topLeftCorner<3, 3>()) {
    for (const VoxelizedOrgan& organ : s.organs)
      m_probes.emplace_back(*organ.level_set);
    // deepest()'s order: the deeper organ first, of two as deep the later one.
    m_priority.resize(m_organ_count);
    std::iota(m_priority.begin(), m_priority.end(), std::size_t{0});
    std::sort(m_priority.begin(), m_priority.end(), [&](std::size_t a, std::size_t b) {
      const int da = s.organs[a].depth, db = s.organs[b].depth;
      return da != db ? da > db : a > b;
    });
    m_sides.resize(m_organ_count);
    m_sample_owner.resize(s.sampling.samples);
    m_owner_count.resize(m_organ_count + 1);
    // A whole voxel's label, fractions and wholeness follow from its owner alone: each owner's
    // (none first), by write_voxel's own sums.
    m_whole.resize(m_organ_count + 1);
    for (std::size_t w = 0; w <= m_organ_count; ++w) {
      std::fill(m_organ_share.begin(), m_organ_share.end(), 0.0);
      double background = 0.0;
      (w == 0 ? background : m_organ_share[w - 1]) = 1.0;
      Whole& whole = m_whole[w];
      whole.label = label_and_row(background);
      whole.row = m_row;
      whole.whole = m_s.out.whole(whole.label, m_row.data());
    }
  }

  /// The voxels of block (ib, jb, kb): each label into the volumes, each partial voxel into `found`.
  void sample_block(int ib, int jb, int kb, SlabFound& found, std::size_t& sampled) {
    const int i0 = ib * k_block, j0 = jb * k_block, k0 = kb * k_block;
    const std::size_t block = m_s.blocks.block_of(i0, j0, k0);
    if (!m_s.copied.empty() && m_s.copied[block]) return;
    const Eigen::Vector3i& dims = m_s.grid.dims;
    const int bx = std::min(k_block, dims.x() - i0), by = std::min(k_block, dims.y() - j0),
              bz = std::min(k_block, dims.z() - k0);
    probe_centres(block, i0, j0, k0, bx, by, bz);
    std::size_t v = 0;
    for (int k = k0; k < k0 + bz; ++k)
      for (int j = j0; j < j0 + by; ++j)
        for (int i = i0; i < i0 + bx; ++i, ++v) {
          const std::size_t index = voxel_index(dims, i, j, k);
          const int owner = centre_owner(block, v);
          if (owner != k_sampled) {
            write_whole(index, m_whole[static_cast<std::size_t>(owner + 1)], found);
            continue;
          }
          ++sampled;
          write_voxel(index, sampled_shares(v), found);
        }
  }

private:
  static constexpr std::size_t k_block_voxels = k_block * k_block * k_block;

  /// Whether the points p[a + na (b + nb c)] form a lattice: x depends on a alone, y on b alone
  /// and z on c alone (a grid whose axes are the world's), bit for bit. Then the lattice's
  /// coordinates along each axis go to m_lattice, for LevelSet::Probe::lattice, which gives the
  /// same values as probing point by point.
  bool form_lattice(const Eigen::Vector3d* p, int na, int nb, int nc) {
    std::vector<double>* lattice = m_lattice;
    lattice[0].resize(static_cast<std::size_t>(na));
    lattice[1].resize(static_cast<std::size_t>(nb));
    lattice[2].resize(static_cast<std::size_t>(nc));
    for (int a = 0; a < na; ++a)
      lattice[0][static_cast<std::size_t>(a)] = p[a].x();
    for (int b = 0; b < nb; ++b)
      lattice[1][static_cast<std::size_t>(b)] = p[na * b].y();
    for (int c = 0; c < nc; ++c)
      lattice[2][static_cast<std::size_t>(c)] = p[na * nb * c].z();
    for (int c = 0; c < nc; ++c)
      for (int b = 0; b < nb; ++b)
        for (int a = 0; a < na; ++a) {
          const Eigen::Vector3d& x = *p++;
          if (!(x.x() == lattice[0][static_cast<std::size_t>(a)] &&
                x.y() == lattice[1][static_cast<std::size_t>(b)] &&
                x.z() == lattice[2][static_cast<std::size_t>(c)]))
            return false;
        }
    return true;
  }

  /// The block's voxel centres (i fastest), and the values there of each organ that varies over
  /// the block, read at all its voxel centres together.
  void probe_centres(std::size_t block, int i0, int j0, int k0, int bx, int by, int bz) {
    const auto voxels = static_cast<std::size_t>(bx * by * bz);
    std::size_t v = 0;
    for (int k = k0; k < k0 + bz; ++k)
      for (int j = j0; j < j0 + by; ++j)
        for (int i = i0; i < i0 + bx; ++i)
          m_centres[v++] = m_s.grid.world_from_index(Eigen::Vector3d(i, j, k));
    bool centres_form_lattice = false, formed = false;
    for (std::size_t o = 0; o < m_organ_count; ++o) {
      if (!m_s.blocks.varies[block * m_organ_count + o]) continue;
      if (!formed) {
        centres_form_lattice = form_lattice(m_centres.data(), bx, by, bz);
        formed = true;
      }
      float* values = &m_centre_values[o * k_block_voxels];
      if (centres_form_lattice) {
        m_probes[o].lattice(m_lattice[0].data(), bx, m_lattice[1].data(), by, m_lattice[2].data(), bz,
                            values);
      } else {
        for (std::size_t w = 0; w < voxels; ++w)
          values[w] = static_cast<float>(m_probes[o](m_centres[w]));
      }
    }
  }

  /// The deepest organ for which inside(o) holds, -1 for none.
  template <class Inside>
  int deepest(Inside&& inside) const {
    int best = -1;
    for (std::size_t o = 0; o < m_organ_count; ++o) {
      if (inside(o) && (best < 0 || m_s.organs[o].depth >= m_s.organs[static_cast<std::size_t>(best)].depth))
        best = static_cast<int>(o);
    }
    return best;
  }

  /// Voxel v of the block: each organ's value at its centre into m_centre_distance. Returns the
  /// deepest organ holding the centre (-1 for none) when the centre is farther than half a
  /// diagonal from every surface (the voxel is whole), k_sampled otherwise.
  int centre_owner(std::size_t block, std::size_t v) {
    bool decided = true;
    for (std::size_t o = 0; o < m_organ_count; ++o) {
      const std::size_t at = block * m_organ_count + o;
      m_varies[o] = m_s.blocks.varies[at];
      m_centre_distance[o] =
          static_cast<double>(m_varies[o] ? m_centre_values[o * k_block_voxels + v] : m_s.blocks.value[at]);
      if (std::abs(m_centre_distance[o]) < m_half_diagonal) decided = false;
    }
    if (!decided) return k_sampled;
    return deepest([&](std::size_t o) { return m_centre_distance[o] < 0.0; });
  }

  /// Voxel v of the block, not whole (centre_owner): each organ's share of its samples into
  /// m_organ_share; returns the background's. Each sample goes to the deepest organ holding it
  /// (deepest()), found by taking the organs deepest first: the first that holds a sample owns it.
  double sampled_shares(std::size_t v) {
    sample_voxel(m_centres[v]);
    const std::size_t samples = m_s.sampling.samples;
    constexpr int unset = -2;
    std::fill(m_sample_owner.begin(), m_sample_owner.end(), unset);
    std::size_t left = samples;
    for (const std::size_t o : m_priority) {
      if (left == 0) break;
      if (m_sides[o] == Side::outside) continue;
      if (m_sides[o] == Side::inside) {
        for (int& owner : m_sample_owner)
          if (owner == unset) owner = static_cast<int>(o);
        break;
      }
      const std::uint8_t* in = &m_sample_inside[o * samples];
      for (std::size_t s = 0; s < samples; ++s)
        if (m_sample_owner[s] == unset && in[s] != 0) {
          m_sample_owner[s] = static_cast<int>(o);
          --left;
        }
    }
    // Each share is its samples' weights added one by one: counted first, then added (the same
    // bits as adding them sample by sample).
    std::fill(m_owner_count.begin(), m_owner_count.end(), 0);
    for (const int owner : m_sample_owner)
      ++m_owner_count[owner == unset ? 0 : static_cast<std::size_t>(owner) + 1];
    for (std::size_t o = 0; o < m_organ_count; ++o)
      m_organ_share[o] = m_s.sampling.sum_of_weights(m_owner_count[o + 1]);
    return m_s.sampling.sum_of_weights(m_owner_count[0]);
  }

  /// Per organ, whether each sample of the voxel centred at `centre` lies inside it: the side of
  /// them all into m_sides, or Side::varies and each sample's into m_sample_inside.
  void sample_voxel(const Eigen::Vector3d& centre) {
    const Supersampling& sampling = m_s.sampling;
    const int n = sampling.n;
    for (std::size_t s = 0; s < sampling.samples; ++s)
      m_points[s] = centre + m_axes * sampling.offsets[s];
    const bool samples_form_lattice = form_lattice(m_points.data(), n, n, n);
    for (std::size_t o = 0; o < m_organ_count; ++o) {
      std::uint8_t* in = &m_sample_inside[o * sampling.samples];
      m_sides[o] = Side::varies;
      if (std::abs(m_centre_distance[o]) >= m_half_diagonal || !m_varies[o]) {
        // An organ far from the centre, or with one value over the block, is on the centre's
        // side at every sample.
        m_sides[o] = m_centre_distance[o] < 0.0 ? Side::inside : Side::outside;
      } else if (samples_form_lattice) {
        m_probes[o].lattice_inside(m_lattice[0].data(), n, m_lattice[1].data(), n, m_lattice[2].data(), n,
                                   in);
      } else {
        for (std::size_t s = 0; s < sampling.samples; ++s)
          in[s] = m_probes[o](m_points[s]) < 0.0 ? 1 : 0;
      }
    }
  }

  /// The label (the organ of the largest share in m_organ_share) and, into m_row, the fractions:
  /// every tissue's, then the background's.
  int label_and_row(double background) {
    int label = 0;
    double largest = background;
    double empty = background; // outside every organ, or in a gap filled with air
    std::fill(m_row.begin(), m_row.end(), 0.0f);
    for (std::size_t o = 0; o < m_organ_count; ++o) {
      if (m_s.organs[o].tissue < 0) {
        empty += m_organ_share[o];
      } else {
        m_row[static_cast<std::size_t>(m_s.organs[o].tissue)] += static_cast<float>(m_organ_share[o]);
      }
      if (m_organ_share[o] > largest) {
        largest = m_organ_share[o];
        label = m_s.organs[o].label;
      }
    }
    m_row[m_stride - 1] = static_cast<float>(empty);
    return label;
  }

  /// The voxel's label and, when it is not whole, its fractions.
  void write_voxel(std::size_t index, double background, SlabFound& found) {
    const int label = label_and_row(background);
    m_s.out.labels[index] = label;
    if (!m_s.out.whole(label, m_row.data())) {
      found.voxels.push_back(index);
      found.fractions.insert(found.fractions.end(), m_row.begin(), m_row.end());
    }
  }

  /// A voxel that one owner holds whole (centre_owner): what write_voxel writes for it.
  struct Whole {
    int label = 0;
    std::vector<float> row;
    bool whole = true;
  };
  void write_whole(std::size_t index, const Whole& w, SlabFound& found) const {
    m_s.out.labels[index] = w.label;
    if (!w.whole) {
      found.voxels.push_back(index);
      found.fractions.insert(found.fractions.end(), w.row.begin(), w.row.end());
    }
  }

  static constexpr int k_sampled = -2; ///< centre_owner: the voxel is sampled

  const TissueSampling& m_s;
  std::size_t m_organ_count, m_stride;
  std::vector<float> m_row; // a voxel's fractions: every tissue's, then the background's
  std::vector<LevelSet::Probe> m_probes;
  std::vector<double> m_centre_distance, m_organ_share;
  std::vector<std::uint8_t> m_varies;
  // A block's voxel centres (i fastest), and the varying organs' values there.
  std::vector<Eigen::Vector3d> m_centres;
  std::vector<float> m_centre_values;
  // A sampled voxel's samples, and per organ whether each lies inside.
  std::vector<Eigen::Vector3d> m_points;
  std::vector<std::uint8_t> m_sample_inside;
  std::vector<double> m_lattice[3];
  double m_half_diagonal;
  Eigen::Matrix3d m_axes;
  std::vector<Whole> m_whole;          ///< per owner (none first): a whole voxel's label and fractions
  std::vector<std::size_t> m_priority; ///< the organs in deepest()'s order
  enum class Side : std::uint8_t { outside, inside, varies };
  std::vector<Side> m_sides;       ///< per organ, a sampled voxel's samples' side (sample_voxel)
  std::vector<int> m_sample_owner; ///< per sample, the organ that holds it (sampled_shares)
  std::vector<int> m_owner_count;  ///< per owner (none first), its samples (sampled_shares)
};

/// The other state's partial voxels in slab kb's copied blocks, into `found`.
void copy_reused_partials(const TissueSampling& s, const TissueVolumes& other_volumes, int kb,
                          SlabFound& found) {
  const std::size_t stride = s.out.fractions_per_voxel();
  const int nx = s.grid.dims.x(), ny = s.grid.dims.y(), nz = s.grid.dims.z();
  const std::vector<std::size_t>& other = other_volumes.partial_voxels;
  const auto layer = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  const auto first =
      std::lower_bound(other.begin(), other.end(), static_cast<std::size_t>(kb) * k_block * layer);
  const auto last = std::lower_bound(first, other.end(),
                                     static_cast<std::size_t>(std::min(nz, (kb + 1) * k_block)) * layer);
  for (auto at = first; at != last; ++at) {
    const auto i = static_cast<int>(*at % static_cast<std::size_t>(nx));
    const auto j = static_cast<int>(*at / static_cast<std::size_t>(nx) % static_cast<std::size_t>(ny));
    if (!s.copied[s.blocks.block_of(i, j, kb * k_block)]) continue;
    found.voxels.push_back(*at);
    const float* from =
        &other_volumes.partial_fractions[static_cast<std::size_t>(at - other.begin()) * stride];
    found.fractions.insert(found.fractions.end(), from, from + stride);
  }
}

/// A slab's partial voxels as found (in block order), sorted into ascending voxel order.
SlabFound sorted_slab(const SlabFound& found, std::size_t stride, std::vector<std::size_t>& order) {
  order.resize(found.voxels.size());
  for (std::size_t p = 0; p < order.size(); ++p)
    order[p] = p;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return found.voxels[a] < found.voxels[b]; });
  SlabFound sorted;
  sorted.voxels.reserve(order.size());
  sorted.fractions.reserve(order.size() * stride);
  for (const std::size_t p : order) {
    sorted.voxels.push_back(found.voxels[p]);
    sorted.fractions.insert(sorted.fractions.end(),
                            found.fractions.begin() + static_cast<std::ptrdiff_t>(p * stride),
                            found.fractions.begin() + static_cast<std::ptrdiff_t>((p + 1) * stride));
  }
  return sorted;
}

/// Each label's tissue (TissueVolumes::label_tissues), -1 for none.
std::vector<int> label_tissues(const std::vector<VoxelizedOrgan>& organs) {
  std::vector<int> tissues(1, -1); // 0, the background, even when no organ is voxelized
  for (const VoxelizedOrgan& organ : organs) {
    const auto label = static_cast<std::size_t>(organ.label);
    if (tissues.size() <= label) tissues.resize(label + 1, -1);
    tissues[label] = organ.tissue;
  }
  return tissues;
}

} // namespace

TissueVolumes voxelize_tissues(const ImageGrid& grid, const std::vector<VoxelizedOrgan>& organs,
                               int tissue_count, int supersampling, const TissuesToReuse& reuse) {
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  const BlockValues blocks = block_values(grid, organs);
  std::vector<std::uint8_t> copied; // per block: the other state's voxels are this one's
  if (reuse.volumes && reuse.organs && reuse.volumes->labels.size() == count &&
      reuse.volumes->tissue_count == tissue_count)
    copied = blocks_alike(organs, blocks, *reuse.organs, block_values(grid, *reuse.organs));
  TissueVolumes out;
  out.tissue_count = tissue_count;
  out.label_tissues = label_tissues(organs);
  if (!copied.empty()) {
    // The other state's labels whole; the blocks that are not copied are written over below.
    out.labels = reuse.volumes->labels;
  } else {
    out.labels.assign(count, 0);
  }
  const Supersampling sampling(supersampling);
  const TissueSampling shared{grid, organs, blocks, copied, sampling, out};
  std::size_t sampled = 0;
  std::atomic<int> slabs_done{0};
  const std::size_t stride = out.fractions_per_voxel();
  // Per slab of blocks: its partial voxels, ascending, and their fractions. A slab's voxels are
  // the indices from its first voxel layer to its last, so the slabs in order give the ascending
  // list.
  const auto slab_count = static_cast<std::size_t>(blocks.blocks.z());
  std::vector<SlabFound> slabs(slab_count);
#pragma omp parallel reduction(+ : sampled)
  {
    BlockSampler sampler(shared);
    std::vector<std::size_t> order; // a slab's partial voxels in ascending order
    // The grid in blocks of k_block^3 voxels, a slab of blocks at a time: each organ that varies
    // over a block is read there once, at all its voxel centres together.
#pragma omp for schedule(dynamic, 1)
    for (int kb = 0; kb < blocks.blocks.z(); ++kb) {
      if (cancellation_requested()) continue; // no exception may leave an OpenMP region
      const int slab = slabs_done.fetch_add(1) + 1;
      if (progress_detail_due())
        progress_detail("tissue fractions, slab " + std::to_string(slab) + "/" +
                        std::to_string(blocks.blocks.z()));
      SlabFound found; // this slab's partial voxels, in block order
      for (int jb = 0; jb < blocks.blocks.y(); ++jb)
        for (int ib = 0; ib < blocks.blocks.x(); ++ib)
          sampler.sample_block(ib, jb, kb, found, sampled);
      if (!copied.empty()) copy_reused_partials(shared, *reuse.volumes, kb, found);
      slabs[static_cast<std::size_t>(kb)] = sorted_slab(found, stride, order);
    }
  }
  throw_if_cancelled();
  std::size_t partial = 0;
  for (const SlabFound& slab : slabs)
    partial += slab.voxels.size();
  out.partial_voxels.reserve(partial);
  out.partial_fractions.reserve(partial * stride);
  for (SlabFound& slab : slabs) {
    out.partial_voxels.insert(out.partial_voxels.end(), slab.voxels.begin(), slab.voxels.end());
    out.partial_fractions.insert(out.partial_fractions.end(), slab.fractions.begin(), slab.fractions.end());
    slab = SlabFound(); // freed as it is taken over
  }
  out.supersampled_voxels = sampled;
  return out;
}

} // namespace phantasm
