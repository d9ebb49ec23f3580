#include "voxelize/tissue_volumes.hpp"

#include "core/cancellation.hpp"
#include "core/progress.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
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
  out.label_tissues.assign(1, -1); // 0, the background, even when no organ is voxelized
  for (const VoxelizedOrgan& organ : organs) {
    const auto label = static_cast<std::size_t>(organ.label);
    if (out.label_tissues.size() <= label) out.label_tissues.resize(label + 1, -1);
    out.label_tissues[label] = organ.tissue;
  }
  if (!copied.empty()) {
    // The other state's labels whole; the blocks that are not copied are written over below.
    out.labels = reuse.volumes->labels;
  } else {
    out.labels.assign(count, 0);
  }
  const int n = std::max(1, supersampling);
  const auto samples =
      static_cast<std::size_t>(n) * static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
  std::vector<Eigen::Vector3d> offsets; // a fastest, then b, then c
  offsets.reserve(samples);
  for (int c = 0; c < n; ++c)
    for (int b = 0; b < n; ++b)
      for (int a = 0; a < n; ++a)
        offsets.emplace_back((a + 0.5) / n - 0.5, (b + 0.5) / n - 0.5, (c + 0.5) / n - 0.5);
  const double half_diagonal = 0.5 * grid.spacing_mm.norm();
  const Eigen::Matrix3d axes = grid.world_from_voxel.topLeftCorner<3, 3>();
  const double weight = 1.0 / (n * n * n);
  std::size_t sampled = 0;
  std::atomic<int> slabs_done{0};
  const int nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  constexpr std::size_t block_voxels = k_block * k_block * k_block;
  const std::size_t organ_count = organs.size();
  const std::size_t stride = out.fractions_per_voxel();
  // Per slab of blocks: its partial voxels (TissueVolumes::partial_voxels), ascending, and their
  // fractions. A slab's voxels are the indices from its first voxel layer to its last, so the
  // slabs in order give the ascending list.
  const auto slab_count = static_cast<std::size_t>(blocks.blocks.z());
  std::vector<std::vector<std::size_t>> slab_voxels(slab_count);
  std::vector<std::vector<float>> slab_fractions(slab_count);
