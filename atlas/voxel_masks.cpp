#include "atlas/voxel_masks.hpp"

#include "core/cancellation.hpp"
#include "io/nifti_file.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>

namespace phantasm::voxel_masks {

/// Nearest-neighbour resampling of a source volume onto a target grid through both affines
/// (world RAS mm): the atlases do not share one voxel order, so indices are never compared.
std::vector<double> resample_nearest(const ImageGrid& source, const std::vector<double>& values,
                                     const ImageGrid& target) {
  const Eigen::Matrix4d source_from_target = source.world_from_voxel.inverse() * target.world_from_voxel;
  const Volume dst(target);
  const Eigen::Vector3i sdims = source.dims;
  std::vector<double> out(static_cast<std::size_t>(dst.size()), 0.0);
  // Each voxel its own: in parallel over slices.
#pragma omp parallel for schedule(static)
  for (int k = 0; k < dst.nz; ++k) {
    for (int j = 0; j < dst.ny; ++j) {
      for (int i = 0; i < dst.nx; ++i) {
        const Eigen::Vector4d s = source_from_target * Eigen::Vector4d(i, j, k, 1.0);
        const long si = std::lround(s.x()), sj = std::lround(s.y()), sk = std::lround(s.z());
        if (si < 0 || sj < 0 || sk < 0 || si >= sdims.x() || sj >= sdims.y() || sk >= sdims.z()) continue;
        out[static_cast<std::size_t>(dst.at(i, j, k))] =
            values[static_cast<std::size_t>(si + sdims.x() * (sj + std::int64_t(sdims.y()) * sk))];
      }
    }
  }
  return out;
}

/// One-dimensional squared distance transform of sampled function f (Felzenszwalb and
/// Huttenlocher 2012, Theory of Computing 8:415), samples spacing apart.
void distance_transform_1d(const std::vector<double>& f, std::vector<double>& d, int n, double spacing,
                           std::vector<int>& v, std::vector<double>& z) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (f[q] == inf) continue;
    const double xq = q * spacing;
    while (k >= 0) {
      const double xv = v[k] * spacing;
      const double s = ((f[q] + xq * xq) - (f[v[k]] + xv * xv)) / (2.0 * (xq - xv));
      if (s <= z[k]) {
        --k;
        continue;
      }
      break;
    }
    ++k;
    v[k] = q;
    z[k] = k == 0 ? -inf
                  : ((f[q] + xq * xq) - (f[v[k - 1]] + std::pow(v[k - 1] * spacing, 2))) /
                        (2.0 * (xq - v[k - 1] * spacing));
    z[k + 1] = inf;
  }
  if (k < 0) {
    std::fill(d.begin(), d.begin() + n, inf);
    return;
  }
  int j = 0;
  for (int q = 0; q < n; ++q) {
    while (z[j + 1] < q * spacing)
      ++j;
    const double dx = (q - v[j]) * spacing;
    d[q] = dx * dx + f[v[j]];
  }
}

/// Exact Euclidean distance (mm) from every voxel to the nearest voxel of the mask (0 inside).
std::vector<float> distance_to(const Mask& mask, const ImageGrid& grid) {
  const Volume vol(grid);
  constexpr double inf = std::numeric_limits<double>::infinity();
  std::vector<double> dist(mask.size());
  for (std::size_t n = 0; n < mask.size(); ++n)
    dist[n] = mask[n] ? 0.0 : inf;
  const int longest = std::max({vol.nx, vol.ny, vol.nz});
  const std::array<int, 3> n{vol.nx, vol.ny, vol.nz};
  const std::array<std::int64_t, 3> stride{1, vol.nx, std::int64_t(vol.nx) * vol.ny};
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    // Each line along the axis on its own: in parallel over planes, the same values.
#pragma omp parallel
    {
      std::vector<double> f(longest), d(longest), z(longest + 1);
      std::vector<int> v(longest);
#pragma omp for schedule(static)
      for (int p2 = 0; p2 < n[a2]; ++p2) {
        for (int p1 = 0; p1 < n[a1]; ++p1) {
          const std::int64_t base = p1 * stride[a1] + p2 * stride[a2];
          for (int q = 0; q < n[axis]; ++q)
            f[q] = dist[static_cast<std::size_t>(base + q * stride[axis])];
          distance_transform_1d(f, d, n[axis], grid.spacing_mm[axis], v, z);
          for (int q = 0; q < n[axis]; ++q)
            dist[static_cast<std::size_t>(base + q * stride[axis])] = d[q];
        }
      }
    }
  }
  std::vector<float> out(mask.size());
  for (std::size_t m = 0; m < mask.size(); ++m)
    out[m] = static_cast<float>(std::sqrt(dist[m]));
  return out;
}

