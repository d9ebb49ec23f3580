#include "atlas/colin27_head.hpp"

#include "core/error.hpp"
#include "io/nifti_file.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace phantasm {
namespace {

using Mask = std::vector<std::uint8_t>;

constexpr const char* debian_package = "mricron-data";

/// Index arithmetic on one grid.
struct Volume {
  int nx = 0, ny = 0, nz = 0;
  explicit Volume(const ImageGrid& grid) : nx(grid.dims.x()), ny(grid.dims.y()), nz(grid.dims.z()) {}
  std::int64_t size() const { return std::int64_t(nx) * ny * nz; }
  std::int64_t at(int i, int j, int k) const { return i + std::int64_t(nx) * (j + std::int64_t(ny) * k); }
};

std::filesystem::path require_template(const std::filesystem::path& folder, const std::string& name) {
  const std::filesystem::path path = folder / name;
  if (!std::filesystem::is_regular_file(path)) {
    throw InputError("colin27: template " + path.string() + " not found; it comes with the Debian package " +
                     debian_package + " (apt-get install " + debian_package +
                     ", or scripts/install-deps.sh), or pass the folder holding it");
  }
  return path;
}

/// Nearest-neighbour resampling of a source volume onto a target grid through both affines
/// (world RAS mm): the atlases do not share one voxel order, so indices are never compared.
std::vector<double> resample_nearest(const NiftiVolume& source, const ImageGrid& target) {
  const Eigen::Matrix4d source_from_target = source.grid.world_from_voxel.inverse() * target.world_from_voxel;
  const Volume dst(target);
  const Eigen::Vector3i sdims = source.grid.dims;
  std::vector<double> out(static_cast<std::size_t>(dst.size()), 0.0);
  for (int k = 0; k < dst.nz; ++k) {
    for (int j = 0; j < dst.ny; ++j) {
      for (int i = 0; i < dst.nx; ++i) {
        const Eigen::Vector4d s = source_from_target * Eigen::Vector4d(i, j, k, 1.0);
        const long si = std::lround(s.x()), sj = std::lround(s.y()), sk = std::lround(s.z());
        if (si < 0 || sj < 0 || sk < 0 || si >= sdims.x() || sj >= sdims.y() || sk >= sdims.z()) continue;
        out[static_cast<std::size_t>(dst.at(i, j, k))] =
            source.values[static_cast<std::size_t>(si + sdims.x() * (sj + std::int64_t(sdims.y()) * sk))];
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
  std::vector<double> f(longest), d(longest), z(longest + 1);
  std::vector<int> v(longest);
  const std::array<int, 3> n{vol.nx, vol.ny, vol.nz};
  const std::array<std::int64_t, 3> stride{1, vol.nx, std::int64_t(vol.nx) * vol.ny};
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
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
  std::vector<float> out(mask.size());
  for (std::size_t m = 0; m < mask.size(); ++m)
    out[m] = static_cast<float>(std::sqrt(dist[m]));
  return out;
}

/// 6-connected components of a mask, numbered 1, 2, ... in scan order (deterministic).
std::vector<std::int32_t> connected_components(const Mask& mask, const ImageGrid& grid, std::int32_t* count) {
  const Volume vol(grid);
  std::vector<std::int32_t> component(mask.size(), 0);
  std::vector<std::int64_t> stack;
  std::int32_t next = 0;
  for (std::int64_t seed = 0; seed < vol.size(); ++seed) {
    if (!mask[seed] || component[seed]) continue;
    component[seed] = ++next;
    stack.assign(1, seed);
    while (!stack.empty()) {
      const std::int64_t n = stack.back();
      stack.pop_back();
      const int i = static_cast<int>(n % vol.nx), j = static_cast<int>((n / vol.nx) % vol.ny),
                k = static_cast<int>(n / (std::int64_t(vol.nx) * vol.ny));
      const std::array<std::array<int, 3>, 6> steps{
          {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}}};
      for (const auto& s : steps) {
        const int a = i + s[0], b = j + s[1], c = k + s[2];
        if (a < 0 || b < 0 || c < 0 || a >= vol.nx || b >= vol.ny || c >= vol.nz) continue;
        const std::int64_t m = vol.at(a, b, c);
        if (mask[m] && !component[m]) {
          component[m] = next;
          stack.push_back(m);
        }
      }
    }
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

/// AAL index ranges (aal.nii.txt: "index name code").
bool aal_is(int index, int first, int last) {
  return index >= first && index <= last;
}

/// Where the thalami lie (mm): their lowest point, front and back ends, and the midline (their mean x).
struct ThalamusExtent {
  double min_z = std::numeric_limits<double>::infinity();
  double min_y = std::numeric_limits<double>::infinity();
  double max_y = -std::numeric_limits<double>::infinity();
  double midline_x = 0.0;
};

ThalamusExtent thalamus_extent(const ImageGrid& grid, const Volume& vol, const Mask& brain,
                               const std::vector<int>& aal) {
  ThalamusExtent extent;
  double x_sum = 0.0;
  std::int64_t voxels = 0;
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (!brain[n] || !aal_is(aal[n], 77, 78)) continue;
        const Eigen::Vector3d p = grid.world_from_index(Eigen::Vector3d(i, j, k));
        extent.min_z = std::min(extent.min_z, p.z());
        extent.min_y = std::min(extent.min_y, p.y());
        extent.max_y = std::max(extent.max_y, p.y());
        x_sum += p.x();
        ++voxels;
      }
  if (voxels > 0) extent.midline_x = x_sum / double(voxels);
  return extent;
}

/// Marks in `out` every run of CSF-class voxels along x, at most `fissure_max_width_mm` wide, that
/// comes within `ventricle_midline_gap_mm` of the midline: the interhemispheric fissure.
void mark_fissure(const ImageGrid& grid, const Volume& vol, const Mask& brain,
                  const std::vector<std::int8_t>& cls, double midline_x, const Colin27Options& options,
                  Mask& out) {
  const auto x_of = [&](int i, int j, int k) { return grid.world_from_index(Eigen::Vector3d(i, j, k)).x(); };
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx;) {
        const std::int64_t n = vol.at(i, j, k);
        if (!brain[n] || cls[n] != 1) {
          ++i;
          continue;
        }
        int end = i;
        double nearest = std::abs(x_of(i, j, k) - midline_x);
        while (end + 1 < vol.nx && brain[vol.at(end + 1, j, k)] && cls[vol.at(end + 1, j, k)] == 1) {
          ++end;
          nearest = std::min(nearest, std::abs(x_of(end, j, k) - midline_x));
        }
        const double width = std::abs(x_of(end, j, k) - x_of(i, j, k)) + grid.spacing_mm.x();
        if (nearest < options.ventricle_midline_gap_mm && width <= options.fissure_max_width_mm)
          for (int m = i; m <= end; ++m)
            out[static_cast<std::size_t>(vol.at(m, j, k))] = 1;
        i = end + 1;
      }
}

/// The CSF that is not a lateral ventricle however deep it lies: the third ventricle (voxels with
/// thalamus on both sides along x, each within `third_ventricle_reach_mm`) and the fourth
/// ventricle, the aqueduct and the cisterns around the brainstem and the cerebellum (voxels within
/// `ventricle_clearance_mm` of either), and the interhemispheric fissure where it leaves the
/// midline slab (a run of CSF along x, at most `fissure_max_width_mm` wide, that reaches into the
/// slab: the fissure is not straight, and beside the slab it joined the ventricles).
Mask not_lateral_ventricle(const ImageGrid& grid, const Volume& vol, const Mask& brain,
                           const std::vector<int>& aal, const std::vector<std::int8_t>& cls,
                           const Mask& brainstem, const ThalamusExtent& thalamus,
                           const Colin27Options& options) {
  const std::size_t count = static_cast<std::size_t>(vol.size());
  Mask hindbrain(count);
  for (std::size_t n = 0; n < count; ++n)
    hindbrain[n] = brainstem[n] || (brain[n] && aal_is(aal[n], 91, 116));
  const std::vector<float> from_hindbrain = distance_to(hindbrain, grid);
  Mask out(count);
  for (std::size_t n = 0; n < count; ++n)
    out[n] = from_hindbrain[n] <= options.ventricle_clearance_mm;
  const int reach = static_cast<int>(std::floor(options.third_ventricle_reach_mm / grid.spacing_mm.x()));
  // Per voxel: 1 thalamus left of the midline (x below it), 2 right of it, 0 none.
  std::vector<std::int8_t> side(count, 0);
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (!brain[n] || !aal_is(aal[n], 77, 78)) continue;
        side[n] = grid.world_from_index(Eigen::Vector3d(i, j, k)).x() < thalamus.midline_x ? 1 : 2;
      }
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (!brain[n] || side[n] != 0) continue;
        int found = 0; // bit 1: left thalamus within reach, bit 2: right
        for (int s = std::max(0, i - reach); s <= std::min(vol.nx - 1, i + reach); ++s)
          found |= side[static_cast<std::size_t>(vol.at(s, j, k))];
        if (found == 3) out[n] = 1;
      }
  mark_fissure(grid, vol, brain, cls, thalamus.midline_x, options, out);
  return out;
}

/// The lateral ventricles: per CSF component of the deep, off-midline CSF-class voxels, whether
/// it is one (the largest piece on each side of the midline, if at least the minimum volume).
/// `csf_component` receives each voxel's component (0: none).
std::vector<std::uint8_t> lateral_ventricles(const ImageGrid& grid, const Volume& vol, const Mask& brain,
                                             const std::vector<std::int8_t>& cls, const Mask& not_ventricle,
                                             double midline_x, const Colin27Options& options,
                                             std::vector<std::int32_t>& csf_component) {
  const std::size_t count = static_cast<std::size_t>(vol.size());
  // Lateral ventricles: CSF-class voxels deep inside the brain (never near the brain's outer
  // rim, where sulcal CSF is), off a thin midline slab (which cuts the interhemispheric
  // fissure's CSF from them, as the septum pellucidum does) and outside `not_ventricle` (the
  // third and fourth ventricles and the cisterns), then on each side of the midline the largest
  // connected piece, if at least the minimum volume.
  Mask not_brain(count);
  for (std::size_t n = 0; n < count; ++n)
    not_brain[n] = !brain[n];
  const std::vector<float> depth = distance_to(not_brain, grid);
  Mask deep_csf(count);
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (cls[n] != 1 || depth[n] < options.ventricle_depth_mm || not_ventricle[n]) continue;
        const double x = grid.world_from_index(Eigen::Vector3d(i, j, k)).x();
        deep_csf[n] = std::abs(x - midline_x) >= options.ventricle_midline_gap_mm;
      }
  std::int32_t csf_components = 0;
  csf_component = connected_components(deep_csf, grid, &csf_components);
  std::vector<std::int64_t> csf_size(static_cast<std::size_t>(csf_components) + 1, 0);
  std::vector<double> csf_x(static_cast<std::size_t>(csf_components) + 1, 0.0);
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int32_t c = csf_component[vol.at(i, j, k)];
        ++csf_size[c];
        csf_x[c] += grid.world_from_index(Eigen::Vector3d(i, j, k)).x();
      }
  const double voxel_ml = grid.spacing_mm.prod() / 1000.0;
  std::array<std::int32_t, 2> largest{0, 0}; // left (x < midline), right
  for (std::int32_t c = 1; c <= csf_components; ++c) {
    const int side = csf_x[c] / double(csf_size[c]) < midline_x ? 0 : 1;
    if (largest[side] == 0 || csf_size[c] > csf_size[largest[side]]) largest[side] = c;
  }
  std::vector<std::uint8_t> is_ventricle(static_cast<std::size_t>(csf_components) + 1, 0);
  for (const std::int32_t c : largest)
    if (c != 0 && double(csf_size[c]) * voxel_ml >= options.ventricle_min_volume_ml) is_ventricle[c] = 1;

  return is_ventricle;
}

