#include "voxelize/material_maps.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <stdexcept>
#include <utility>

namespace phantasm {
namespace {

std::size_t index_of(const Eigen::Vector3i& dims, int i, int j, int k) {
  return static_cast<std::size_t>(i) +
         static_cast<std::size_t>(dims.x()) *
             (static_cast<std::size_t>(j) + static_cast<std::size_t>(dims.y()) * static_cast<std::size_t>(k));
}

/// Calls visit(voxel, world position) for every voxel of `grid`, in parallel over layers.
template <typename Visit>
void for_each_centre(const ImageGrid& grid, Visit&& visit) {
  const int nz = grid.dims.z();
#pragma omp parallel for schedule(static)
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i)
        visit(index_of(grid.dims, i, j, k), grid.world_from_index(Eigen::Vector3d(i, j, k)));
}

/// The world position of voxel `voxel` moved by the displacement stored for it (component-major).
Eigen::Vector3d displaced(const Eigen::Vector3d& world, const std::vector<float>& field, std::size_t voxel,
                          std::size_t count) {
  return world + Eigen::Vector3d(field[voxel], field[count + voxel], field[2 * count + voxel]);
}

void require_field(const ImageGrid& grid, std::size_t values, const std::vector<float>& field) {
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  if (values != count || field.size() != 3 * count)
    throw std::invalid_argument("carry: a volume or displacement field of another grid");
}

} // namespace

namespace {

/// label_at at a continuous voxel index of `source`.
std::int32_t label_at_index(const ImageGrid& source, const std::vector<std::int32_t>& labels,
                            const Eigen::Vector3d& ijk, std::int32_t outside = 0) {
  int at[3];
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(ijk[a])) return outside;
    const double rounded = std::floor(ijk[a] + 0.5);
    if (rounded < 0.0 || rounded > source.dims[a] - 1) return outside;
    at[a] = static_cast<int>(rounded);
  }
  return labels[index_of(source.dims, at[0], at[1], at[2])];
}

/// value_at at a continuous voxel index of `source`.
float value_at_index(const ImageGrid& source, const std::vector<float>& values, const Eigen::Vector3d& ijk,
                     float outside) {
  int low[3];
  double weight[3];
  for (int a = 0; a < 3; ++a) {
    const double last = source.dims[a] - 1;
    if (!std::isfinite(ijk[a]) || ijk[a] < -1e-6 || ijk[a] > last + 1e-6) return outside;
    const double x = std::clamp(ijk[a], 0.0, last);
    low[a] = std::min(static_cast<int>(std::floor(x)), std::max(0, source.dims[a] - 2));
    weight[a] = source.dims[a] > 1 ? x - low[a] : 0.0;
  }
  double sum = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    double w = 1.0;
    int at[3];
    for (int a = 0; a < 3; ++a) {
      const bool high = (corner >> a) & 1;
      w *= high ? weight[a] : 1.0 - weight[a];
      at[a] = std::min(low[a] + (high ? 1 : 0), source.dims[a] - 1);
    }
    if (w != 0.0) sum += w * values[index_of(source.dims, at[0], at[1], at[2])];
  }
  return static_cast<float>(sum);
}

} // namespace

std::int32_t label_at(const ImageGrid& source, const std::vector<std::int32_t>& labels,
                      const Eigen::Vector3d& world_mm, std::int32_t outside) {
  return label_at_index(source, labels, source.index_from_world(world_mm), outside);
}

float value_at(const ImageGrid& source, const std::vector<float>& values, const Eigen::Vector3d& world_mm,
               float outside) {
  return value_at_index(source, values, source.index_from_world(world_mm), outside);
}

// The loops below map each point through the source's inverse made once (IndexFromWorld).

std::vector<std::int32_t> resample_labels(const ImageGrid& target, const ImageGrid& source,
                                          const std::vector<std::int32_t>& labels) {
  std::vector<std::int32_t> out(static_cast<std::size_t>(target.voxel_count()));
  const IndexFromWorld index(source);
  for_each_centre(target, [&](std::size_t v, const Eigen::Vector3d& x) {
    out[v] = label_at_index(source, labels, index(x));
  });
  return out;
}

std::vector<float> resample_values(const ImageGrid& target, const ImageGrid& source,
                                   const std::vector<float>& values, float outside) {
  std::vector<float> out(static_cast<std::size_t>(target.voxel_count()));
  const IndexFromWorld index(source);
  for_each_centre(target, [&](std::size_t v, const Eigen::Vector3d& x) {
    out[v] = value_at_index(source, values, index(x), outside);
  });
  return out;
}