/// 6-connected components of a mask, numbered 1, 2, ... in scan order (deterministic): a
/// component's number is the rank of its first voxel in scan order among the components' first
/// voxels. Two passes over the voxels in scan order: each mask voxel takes a provisional label,
/// joined in a union-find with those of its neighbours before it (-x, -y, -z); the second pass
/// numbers each set as its first voxel comes. A flood fill from each unlabelled voxel in scan
/// order numbers them the same, with a division per voxel to find its neighbours and a jump in
/// memory per step.
std::vector<std::int32_t> connected_components(const Mask& mask, const ImageGrid& grid, std::int32_t* count) {
  const Volume vol(grid);
  std::vector<std::int32_t> component(mask.size(), 0);
  // parent[l] <= l: provisional label l's parent; 0 is unused.
  std::vector<std::int32_t> parent(1, 0);
  const auto root = [&parent](std::int32_t l) {
    while (parent[static_cast<std::size_t>(l)] != l) {
      const std::int32_t up = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(l)])];
      parent[static_cast<std::size_t>(l)] = up; // path halving
      l = up;
    }
    return l;
  };
  const auto join = [&](std::int32_t a, std::int32_t b) {
    a = root(a);
    b = root(b);
    if (a < b) parent[static_cast<std::size_t>(b)] = a;
    if (b < a) parent[static_cast<std::size_t>(a)] = b;
    return std::min(a, b);
  };
  const std::int64_t sx = 1, sy = vol.nx, sz = std::int64_t(vol.nx) * vol.ny;
  for (int k = 0; k < vol.nz; ++k) {
    throw_if_cancelled();
    for (int j = 0; j < vol.ny; ++j) {
      const std::int64_t row = vol.at(0, j, k);
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t v = row + i;
        if (!mask[static_cast<std::size_t>(v)]) continue;
        std::int32_t label = 0;
        for (const std::int64_t w : {i > 0 ? v - sx : -1, j > 0 ? v - sy : -1, k > 0 ? v - sz : -1}) {
          if (w < 0) continue;
          const std::int32_t l = component[static_cast<std::size_t>(w)];
          if (l == 0) continue;
          label = label == 0 ? root(l) : join(label, l);
        }
        if (label == 0) {
          label = static_cast<std::int32_t>(parent.size());
          parent.push_back(label);
        }
        component[static_cast<std::size_t>(v)] = label;
      }
    }
  }
  // Roots numbered in the order their first voxels come.
  std::vector<std::int32_t> number(parent.size(), 0);
  std::int32_t next = 0;
  for (std::int32_t& c : component) {
    if (c == 0) continue;
    const std::int32_t r = root(c);
    if (number[static_cast<std::size_t>(r)] == 0) number[static_cast<std::size_t>(r)] = ++next;
    c = number[static_cast<std::size_t>(r)];
  }
  *count = next;
  return component;
}

/// The mask with its holes filled: voxels not reachable from the volume's border through
/// voxels outside the mask.
Mask fill_holes(const Mask& mask, const ImageGrid& grid) {
  const Volume vol(grid);
  Mask outside(mask.size());
  for (std::size_t n = 0; n < mask.size(); ++n)
    outside[n] = !mask[n];
  std::int32_t count = 0;
  const std::vector<std::int32_t> component = connected_components(outside, grid, &count);
  std::vector<std::uint8_t> touches_border(static_cast<std::size_t>(count) + 1, 0);
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i)
        if (i == 0 || j == 0 || k == 0 || i == vol.nx - 1 || j == vol.ny - 1 || k == vol.nz - 1)
          touches_border[component[vol.at(i, j, k)]] = 1;
  Mask filled(mask.size());
  for (std::size_t n = 0; n < mask.size(); ++n)
    filled[n] = mask[n] || !touches_border[component[n]];
  return filled;
}

