#include "mri/texture_signal.hpp"

#include "mri/signal_equations.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace phantasm {
namespace {

// The table covers T1 factors exp(-k_log_range) to exp(k_log_range): the largest gain (5) times
// the largest clamp of the deviation (0.9) the scene allows (scene/parse_material_maps.cpp), so
// the images never read a clamped factor where the T1 map holds the exact one; steps of 0.005 in
// log T1.
constexpr double k_log_range = 5.0 * 0.9;
constexpr int k_table_steps = 1800;

} // namespace

TexturedSignal::TexturedSignal(const SequenceSettings& sequence, const std::vector<std::string>& tissues,
                               const std::vector<Relaxation>& relaxation, double gain,
                               const TextureMaps& maps)
    : m_maps(&maps), m_table(tissues.size()) {
  for (std::size_t t = 0; t < tissues.size(); ++t) {
    if (t >= maps.textured.size() || !maps.textured[t]) continue;
    std::vector<double>& table = m_table[t];
    table.resize(k_table_steps + 1);
    for (int s = 0; s <= k_table_steps; ++s) {
      Relaxation r = relaxation[t];
      r.T1_ms *= std::exp(-k_log_range + 2.0 * k_log_range * s / k_table_steps);
      table[static_cast<std::size_t>(s)] = sequence_signal(sequence, r) * gain;
    }
  }
}

double TexturedSignal::signal(std::size_t tissue, float t1_factor, float pd_factor) const {
  const std::vector<double>& table = m_table[tissue];
  const double x =
      std::clamp((std::log(std::max(t1_factor, 1e-6f)) + k_log_range) / (2.0 * k_log_range), 0.0, 1.0) *
      k_table_steps;
  const int low = std::min(static_cast<int>(x), k_table_steps - 1);
  const double w = x - low;
  return pd_factor *
         ((1.0 - w) * table[static_cast<std::size_t>(low)] + w * table[static_cast<std::size_t>(low) + 1]);
}

std::optional<MatchedT1Gain> matched_T1_gain(const SequenceSettings& sequence, const Relaxation& tissue,
                                             double PD_gain, double max_gain) {
  constexpr double h = 1e-4;
  Relaxation longer = tissue, shorter = tissue;
  longer.T1_ms *= std::exp(h);
  shorter.T1_ms *= std::exp(-h);
  const double at = std::abs(sequence_signal(sequence, tissue));
  const double up = std::abs(sequence_signal(sequence, longer)),
               down = std::abs(sequence_signal(sequence, shorter));
  if (!(at > 0.0) || !(up > 0.0) || !(down > 0.0) || !std::isfinite(up) || !std::isfinite(down))
    return std::nullopt;
  MatchedT1Gain matched;
  matched.sensitivity = -(std::log(up) - std::log(down)) / (2.0 * h);
  const double wanted = 1.0 - PD_gain;
  if (wanted != 0.0 && std::abs(wanted) >= max_gain * std::abs(matched.sensitivity)) {
    matched.clamped = true;
    const double sign = (wanted < 0.0) != (matched.sensitivity < 0.0) ? -1.0 : 1.0;
    matched.gain = sign * max_gain;
  } else {
    matched.gain = wanted / matched.sensitivity;
  }
  return matched;
}

void apply_texture(ParameterMaps& maps, const TissueVolumes& volumes, const std::vector<std::string>& tissues,
                   const std::map<std::string, TissueParameters>& parameters, const TextureMaps& texture) {
  std::vector<std::optional<double>> T1(tissues.size()), PD(tissues.size());
  for (std::size_t t = 0; t < tissues.size(); ++t) {
    const auto found = parameters.find(tissues[t]);
    if (found == parameters.end()) continue;
    T1[t] = found->second.T1_ms;
    PD[t] = found->second.PD;
  }
  const std::size_t count = volumes.labels.size();
  constexpr std::size_t k_run = std::size_t{1} << 16;
  const auto runs = static_cast<std::int64_t>((count + k_run - 1) / k_run);
#pragma omp parallel for schedule(dynamic, 1)
  for (std::int64_t run = 0; run < runs; ++run) {
    const std::size_t first = static_cast<std::size_t>(run) * k_run;
    volumes.for_each_voxel(first, std::min(count, first + k_run), [&](std::size_t v, const float* fractions) {
      const float a = texture.T1_factor[v], b = texture.PD_factor[v];
      if (a == 1.0f && b == 1.0f) return;
      bool any = false;
      double t1_sum = 0.0, t1_weight = 0.0, pd_sum = 0.0;
      for (std::size_t t = 0; t < tissues.size(); ++t) {
        if (fractions[t] == 0.0f) continue;
        const bool textured = t < texture.textured.size() && texture.textured[t];
        any = any || textured;
        if (T1[t]) {
          t1_sum += fractions[t] * *T1[t] * (textured ? a : 1.0f);
          t1_weight += fractions[t];
        }
        if (PD[t]) pd_sum += fractions[t] * *PD[t] * (textured ? b : 1.0f);
      }
      if (!any) return;
      if (t1_weight > 0.0) maps.T1_ms[v] = static_cast<float>(t1_sum / t1_weight);
      maps.PD[v] = static_cast<float>(pd_sum);
    });
  }
}

} // namespace phantasm