std::vector<std::int32_t> carry_labels(const ImageGrid& grid, const std::vector<std::int32_t>& reference,
                                       const std::vector<float>& def_to_ref) {
  require_field(grid, reference.size(), def_to_ref);
  const std::size_t count = reference.size();
  std::vector<std::int32_t> out(count);
  const IndexFromWorld index(grid);
  for_each_centre(grid, [&](std::size_t v, const Eigen::Vector3d& x) {
    out[v] = label_at_index(grid, reference, index(displaced(x, def_to_ref, v, count)));
  });
  return out;
}

std::vector<float> carry_values(const ImageGrid& grid, const std::vector<float>& reference,
                                const std::vector<float>& def_to_ref, float outside) {
  require_field(grid, reference.size(), def_to_ref);
  const std::size_t count = reference.size();
  std::vector<float> out(count);
  const IndexFromWorld index(grid);
  for_each_centre(grid, [&](std::size_t v, const Eigen::Vector3d& x) {
    out[v] = value_at_index(grid, reference, index(displaced(x, def_to_ref, v, count)), outside);
  });
  return out;
}

void widen_tissues(TissueVolumes& volumes, int tissue_count) {
  if (tissue_count < volumes.tissue_count)
    throw std::invalid_argument("widen_tissues: fewer tissues than the volumes hold");
  if (tissue_count == volumes.tissue_count) return;
  const std::size_t old_stride = volumes.fractions_per_voxel();
  const std::size_t stride = static_cast<std::size_t>(tissue_count) + 1;
  std::vector<float> widened(volumes.partial_voxels.size() * stride, 0.0f);
  for (std::size_t p = 0; p < volumes.partial_voxels.size(); ++p) {
    const float* from = &volumes.partial_fractions[p * old_stride];
    float* to = &widened[p * stride];
    std::copy(from, from + old_stride - 1, to);
    to[stride - 1] = from[old_stride - 1]; // the background, last
  }
  // A label without a tissue (-1) keeps none; the background's index moves with the count.
  volumes.partial_fractions = std::move(widened);
  volumes.tissue_count = tissue_count;
}

std::vector<std::size_t> apply_tissue_regions(TissueVolumes& volumes,
                                              const std::vector<std::int32_t>& region_volume,
                                              const std::vector<TissueRegion>& regions) {
  if (region_volume.size() != volumes.labels.size())
    throw std::invalid_argument("apply_tissue_regions: a region volume of another grid");
  std::map<std::pair<std::int32_t, std::int32_t>, std::size_t> by_organ_and_value;
  std::int32_t largest = 0;
  for (std::size_t r = 0; r < regions.size(); ++r) {
    const TissueRegion& region = regions[r];
    if (region.tissue < 0 || region.tissue >= volumes.tissue_count)
      throw std::invalid_argument("apply_tissue_regions: region " + region.name +
                                  " of a tissue the volumes lack");
    by_organ_and_value[{region.organ_label, region.region_value}] = r;
    largest = std::max(largest, region.label);
  }
  // The tissue whole voxels of each region label hold.
  if (volumes.label_tissues.size() <= static_cast<std::size_t>(largest))
    volumes.label_tissues.resize(static_cast<std::size_t>(largest) + 1, -1);
  std::vector<int> organ_tissue(regions.size());
  for (std::size_t r = 0; r < regions.size(); ++r) {
    volumes.label_tissues[static_cast<std::size_t>(regions[r].label)] = regions[r].tissue;
    const auto organ = static_cast<std::size_t>(regions[r].organ_label);
    organ_tissue[r] = organ < volumes.label_tissues.size() ? volumes.label_tissues[organ] : -1;
  }
  // The regions of each organ label (a few each): a voxel's label picks its list, its region
  // value the entry; the map itself only for an organ label below 0.
  std::vector<std::vector<std::pair<std::int32_t, std::size_t>>> of_organ;
  for (const auto& [key, r] : by_organ_and_value) {
    if (key.first < 0) continue;
    if (of_organ.size() <= static_cast<std::size_t>(key.first))
      of_organ.resize(static_cast<std::size_t>(key.first) + 1);
    of_organ[static_cast<std::size_t>(key.first)].emplace_back(key.second, r);
  }
  const auto region_of = [&](std::int32_t label, std::int32_t value) -> std::ptrdiff_t {
    if (label < 0) {
      const auto found = by_organ_and_value.find({label, value});
      return found == by_organ_and_value.end() ? -1 : static_cast<std::ptrdiff_t>(found->second);
    }
    if (static_cast<std::size_t>(label) >= of_organ.size()) return -1;
    for (const auto& [region_value, r] : of_organ[static_cast<std::size_t>(label)])
      if (region_value == value) return static_cast<std::ptrdiff_t>(r);
    return -1;
  };
  std::vector<std::size_t> relabelled(regions.size(), 0);
  const std::size_t stride = volumes.fractions_per_voxel();
  auto partial = volumes.partial_voxels.begin();
  for (std::size_t v = 0; v < volumes.labels.size(); ++v) {
    while (partial != volumes.partial_voxels.end() && *partial < v)
      ++partial;
    const std::ptrdiff_t found = region_of(volumes.labels[v], region_volume[v]);
    if (found < 0) continue;
    const auto r = static_cast<std::size_t>(found);
    volumes.labels[v] = regions[r].label;
    ++relabelled[r];
    if (partial == volumes.partial_voxels.end() || *partial != v || organ_tissue[r] < 0) continue;
    // A partial voxel: the organ tissue's share is the region tissue's.
    float* fractions =
        &volumes
             .partial_fractions[static_cast<std::size_t>(partial - volumes.partial_voxels.begin()) * stride];
    if (organ_tissue[r] == regions[r].tissue) continue;
    fractions[regions[r].tissue] += fractions[organ_tissue[r]];
    fractions[organ_tissue[r]] = 0.0f;
  }
  return relabelled;
}