/// The brainstem (see the comment inside).
Mask brainstem_mask(const ImageGrid& grid, const Volume& vol, const Mask& brain, const std::vector<int>& aal,
                    const std::vector<std::int8_t>& cls, const ThalamusExtent& thalamus,
                    const Colin27Options& options) {
  const std::size_t count = static_cast<std::size_t>(vol.size());
  // Brainstem: the unlabelled part of the brain below the thalamus near the midline. AAL
  // labels grey matter only, so its zero inside the brain is white matter or brainstem; below
  // the thalamus's lowest point, within a slab around the midline and under the thalamus from
  // front to back (extended backwards: the medulla leans back), the largest connected piece of
  // it (CSF excluded) is the brainstem. Without the front and back limits it took the frontal
  // lobe's basal white matter (up to 60 mm in front of the pons) and the cerebellum's.
  Mask stem_candidate(count);
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (!brain[n] || aal[n] != 0 || cls[n] == 1) continue;
        const Eigen::Vector3d p = grid.world_from_index(Eigen::Vector3d(i, j, k));
        stem_candidate[n] = p.z() < thalamus.min_z &&
                            std::abs(p.x() - thalamus.midline_x) <= options.brainstem_half_width_mm &&
                            p.y() <= thalamus.max_y &&
                            p.y() >= thalamus.min_y - options.brainstem_posterior_mm;
      }
  return largest_component(stem_candidate, grid);
}

