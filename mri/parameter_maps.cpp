#include "mri/parameter_maps.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <optional>

namespace phantasm {
namespace {

/// Whether the n floats of a and b are the same bit for bit (a handful: inline, not memcmp()).
bool same_bits(const float* a, const float* b, std::size_t n) {
  for (std::size_t t = 0; t < n; ++t) {
    std::uint32_t x, y;
    std::memcpy(&x, a + t, sizeof x);
    std::memcpy(&y, b + t, sizeof y);
    if (x != y) return false;
  }
  return true;
}

/// Fraction-weighted mean of one quantity over the tissues that have it; the sum instead when
/// `additive`. Each voxel on its own: in parallel over runs of voxels, the same values. A voxel
/// whose fractions are bit for bit those of the voxel before it (most of them: whole voxels of
/// one label side by side) takes its value without the arithmetic.
std::vector<float> mixed(const TissueVolumes& volumes, const std::vector<std::optional<double>>& values,
                         bool additive) {
  std::vector<float> map(volumes.labels.size(), 0.0f);
  const std::size_t stride = volumes.fractions_per_voxel();
  constexpr std::size_t k_run = std::size_t{1} << 16;
  const auto runs = static_cast<std::int64_t>((map.size() + k_run - 1) / k_run);
#pragma omp parallel for schedule(dynamic, 1)
  for (std::int64_t run = 0; run < runs; ++run) {
    const std::size_t first = static_cast<std::size_t>(run) * k_run;
    std::vector<float> previous(stride);
    bool have_previous = false, previous_set = false;
    float previous_value = 0.0f;
    volumes.for_each_voxel(first, std::min(map.size(), first + k_run),
                           [&](std::size_t voxel, const float* fractions) {
                             if (!have_previous || !same_bits(fractions, previous.data(), stride)) {
                               double sum = 0.0, weight = 0.0;
                               for (std::size_t t = 0; t < values.size(); ++t) {
                                 if (!values[t]) continue;
                                 sum += fractions[t] * *values[t];
                                 weight += fractions[t];
                               }
                               previous_set = weight > 0.0;
                               if (previous_set)
                                 previous_value = static_cast<float>(additive ? sum : sum / weight);
                               std::copy(fractions, fractions + stride, previous.begin());
                               have_previous = true;
                             }
                             if (previous_set) map[voxel] = previous_value;
                           });
  }
  return map;
}

} // namespace

ParameterMaps parameter_maps(const TissueVolumes& volumes, const std::vector<std::string>& tissues,
                             const std::map<std::string, TissueParameters>& parameters) {
  auto values = [&](std::optional<double> TissueParameters::*member) {
    std::vector<std::optional<double>> list;
    for (const std::string& tissue : tissues) {
      const auto found = parameters.find(tissue);
      list.push_back(found == parameters.end() ? std::nullopt : found->second.*member);
    }
    return list;
  };
  ParameterMaps maps;
  maps.PD = mixed(volumes, values(&TissueParameters::PD), true);
  maps.T1_ms = mixed(volumes, values(&TissueParameters::T1_ms), false);
  maps.T2_ms = mixed(volumes, values(&TissueParameters::T2_ms), false);
  maps.T2star_ms = mixed(volumes, values(&TissueParameters::T2star_ms), false);
  return maps;
}

} // namespace phantasm