std::vector<std::int32_t> held_region_values(const std::vector<std::int32_t>& reference_labels,
                                             const std::vector<std::int32_t>& region_volume,
                                             const std::vector<TissueRegion>& regions) {
  if (region_volume.size() != reference_labels.size())
    throw std::invalid_argument("held_region_values: a region volume of another grid");
  std::map<std::int32_t, std::int32_t> value_of_label;
  for (const TissueRegion& region : regions)
    value_of_label[region.label] = region.region_value;
  std::vector<std::int32_t> held(region_volume.size(), k_no_region);
  for (std::size_t v = 0; v < held.size(); ++v) {
    const auto found = value_of_label.find(reference_labels[v]);
    if (found != value_of_label.end() && region_volume[v] == found->second) held[v] = found->second;
  }
  return held;
}

namespace {

/// The texture of deviations `deviation` (one per voxel; used only where a textured tissue fills
/// the voxel's label).
TextureMaps texture_of(const TissueVolumes& volumes, const std::vector<bool>& textured,
                       const std::vector<float>& deviation, const TextureGains& gains) {
  TextureMaps maps;
  maps.textured = textured;
  maps.T1_factor.assign(volumes.labels.size(), 1.0f);
  maps.PD_factor.assign(volumes.labels.size(), 1.0f);
  for (std::size_t v = 0; v < volumes.labels.size(); ++v) {
    const int tissue = volumes.label_tissues[static_cast<std::size_t>(volumes.labels[v])];
    if (tissue < 0 || !textured[static_cast<std::size_t>(tissue)] || !std::isfinite(deviation[v])) continue;
    const double d = std::clamp(static_cast<double>(deviation[v]), -gains.max_deviation, gains.max_deviation);
    maps.T1_factor[v] = static_cast<float>(std::exp(-gains.T1_gain_of(tissue) * d));
    maps.PD_factor[v] = static_cast<float>(std::exp(gains.PD_gain * d));
  }
  return maps;
}

/// The tissue whose texture a voxel takes: its label's, when textured; -1 otherwise.
int textured_tissue(const TissueVolumes& volumes, const std::vector<bool>& textured, std::size_t v) {
  const int tissue = volumes.label_tissues[static_cast<std::size_t>(volumes.labels[v])];
  return tissue >= 0 && static_cast<std::size_t>(tissue) < textured.size() &&
                 textured[static_cast<std::size_t>(tissue)]
             ? tissue
             : -1;
}

/// One pass of a normalised Gaussian along `axis` (sigma in voxels), edges clamped.
void blur_axis(std::vector<float>& volume, const Eigen::Vector3i& dims, int axis, double sigma) {
  if (sigma <= 0.0 || dims[axis] < 2) return;
  const int radius = static_cast<int>(std::ceil(3.0 * sigma));
  std::vector<double> kernel(static_cast<std::size_t>(2 * radius + 1));
  double total = 0.0;
  for (int r = -radius; r <= radius; ++r)
    total += kernel[static_cast<std::size_t>(r + radius)] = std::exp(-0.5 * r * r / (sigma * sigma));
  for (double& w : kernel)
    w /= total;
  const int n = dims[axis];
  const int other1 = (axis + 1) % 3, other2 = (axis + 2) % 3;
  const auto lines = static_cast<std::int64_t>(dims[other1]) * dims[other2];
#pragma omp parallel for schedule(static)
  for (std::int64_t line = 0; line < lines; ++line) {
    std::vector<float> in(static_cast<std::size_t>(n));
    int at[3];
    at[other1] = static_cast<int>(line % dims[other1]);
    at[other2] = static_cast<int>(line / dims[other1]);
    for (int x = 0; x < n; ++x) {
      at[axis] = x;
      in[static_cast<std::size_t>(x)] = volume[index_of(dims, at[0], at[1], at[2])];
    }
    for (int x = 0; x < n; ++x) {
      double sum = 0.0;
      for (int r = -radius; r <= radius; ++r)
        sum += kernel[static_cast<std::size_t>(r + radius)] *
               in[static_cast<std::size_t>(std::clamp(x + r, 0, n - 1))];
      at[axis] = x;
      volume[index_of(dims, at[0], at[1], at[2])] = static_cast<float>(sum);
    }
  }
}

} // namespace