/// Labels the brain's voxels: the atlas's deep nuclei (which win over the ventricles they border:
/// CSF partial volume at their edges is the atlas's call), the lateral ventricles, CSF, the
/// cerebellum (AAL's, and below the thalamus the unlabelled non-CSF voxels nearer to AAL's
/// cerebellum than to its cerebrum: the cerebellum's white matter, which AAL leaves unlabelled
/// as it does the cerebrum's; its voxels of the white-matter class are cerebellar white matter,
/// the rest its cortex), the brainstem, then white or cortical grey matter by class.
template <class IsVentricle>
void label_brain(const ImageGrid& grid, const Volume& vol, const Mask& brain, const std::vector<int>& aal,
                 const std::vector<std::int8_t>& cls, const Mask& brainstem, const ThalamusExtent& thalamus,
                 IsVentricle&& is_ventricle, std::vector<std::int32_t>& labels) {
  const std::size_t count = static_cast<std::size_t>(vol.size());
  Mask cerebellum(count), cerebrum(count);
  for (std::size_t n = 0; n < count; ++n) {
    cerebellum[n] = brain[n] && aal_is(aal[n], 91, 116);
    cerebrum[n] = brain[n] && aal_is(aal[n], 1, 90);
  }
  const std::vector<float> from_cerebellum = distance_to(cerebellum, grid);
  const std::vector<float> from_cerebrum = distance_to(cerebrum, grid);
  for (int k = 0; k < vol.nz; ++k)
    for (int j = 0; j < vol.ny; ++j)
      for (int i = 0; i < vol.nx; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (!brain[n]) continue;
        const int a = aal[n];
        // Inside the cerebellum the brain's white-matter class (step 2) is its white matter.
        const std::int32_t cerebellar = cls[n] == 3 ? colin27_cerebellar_white_matter : colin27_cerebellum;
        if (aal_is(a, 71, 72))
          labels[n] = colin27_caudate;
        else if (aal_is(a, 73, 74))
          labels[n] = colin27_putamen;
        else if (aal_is(a, 75, 76))
          labels[n] = colin27_pallidum;
        else if (aal_is(a, 77, 78))
          labels[n] = colin27_thalamus;
        else if (is_ventricle(n))
          labels[n] = colin27_ventricles;
        else if (cls[n] == 1)
          labels[n] = colin27_csf;
        else if (aal_is(a, 91, 116))
          labels[n] = cerebellar;
        else if (brainstem[n])
          labels[n] = colin27_brainstem;
        else if (a == 0 && from_cerebellum[n] < from_cerebrum[n] &&
                 grid.world_from_index(Eigen::Vector3d(i, j, k)).z() < thalamus.min_z)
          labels[n] = cerebellar;
        else
          labels[n] = cls[n] == 3 ? colin27_white_matter : colin27_cortical_gm;
      }
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

/// The eyes and the orbital fat behind them (see the comments inside); labels them in place.
void label_eyes(const ImageGrid& grid, const std::vector<int>& intensity, double white_matter_mean,
                const Colin27Options& options, std::vector<std::int32_t>& labels) {
  const Volume vol(grid);
  const std::size_t count = labels.size();
  const auto extracranial = [](std::int32_t l) {
    return l == colin27_skull || l == colin27_subcutaneous_fat || l == colin27_muscle;
  };
  const auto world = [&grid, &vol](std::int64_t n) {
    return grid.world_from_index(Eigen::Vector3d(double(n % vol.nx), double((n / vol.nx) % vol.ny),
                                                 double(n / (std::int64_t(vol.nx) * vol.ny))));
  };
  Mask in_box(count);
  for (std::int64_t n = 0; n < vol.size(); ++n) {
    const Eigen::Vector3d x = world(n);
    in_box[n] = std::abs(x.x()) >= options.orbit_abs_x_mm[0] &&
                std::abs(x.x()) <= options.orbit_abs_x_mm[1] && x.y() >= options.orbit_y_mm[0] &&
                x.y() <= options.orbit_y_mm[1] && x.z() >= options.orbit_z_mm[0] &&
                x.z() <= options.orbit_z_mm[1];
  }
  // Vitreous is darker than muscle and brighter than air and cortical bone: within the orbit box,
  // under the skin and outside the skull's cavity, the voxels of that range, opened to cut them
  // from the dark bone and muscle they touch; each side's largest piece, holes filled (the lens),
  // is its eye.
  Mask dark(count);
  for (std::size_t n = 0; n < count; ++n)
    dark[n] = in_box[n] && extracranial(labels[n]) &&
              intensity[n] >= options.vitreous_intensity_fraction[0] * white_matter_mean &&
              intensity[n] <= options.vitreous_intensity_fraction[1] * white_matter_mean;
  for (int e = 0; e < options.eye_opening_voxels; ++e)
    dark = step_mask(dark, grid, true);
  for (int e = 0; e < options.eye_opening_voxels; ++e)
    dark = step_mask(dark, grid, false);
  const double fat_level = options.fat_intensity_fraction * white_matter_mean;
  for (const double side : {-1.0, 1.0}) {
    Mask half(count);
    for (std::size_t n = 0; n < count; ++n)
      half[n] = dark[n] && in_box[n] && world(std::int64_t(n)).x() * side > 0.0;
    const Mask eye = fill_holes(largest_component(half, grid), grid);
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    std::int64_t voxels = 0;
    for (std::size_t n = 0; n < count; ++n)
      if (eye[n] && extracranial(labels[n])) {
        labels[n] = colin27_eye;
        centre += world(std::int64_t(n));
        ++voxels;
      }
    if (voxels == 0) continue;
    centre /= double(voxels);
    // Orbital fat: the fat-bright voxels behind the eye's centre, within reach of it.
    for (std::size_t n = 0; n < count; ++n)
      if (in_box[n] && extracranial(labels[n]) && intensity[n] >= fat_level &&
          world(std::int64_t(n)).y() < centre.y() &&
          (world(std::int64_t(n)) - centre).norm() <= options.orbital_fat_reach_mm)
        labels[n] = colin27_orbital_fat;
  }
}

/// Divides the tissue outside the skull (labelled scalp) into skin, subcutaneous fat and muscle,
/// takes the eyes and the orbital fat out of them and the skull (label_eyes), and divides the
/// skull into cortical bone and marrow (see the comments inside).
void label_extracranial_tissues(const ImageGrid& grid, const std::vector<int>& intensity,
                                const std::vector<float>& from_outside, double white_matter_mean,
                                double bone_level, const Colin27Options& options,
                                std::vector<std::int32_t>& labels) {
  const Volume vol(grid);
  const std::size_t count = labels.size();
  // Skin: the head's outer layer. Under it, fat is what is brighter than the brain's white matter
  // (fat's short T1 makes it the brightest tissue of a T1w head), muscle the rest; one majority
  // pass as inside the brain drops single voxels of either.
  const double fat_level = options.fat_intensity_fraction * white_matter_mean;
  Mask soft(count);
  std::vector<std::int8_t> cls(count, 0);
  for (std::size_t n = 0; n < count; ++n) {
    if (labels[n] != colin27_scalp || from_outside[n] <= options.skin_thickness_mm) continue;
    soft[n] = 1;
    cls[n] = intensity[n] >= fat_level ? 2 : 1;
  }
  for (int pass = 0; pass < options.majority_filter_passes; ++pass)
    cls = majority_filter(cls, soft, grid);
  for (std::size_t n = 0; n < count; ++n)
    if (soft[n]) labels[n] = cls[n] == 2 ? colin27_subcutaneous_fat : colin27_muscle;
  // The eyes and the orbital fat come out of the skull, fat and muscle before the marrow, which
  // stays enclosed by the bone left.
  label_eyes(grid, intensity, white_matter_mean, options, labels);
  // Marrow (diploe): skull voxels brighter than marrow_intensity_fraction times white matter
  // whose six neighbours are all skull, so that the cortical tables stay bone on both sides.
  const double marrow_level = std::max(bone_level, options.marrow_intensity_fraction * white_matter_mean);
  std::vector<std::int64_t> marrow;
  for (int k = 1; k < vol.nz - 1; ++k)
    for (int j = 1; j < vol.ny - 1; ++j)
      for (int i = 1; i < vol.nx - 1; ++i) {
        const std::int64_t n = vol.at(i, j, k);
        if (labels[n] != colin27_skull || intensity[n] < marrow_level) continue;
        bool enclosed = true;
        for (const std::int64_t m : {n - 1, n + 1, n - vol.nx, n + vol.nx, n - std::int64_t(vol.nx) * vol.ny,
                                     n + std::int64_t(vol.nx) * vol.ny})
          enclosed = enclosed && labels[m] == colin27_skull;
        if (enclosed) marrow.push_back(n);
      }
  for (const std::int64_t n : marrow)
    labels[n] = colin27_bone_marrow;
}

/// Labels the voxels outside the brain: outer CSF, skull and scalp, then the tissues inside
/// scalp and skull (see the comments inside).
void label_outside_brain(const ImageGrid& grid, const Mask& brain, const std::vector<int>& intensity,
                         double white_matter_mean, const Colin27Options& options,
                         std::vector<std::int32_t>& labels) {
  const std::size_t count = labels.size();
  // Outside the brain. Head: T1 above Otsu's threshold of the whole volume, its largest
  // piece, holes filled (dark bone and sinuses are inside the head).
  std::array<std::int64_t, 256> histogram{};
  for (std::size_t n = 0; n < count; ++n)
    ++histogram[intensity[n]];
  const int head_threshold = otsu_threshold(histogram);
  Mask head_mask(count);
  for (std::size_t n = 0; n < count; ++n)
    head_mask[n] = intensity[n] > head_threshold || brain[n];
  head_mask = fill_holes_axial(fill_holes(largest_component(head_mask, grid), grid), grid);

  // Outer CSF: the brain mask dilated by the CSF thickness. Skull: from there, at least the
  // minimum thickness, and further out every dark (bone) voxel. Scalp: the outer layer of the
  // head and every other non-bone voxel outside the skull.
  const std::vector<float> from_brain = distance_to(brain, grid);
  Mask not_head(count);
  for (std::size_t n = 0; n < count; ++n)
    not_head[n] = !head_mask[n];
  const std::vector<float> from_outside = distance_to(not_head, grid);
  const double bone_level = options.bone_intensity_fraction * head_threshold;
  for (std::size_t n = 0; n < count; ++n) {
    if (brain[n]) continue;
    const double d = from_brain[n];
    if (d <= options.outer_csf_thickness_mm) {
      labels[n] = colin27_csf;
      continue;
    }
    if (!head_mask[n]) continue;
    const bool in_scalp = from_outside[n] <= options.scalp_thickness_mm;
    const bool in_min_skull = d <= options.outer_csf_thickness_mm + options.skull_min_thickness_mm;
    if (in_min_skull && !in_scalp)
      labels[n] = colin27_skull;
    else if (!in_scalp && intensity[n] < bone_level)
      labels[n] = colin27_skull;
    else
      labels[n] = colin27_scalp;
  }
  label_extracranial_tissues(grid, intensity, from_outside, white_matter_mean, bone_level, options, labels);
}

} // namespace