#pragma omp parallel reduction(+ : sampled)
  {
    std::vector<float> row(stride); // a voxel's fractions: every tissue's, then the background's
    std::vector<std::size_t> order; // a slab's partial voxels in ascending order
    std::vector<LevelSet::Probe> probes;
    for (const VoxelizedOrgan& organ : organs)
      probes.emplace_back(*organ.level_set);
    std::vector<double> centre_distance(organ_count);
    std::vector<double> organ_share(organ_count);
    std::vector<std::uint8_t> varies(organ_count);
    // A block's voxel centres (i fastest), and the varying organs' values there.
    std::vector<Eigen::Vector3d> centres(block_voxels);
    std::vector<float> centre_values(organ_count * block_voxels);
    // A sampled voxel's samples, and per organ whether each lies inside.
    std::vector<Eigen::Vector3d> points(samples);
    std::vector<std::uint8_t> sample_inside(organ_count * samples);
    std::vector<double> lattice[3];
    // Whether the points p[a + na (b + nb c)] form a lattice: x depends on a alone, y on b alone
    // and z on c alone (a grid whose axes are the world's), bit for bit. Then the lattice's
    // coordinates along each axis go to `lattice`, for LevelSet::Probe::lattice, which gives
    // the same values as probing point by point.
    const auto form_lattice = [&lattice](const Eigen::Vector3d* p, int na, int nb, int nc) {
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
    };
    // The grid in blocks of k_block^3 voxels, a slab of blocks at a time: each organ that varies
    // over a block is read there once, at all its voxel centres together.
#pragma omp for schedule(dynamic, 1)
    for (int kb = 0; kb < blocks.blocks.z(); ++kb) {
      if (cancellation_requested()) continue; // no exception may leave an OpenMP region
      const int slab = slabs_done.fetch_add(1) + 1;
      if (progress_detail_due())
        progress_detail("tissue fractions, slab " + std::to_string(slab) + "/" +
                        std::to_string(blocks.blocks.z()));
      std::vector<std::size_t> voxels_found; // this slab's partial voxels, in block order
      std::vector<float> fractions_found;
      for (int jb = 0; jb < blocks.blocks.y(); ++jb) {
        for (int ib = 0; ib < blocks.blocks.x(); ++ib) {
          const int i0 = ib * k_block, j0 = jb * k_block, k0 = kb * k_block;
          const std::size_t block = blocks.block_of(i0, j0, k0);
          if (!copied.empty() && copied[block]) continue;
          const int bx = std::min(k_block, nx - i0), by = std::min(k_block, ny - j0),
                    bz = std::min(k_block, nz - k0);
          const auto voxels = static_cast<std::size_t>(bx * by * bz);
          std::size_t v = 0;
          for (int k = k0; k < k0 + bz; ++k)
            for (int j = j0; j < j0 + by; ++j)
              for (int i = i0; i < i0 + bx; ++i)
                centres[v++] = grid.world_from_index(Eigen::Vector3d(i, j, k));
          bool centres_form_lattice = false, formed = false;
          for (std::size_t o = 0; o < organ_count; ++o) {
            if (!blocks.varies[block * organ_count + o]) continue;
            if (!formed) {
              centres_form_lattice = form_lattice(centres.data(), bx, by, bz);
              formed = true;
            }
            float* values = &centre_values[o * block_voxels];
            if (centres_form_lattice) {
              probes[o].lattice(lattice[0].data(), bx, lattice[1].data(), by, lattice[2].data(), bz, values);
            } else {
              for (std::size_t w = 0; w < voxels; ++w)
                values[w] = static_cast<float>(probes[o](centres[w]));
            }
          }
          v = 0;
          for (int k = k0; k < k0 + bz; ++k) {
            for (int j = j0; j < j0 + by; ++j) {
              for (int i = i0; i < i0 + bx; ++i, ++v) {
                const std::size_t index = voxel_index(grid.dims, i, j, k);
                const Eigen::Vector3d& centre = centres[v];
                bool decided = true;
                for (std::size_t o = 0; o < organ_count; ++o) {
                  const std::size_t at = block * organ_count + o;
                  varies[o] = blocks.varies[at];
                  centre_distance[o] =
                      static_cast<double>(varies[o] ? centre_values[o * block_voxels + v] : blocks.value[at]);
                  if (std::abs(centre_distance[o]) < half_diagonal) decided = false;
                }
                auto deepest = [&](auto&& inside) {
                  int best = -1;
                  for (std::size_t o = 0; o < organ_count; ++o) {
                    if (inside(o) &&
                        (best < 0 || organs[o].depth >= organs[static_cast<std::size_t>(best)].depth))
                      best = static_cast<int>(o);
                  }
                  return best;
                };
                std::fill(organ_share.begin(), organ_share.end(), 0.0);
                double background = 0.0;
                if (decided) {
                  const int owner = deepest([&](std::size_t o) { return centre_distance[o] < 0.0; });
                  (owner < 0 ? background : organ_share[static_cast<std::size_t>(owner)]) = 1.0;
                } else {
                  ++sampled;
                  for (std::size_t s = 0; s < samples; ++s)
                    points[s] = centre + axes * offsets[s];
                  const bool samples_form_lattice = form_lattice(points.data(), n, n, n);
                  for (std::size_t o = 0; o < organ_count; ++o) {
                    std::uint8_t* in = &sample_inside[o * samples];
                    if (std::abs(centre_distance[o]) >= half_diagonal || !varies[o]) {
                      // An organ far from the centre, or with one value over the block, is on
                      // the centre's side at every sample.
                      std::fill(in, in + samples,
                                static_cast<std::uint8_t>(centre_distance[o] < 0.0 ? 1 : 0));
                    } else if (samples_form_lattice) {
                      probes[o].lattice_inside(lattice[0].data(), n, lattice[1].data(), n, lattice[2].data(),
                                               n, in);
                    } else {
                      for (std::size_t s = 0; s < samples; ++s)
                        in[s] = probes[o](points[s]) < 0.0 ? 1 : 0;
                    }
                  }
                  for (std::size_t s = 0; s < samples; ++s) {
                    const int owner =
                        deepest([&](std::size_t o) { return sample_inside[o * samples + s] != 0; });
                    (owner < 0 ? background : organ_share[static_cast<std::size_t>(owner)]) += weight;
                  }
                }
                int label = 0;
                double largest = background;
                double empty = background; // outside every organ, or in a gap filled with air
                std::fill(row.begin(), row.end(), 0.0f);
                for (std::size_t o = 0; o < organ_count; ++o) {
                  if (organs[o].tissue < 0) {
                    empty += organ_share[o];
                  } else {
                    row[static_cast<std::size_t>(organs[o].tissue)] += static_cast<float>(organ_share[o]);
                  }
                  if (organ_share[o] > largest) {
                    largest = organ_share[o];
                    label = organs[o].label;
                  }
                }
                row[stride - 1] = static_cast<float>(empty);
                out.labels[index] = label;
                if (!out.whole(label, row.data())) {
                  voxels_found.push_back(index);
                  fractions_found.insert(fractions_found.end(), row.begin(), row.end());
                }
              }
            }
          }
        }
      }
      if (!copied.empty()) {
        // The other state's partial voxels in this slab's copied blocks.
        const std::vector<std::size_t>& other = reuse.volumes->partial_voxels;
        const auto layer = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
        const auto first =
            std::lower_bound(other.begin(), other.end(), static_cast<std::size_t>(kb) * k_block * layer);
        const auto last = std::lower_bound(
            first, other.end(), static_cast<std::size_t>(std::min(nz, (kb + 1) * k_block)) * layer);
        for (auto at = first; at != last; ++at) {
          const auto i = static_cast<int>(*at % static_cast<std::size_t>(nx));
          const auto j = static_cast<int>(*at / static_cast<std::size_t>(nx) % static_cast<std::size_t>(ny));
          if (!copied[blocks.block_of(i, j, kb * k_block)]) continue;
          voxels_found.push_back(*at);
          const float* from =
              &reuse.volumes->partial_fractions[static_cast<std::size_t>(at - other.begin()) * stride];
          fractions_found.insert(fractions_found.end(), from, from + stride);
        }
      }
      order.resize(voxels_found.size());
      for (std::size_t p = 0; p < order.size(); ++p)
        order[p] = p;
      std::sort(order.begin(), order.end(),
                [&](std::size_t a, std::size_t b) { return voxels_found[a] < voxels_found[b]; });
      std::vector<std::size_t>& voxels = slab_voxels[static_cast<std::size_t>(kb)];
      std::vector<float>& fractions = slab_fractions[static_cast<std::size_t>(kb)];
      voxels.reserve(order.size());
      fractions.reserve(order.size() * stride);
      for (const std::size_t p : order) {
        voxels.push_back(voxels_found[p]);
        fractions.insert(fractions.end(), fractions_found.begin() + static_cast<std::ptrdiff_t>(p * stride),
                         fractions_found.begin() + static_cast<std::ptrdiff_t>((p + 1) * stride));
      }
    }
  }
  throw_if_cancelled();
  std::size_t partial = 0;
  for (const std::vector<std::size_t>& voxels : slab_voxels)
    partial += voxels.size();
  out.partial_voxels.reserve(partial);
  out.partial_fractions.reserve(partial * stride);
  for (std::size_t slab = 0; slab < slab_count; ++slab) {
    out.partial_voxels.insert(out.partial_voxels.end(), slab_voxels[slab].begin(), slab_voxels[slab].end());
    out.partial_fractions.insert(out.partial_fractions.end(), slab_fractions[slab].begin(),
                                 slab_fractions[slab].end());
    slab_voxels[slab] = std::vector<std::size_t>(); // freed as it is taken over
    slab_fractions[slab] = std::vector<float>();
  }
  out.supersampled_voxels = sampled;
  return out;
}

} // namespace phantasm