TextureMaps texture_from_intensity(const TissueVolumes& volumes, const std::vector<bool>& textured,
                                   const std::vector<float>& intensity, const TextureGains& gains) {
  if (intensity.size() != volumes.labels.size())
    throw std::invalid_argument("texture_from_intensity: an intensity volume of another grid");
  std::vector<double> sum(textured.size(), 0.0);
  std::vector<std::size_t> count(textured.size(), 0);
  for (std::size_t v = 0; v < volumes.labels.size(); ++v) {
    const int tissue = textured_tissue(volumes, textured, v);
    if (tissue < 0 || !std::isfinite(intensity[v])) continue;
    sum[static_cast<std::size_t>(tissue)] += intensity[v];
    ++count[static_cast<std::size_t>(tissue)];
  }
  std::vector<float> deviation(volumes.labels.size(), 0.0f);
  for (std::size_t v = 0; v < volumes.labels.size(); ++v) {
    const int tissue = textured_tissue(volumes, textured, v);
    if (tissue < 0) continue;
    const double mean = sum[static_cast<std::size_t>(tissue)] /
                        std::max<std::size_t>(1, count[static_cast<std::size_t>(tissue)]);
    deviation[v] = mean > 0.0 ? static_cast<float>(intensity[v] / mean - 1.0) : 0.0f;
  }
  return texture_of(volumes, textured, deviation, gains);
}

TextureMaps texture_from_random_field(const ImageGrid& grid, const TissueVolumes& volumes,
                                      const std::vector<bool>& textured, std::uint64_t seed,
                                      double correlation_mm, double deviation_sd, const TextureGains& gains) {
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  if (volumes.labels.size() != count)
    throw std::invalid_argument("texture_from_random_field: volumes of another grid");
  std::vector<float> field(count);
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (float& value : field)
    value = static_cast<float>(normal(random));
  for (int axis = 0; axis < 3; ++axis)
    blur_axis(field, grid.dims, axis, correlation_mm / grid.spacing_mm[axis]);
  double sum = 0.0, squares = 0.0;
  std::size_t n = 0;
  for (std::size_t v = 0; v < count; ++v) {
    if (textured_tissue(volumes, textured, v) < 0) continue;
    sum += field[v];
    squares += static_cast<double>(field[v]) * field[v];
    ++n;
  }
  const double mean = n ? sum / n : 0.0;
  const double sd = n ? std::sqrt(std::max(0.0, squares / n - mean * mean)) : 0.0;
  for (float& value : field)
    value = sd > 0.0 ? static_cast<float>((value - mean) / sd * deviation_sd) : 0.0f;
  return texture_of(volumes, textured, field, gains);
}