std::filesystem::path default_colin27_templates_dir() {
  return "/usr/share/mricron/templates";
}

HeadLabels derive_colin27_head(const std::filesystem::path& templates_dir, const Colin27Options& options) {
  if (!std::filesystem::is_directory(templates_dir)) {
    throw InputError("colin27: templates folder " + templates_dir.string() +
                     " not found; it comes with the Debian package " + debian_package + " (apt-get install " +
                     debian_package + ", or scripts/install-deps.sh)");
  }
  const NiftiVolume t1 = read_nifti(require_template(templates_dir, "ch2.nii.gz"));
  const NiftiVolume bet = read_nifti(require_template(templates_dir, "ch2bet.nii.gz"));
  const NiftiVolume aal_file = read_nifti(require_template(templates_dir, "aal.nii.gz"));

  HeadLabels head;
  head.grid = t1.grid;
  const ImageGrid& grid = head.grid;
  const Volume vol(grid);
  const std::size_t count = static_cast<std::size_t>(vol.size());
  const std::vector<double> bet_values = resample_nearest(bet, grid);
  const std::vector<double> aal_values = resample_nearest(aal_file, grid);
  std::vector<int> aal(count);
  for (std::size_t n = 0; n < count; ++n)
    aal[n] = static_cast<int>(std::lround(aal_values[n]));
  std::vector<int> intensity(count);
  for (std::size_t n = 0; n < count; ++n)
    intensity[n] = std::clamp(static_cast<int>(std::lround(t1.values[n])), 0, 255);

  // Brain: the brain-extracted template's support, holes filled (dark ventricles stay inside).
  Mask brain(count);
  for (std::size_t n = 0; n < count; ++n)
    brain[n] = bet_values[n] > 0.0;
  brain = fill_holes(largest_component(brain, grid), grid);

  // Tissue classes inside the brain: 1 CSF, 2 GM, 3 WM (T1: CSF darkest, WM brightest).
  std::array<std::int64_t, 256> brain_histogram{};
  for (std::size_t n = 0; n < count; ++n)
    if (brain[n]) ++brain_histogram[intensity[n]];
  const std::array<double, 2> cut = three_class_thresholds(brain_histogram);
  std::vector<std::int8_t> cls(count, 0);
  for (std::size_t n = 0; n < count; ++n)
    if (brain[n])
      cls[n] = static_cast<std::int8_t>(intensity[n] < cut[0] ? 1 : (intensity[n] < cut[1] ? 2 : 3));
  for (int pass = 0; pass < options.majority_filter_passes; ++pass)
    cls = majority_filter(cls, brain, grid);

  const ThalamusExtent thalamus = thalamus_extent(grid, vol, brain, aal);
  const Mask brainstem = brainstem_mask(grid, vol, brain, aal, cls, thalamus, options);
  std::vector<std::int32_t> csf_component;
  const std::vector<std::uint8_t> is_ventricle = lateral_ventricles(
      grid, vol, brain, cls, not_lateral_ventricle(grid, vol, brain, aal, cls, brainstem, thalamus, options),
      thalamus.midline_x, options, csf_component);
  head.labels.assign(count, colin27_background);
  label_brain(
      grid, vol, brain, aal, cls, brainstem, thalamus,
      [&](std::int64_t n) { return is_ventricle[csf_component[n]] != 0; }, head.labels);
  std::vector<std::int32_t>& labels = head.labels;

  // The brain's white-matter class: the reference level of the tissues outside it.
  double white_matter_sum = 0.0;
  std::int64_t white_matter_voxels = 0;
  for (std::size_t n = 0; n < count; ++n)
    if (cls[n] == 3) {
      white_matter_sum += intensity[n];
      ++white_matter_voxels;
    }
  const double white_matter_mean =
      white_matter_voxels > 0 ? white_matter_sum / double(white_matter_voxels) : 255.0;
  label_outside_brain(grid, brain, intensity, white_matter_mean, options, labels);

  head.table = {{colin27_background, "background", ""},
                {colin27_scalp, "scalp", "skin"}, // the skin alone (the tissues under it below)
                {colin27_skull, "skull", "bone_cortical"},
                {colin27_csf, "csf", "csf"},
                {colin27_cortical_gm, "cortical_grey_matter", "gray_matter"},
                {colin27_white_matter, "white_matter", "white_matter"},
                {colin27_ventricles, "lateral_ventricles", "csf"},
                {colin27_caudate, "caudate", "gray_matter"},
                {colin27_putamen, "putamen", "gray_matter"},
                {colin27_pallidum, "pallidum", "gray_matter"},
                {colin27_thalamus, "thalamus", "gray_matter"},
                {colin27_cerebellum, "cerebellum", "gray_matter"},
                {colin27_brainstem, "brainstem", "white_matter"},
                {colin27_subcutaneous_fat, "subcutaneous_fat", "fat_subcutaneous"},
                {colin27_muscle, "muscle", "muscle_skeletal"},
                {colin27_bone_marrow, "bone_marrow", "bone_marrow"},
                {colin27_cerebellar_white_matter, "cerebellar_white_matter", "white_matter"},
                {colin27_eye, "eye", "vitreous"},
                {colin27_orbital_fat, "orbital_fat", "fat_subcutaneous"}};
  return head;
}

std::vector<double> label_volumes_ml(const HeadLabels& head) {
  std::int32_t max_label = 0;
  for (const HeadLabelInfo& info : head.table)
    max_label = std::max(max_label, info.label);
  for (const std::int32_t l : head.labels)
    max_label = std::max(max_label, l);
  std::vector<std::int64_t> counts(static_cast<std::size_t>(max_label) + 1, 0);
  for (const std::int32_t l : head.labels)
    if (l >= 0) ++counts[static_cast<std::size_t>(l)];
  const double voxel_ml = head.grid.spacing_mm.prod() / 1000.0;
  std::vector<double> volumes(counts.size());
  for (std::size_t l = 0; l < counts.size(); ++l)
    volumes[l] = double(counts[l]) * voxel_ml;
  return volumes;
}

} // namespace phantasm