/// The mask with its holes filled in every axial (k) slice: 4-connected background reachable
/// from the slice's border stays background. Where the head is cut open at the neck, the dark
/// bone layer connects to the outside in 3-D, yet each axial slice through the skull shows a
/// closed ring of scalp.
Mask fill_holes_axial(const Mask& mask, const ImageGrid& grid) {
  const Volume vol(grid);
  Mask filled = mask;
  std::vector<std::uint8_t> reached(static_cast<std::size_t>(vol.nx) * vol.ny);
  std::vector<std::int64_t> stack;
  for (int k = 0; k < vol.nz; ++k) {
    std::fill(reached.begin(), reached.end(), 0);
    stack.clear();
    auto push = [&](int i, int j) {
      const std::size_t p = static_cast<std::size_t>(i + std::int64_t(vol.nx) * j);
      if (!reached[p] && !mask[vol.at(i, j, k)]) {
        reached[p] = 1;
        stack.push_back(static_cast<std::int64_t>(p));
      }
    };
    for (int i = 0; i < vol.nx; ++i) {
      push(i, 0);
      push(i, vol.ny - 1);
    }
    for (int j = 0; j < vol.ny; ++j) {
      push(0, j);
      push(vol.nx - 1, j);
    }
    while (!stack.empty()) {
      const std::int64_t p = stack.back();
      stack.pop_back();
      const int i = static_cast<int>(p % vol.nx), j = static_cast<int>(p / vol.nx);
      if (i > 0) push(i - 1, j);
      if (i < vol.nx - 1) push(i + 1, j);
      if (j > 0) push(i, j - 1);
      if (j < vol.ny - 1) push(i, j + 1);
    }
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i)
        if (!reached[static_cast<std::size_t>(i + std::int64_t(vol.nx) * j)]) filled[vol.at(i, j, k)] = 1;
  }
  return filled;
}

/// The largest 6-connected component of a mask (the first in scan order on a tie).
Mask largest_component(const Mask& mask, const ImageGrid& grid) {
  std::int32_t count = 0;
  const std::vector<std::int32_t> component = connected_components(mask, grid, &count);
  std::vector<std::int64_t> size(static_cast<std::size_t>(count) + 1, 0);
  for (const std::int32_t c : component)
    ++size[c];
  std::int32_t best = 0;
  for (std::int32_t c = 1; c <= count; ++c)
    if (size[c] > size[best] || best == 0) best = c;
  Mask out(mask.size());
  for (std::size_t n = 0; n < mask.size(); ++n)
    out[n] = count > 0 && component[n] == best;
  return out;
}

/// Otsu's threshold of a 256-bin histogram: the bin that maximises the between-class variance;
/// values at or below it form the lower class.
int otsu_threshold(const std::array<std::int64_t, 256>& histogram) {
  double total = 0.0, sum = 0.0;
  for (int b = 0; b < 256; ++b) {
    total += static_cast<double>(histogram[b]);
    sum += b * static_cast<double>(histogram[b]);
  }
  double weight_low = 0.0, sum_low = 0.0, best = -1.0;
  int threshold = 0;
  for (int b = 0; b < 255; ++b) {
    weight_low += static_cast<double>(histogram[b]);
    sum_low += b * static_cast<double>(histogram[b]);
    const double weight_high = total - weight_low;
    if (weight_low <= 0.0 || weight_high <= 0.0) continue;
    const double mean_low = sum_low / weight_low, mean_high = (sum - sum_low) / weight_high;
    const double between = weight_low * weight_high * (mean_low - mean_high) * (mean_low - mean_high);
    if (between > best) {
      best = between;
      threshold = b;
    }
  }
  return threshold;
}