TextureMaps texture_from_random_fields(const ImageGrid& grid, const TissueVolumes& volumes,
                                       const std::vector<bool>& textured, std::uint64_t seed,
                                       const std::vector<TextureField>& fields, const TextureGains& gains) {
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  if (volumes.labels.size() != count)
    throw std::invalid_argument("texture_from_random_fields: volumes of another grid");
  const std::size_t tissues = textured.size();
  if (fields.size() < tissues)
    throw std::invalid_argument("texture_from_random_fields: a field per tissue expected");
  // The box of each textured tissue's voxels.
  std::vector<Eigen::Vector3i> low(tissues, grid.dims), high(tissues, Eigen::Vector3i::Constant(-1));
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const int tissue = textured_tissue(volumes, textured, index_of(grid.dims, i, j, k));
        if (tissue < 0) continue;
        const auto t = static_cast<std::size_t>(tissue);
        low[t] = low[t].cwiseMin(Eigen::Vector3i(i, j, k));
        high[t] = high[t].cwiseMax(Eigen::Vector3i(i, j, k));
      }
  std::vector<float> deviation(count, 0.0f);
  for (std::size_t t = 0; t < tissues; ++t) {
    if (!textured[t] || high[t].x() < 0) continue;
    const TextureField& figures = fields[t];
    Eigen::Vector3i from, dims;
    for (int a = 0; a < 3; ++a) {
      const int margin = static_cast<int>(std::ceil(3.0 * figures.correlation_mm / grid.spacing_mm[a])) + 1;
      from[a] = low[t][a] - margin; // beyond the grid too: no edge within the smoothing's reach
      dims[a] = high[t][a] + margin - from[a] + 1;
    }
    // One generator per tissue: its seed mixes the run's with the tissue's index (splitmix64).
    std::uint64_t mixed = seed + 0x9E3779B97F4A7C15ull * (static_cast<std::uint64_t>(t) + 1);
    mixed = (mixed ^ (mixed >> 30)) * 0xBF58476D1CE4E5B9ull;
    mixed = (mixed ^ (mixed >> 27)) * 0x94D049BB133111EBull;
    std::mt19937_64 random(mixed ^ (mixed >> 31));
    std::normal_distribution<double> normal(0.0, 1.0);
    std::vector<float> field(static_cast<std::size_t>(dims.x()) * static_cast<std::size_t>(dims.y()) *
                             static_cast<std::size_t>(dims.z()));
    for (float& value : field)
      value = static_cast<float>(normal(random));
    for (int axis = 0; axis < 3; ++axis)
      blur_axis(field, dims, axis, figures.correlation_mm / grid.spacing_mm[axis]);
    double sum = 0.0, squares = 0.0;
    std::size_t n = 0;
    auto for_tissue_voxels = [&](auto&& visit) {
      for (int k = 0; k < dims.z(); ++k)
        for (int j = 0; j < dims.y(); ++j)
          for (int i = 0; i < dims.x(); ++i) {
            const Eigen::Vector3i at = from + Eigen::Vector3i(i, j, k);
            if ((at.array() < 0).any() || (at.array() >= grid.dims.array()).any()) continue;
            const std::size_t v = index_of(grid.dims, at.x(), at.y(), at.z());
            if (textured_tissue(volumes, textured, v) == static_cast<int>(t))
              visit(v, field[index_of(dims, i, j, k)]);
          }
    };
    for_tissue_voxels([&](std::size_t, float value) {
      sum += value;
      squares += static_cast<double>(value) * value;
      ++n;
    });
    const double mean = sum / static_cast<double>(n);
    const double sd = std::sqrt(std::max(0.0, squares / static_cast<double>(n) - mean * mean));
    for_tissue_voxels([&](std::size_t v, float value) {
      deviation[v] = sd > 0.0 ? static_cast<float>((value - mean) / sd * figures.deviation_sd) : 0.0f;
    });
  }
  return texture_of(volumes, textured, deviation, gains);
}

TextureMaps carry_texture(const ImageGrid& grid, const TextureMaps& reference,
                          const std::vector<float>& def_to_ref) {
  TextureMaps out;
  out.textured = reference.textured;
  out.description = reference.description;
  out.T1_factor = carry_values(grid, reference.T1_factor, def_to_ref, 1.0f);
  out.PD_factor = carry_values(grid, reference.PD_factor, def_to_ref, 1.0f);
  return out;
}

} // namespace phantasm