/// Deterministic k-means (Lloyd) of a 256-bin histogram into three classes, started from the
/// 1/6, 3/6 and 5/6 quantiles. Returns the two thresholds between the classes (values below
/// thresholds[0] are class 0, below thresholds[1] class 1, the rest class 2).
std::array<double, 2> three_class_thresholds(const std::array<std::int64_t, 256>& histogram) {
  double total = 0.0;
  for (const std::int64_t h : histogram)
    total += static_cast<double>(h);
  std::array<double, 3> mean{};
  double cumulative = 0.0;
  int c = 0;
  for (int b = 0; b < 256 && c < 3; ++b) {
    cumulative += static_cast<double>(histogram[b]);
    while (c < 3 && cumulative >= total * (2 * c + 1) / 6.0)
      mean[c++] = b;
  }
  std::array<double, 2> cut{};
  for (int iteration = 0; iteration < 100; ++iteration) {
    cut = {0.5 * (mean[0] + mean[1]), 0.5 * (mean[1] + mean[2])};
    std::array<double, 3> weight{}, sum{};
    for (int b = 0; b < 256; ++b) {
      const int cls = b < cut[0] ? 0 : (b < cut[1] ? 1 : 2);
      weight[cls] += static_cast<double>(histogram[b]);
      sum[cls] += b * static_cast<double>(histogram[b]);
    }
    std::array<double, 3> updated = mean;
    for (int k = 0; k < 3; ++k)
      if (weight[k] > 0.0) updated[k] = sum[k] / weight[k];
    if (updated == mean) break;
    mean = updated;
  }
  return {0.5 * (mean[0] + mean[1]), 0.5 * (mean[1] + mean[2])};
}

/// One pass of a 3x3x3 majority filter over the classes 1..3 inside the mask: each voxel
/// takes the class most frequent among its in-mask neighbours (itself included), keeping its
/// own class on a tie. Reads the previous pass only, so the order of the scan does not matter.
std::vector<std::int8_t> majority_filter(const std::vector<std::int8_t>& cls, const Mask& mask,
                                         const ImageGrid& grid) {
  const Volume vol(grid);
  std::vector<std::int8_t> out = cls;
  // Each voxel from the input alone: in parallel over slices.
#pragma omp parallel for schedule(static)
  for (int k = 1; k < vol.nz - 1; ++k) {
    for (int j = 1; j < vol.ny - 1; ++j) {
      for (int i = 1; i < vol.nx - 1; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (!mask[n]) continue;
        std::array<int, 4> votes{};
        for (int c = -1; c <= 1; ++c)
          for (int b = -1; b <= 1; ++b)
            for (int a = -1; a <= 1; ++a) {
              const std::int64_t m = vol.at(i + a, j + b, k + c);
              if (mask[m]) ++votes[cls[m]];
            }
        int best = cls[n];
        for (int v = 1; v <= 3; ++v)
          if (votes[v] > votes[best]) best = v;
        out[n] = static_cast<std::int8_t>(best);
      }
    }
  }
  return out;
}

/// The mask eroded (erode) or dilated by one voxel through its six faces; the volume's border
/// counts as outside.
Mask step_mask(const Mask& mask, const ImageGrid& grid, bool erode) {
  const Volume vol(grid);
  Mask out = mask;
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (erode == !mask[n]) continue; // erosion changes inside voxels only, dilation outside ones
        const bool border =
            i == 0 || j == 0 || k == 0 || i == vol.nx - 1 || j == vol.ny - 1 || k == vol.nz - 1;
        if (border) { // outside the volume is outside the mask: erode there, never dilate
          out[n] = 0;
          continue;
        }
        bool any_other = false;
        for (const std::int64_t m : {n - 1, n + 1, n - vol.nx, n + vol.nx, n - std::int64_t(vol.nx) * vol.ny,
                                     n + std::int64_t(vol.nx) * vol.ny})
          any_other = any_other || mask[m] != mask[n];
        if (any_other) out[n] = erode ? 0 : 1;
      }
  return out;
}

std::vector<double> resample_nearest(const NiftiVolume& source, const ImageGrid& target) {
  return resample_nearest(source.grid, source.values, target);
}

} // namespace phantasm::voxel_masks
