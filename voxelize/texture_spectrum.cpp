#include "voxelize/texture_spectrum.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace phantasm {
namespace {

/// The largest s the fit reports (a correlation that does not fall over the fitted lags).
constexpr double k_max_correlation_mm = 50.0;

/// Fits rho(r) = a exp(-r^2 / (4 s^2)) to points (r^2, log rho): weighted least squares on log rho =
/// log a - r^2 / (4 s^2), weights rho^2 (so that an error of rho counts alike at every lag, as a
/// fit of rho itself would: the small correlations of the far lags are the noisiest in log), a
/// capped at 1 (then refitted through log a = 0).
void fit(const std::vector<double>& r2, const std::vector<double>& log_rho, TextureSpectrum& out) {
  out.lags_fitted = static_cast<int>(r2.size());
  if (r2.empty()) {
    out.amplitude = 0.0;
    out.correlation_mm = 0.0;
    return;
  }
  double sw = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  for (std::size_t p = 0; p < r2.size(); ++p) {
    const double w = std::exp(2.0 * log_rho[p]);
    sw += w;
    sx += w * r2[p];
    sy += w * log_rho[p];
    sxx += w * r2[p] * r2[p];
    sxy += w * r2[p] * log_rho[p];
  }
  double slope = 0.0, intercept = 0.0;
  const double spread = sw * sxx - sx * sx;
  const bool two = r2.size() >= 2 && spread > 1e-9 * sw * sxx;
  if (two) {
    slope = (sw * sxy - sx * sy) / spread;
    intercept = (sy - slope * sx) / sw;
  }
  if (!two || intercept > 0.0) {
    intercept = 0.0; // amplitude 1: through the origin
    slope = sxx > 0.0 ? sxy / sxx : 0.0;
  }
  out.amplitude = std::exp(intercept);
  out.correlation_mm =
      slope < 0.0 ? std::min(k_max_correlation_mm, std::sqrt(-1.0 / (4.0 * slope))) : k_max_correlation_mm;
}

/// The regions eroded by the 6-connected element (a voxel stays if its six neighbours inside the
/// grid are of its region: the grid's edge is no border), each region as deep as up to `steps`
/// erosions leave it at least `min_voxels` voxels and `min_share` of its own.
std::vector<int> eroded_regions(const Eigen::Vector3i& dims, const std::vector<int>& region, int region_count,
                                int steps, std::size_t min_voxels, double min_share) {
  // depth[v]: the erosions voxel v survives, up to steps.
  std::vector<int> depth(region.size(), 0);
  std::vector<int> eroded = region;
  std::vector<int> next;
  for (int step = 0; step < steps; ++step) {
    next = eroded;
    for (int k = 0; k < dims.z(); ++k)
      for (int j = 0; j < dims.y(); ++j)
        for (int i = 0; i < dims.x(); ++i) {
          const std::size_t v = voxel_index(dims, i, j, k);
          const int r = eroded[v];
          if (r < 0) continue;
          const int at[3] = {i, j, k};
          for (int axis = 0; axis < 3 && next[v] >= 0; ++axis)
            for (int side = -1; side <= 1; side += 2) {
              Eigen::Vector3i n(i, j, k);
              n[axis] = at[axis] + side;
              if (n[axis] >= 0 && n[axis] < dims[axis] &&
                  eroded[voxel_index(dims, n.x(), n.y(), n.z())] != r) {
                next[v] = -1;
                break;
              }
            }
          if (next[v] >= 0) depth[v] = step + 1;
        }
    eroded.swap(next);
  }
  const auto regions = static_cast<std::size_t>(std::max(0, region_count));
  const auto levels = static_cast<std::size_t>(steps) + 1;
  std::vector<std::size_t> at_least(regions * levels, 0); // voxels of depth >= level
  for (std::size_t v = 0; v < region.size(); ++v) {
    const int r = region[v];
    if (r < 0 || r >= region_count) continue;
    for (int level = 0; level <= depth[v]; ++level)
      ++at_least[static_cast<std::size_t>(r) * levels + static_cast<std::size_t>(level)];
  }
  std::vector<int> chosen(regions, 0);
  for (std::size_t r = 0; r < regions; ++r) {
    const std::size_t whole = at_least[r * levels];
    for (std::size_t level = 1; level < levels; ++level) {
      const std::size_t kept = at_least[r * levels + level];
      if (kept < min_voxels || static_cast<double>(kept) < min_share * static_cast<double>(whole)) break;
      chosen[r] = static_cast<int>(level);
    }
  }
  std::vector<int> measured(region.size(), -1);
  for (std::size_t v = 0; v < region.size(); ++v) {
    const int r = region[v];
    if (r >= 0 && r < region_count && depth[v] >= chosen[static_cast<std::size_t>(r)]) measured[v] = r;
  }
  return measured;
}

} // namespace

std::vector<TextureSpectrum> measure_texture_spectra(const ImageGrid& grid,
                                                     const std::vector<float>& intensity,
                                                     const std::vector<int>& region, int region_count,
                                                     const TextureSpectrumOptions& options) {
  const auto count = static_cast<std::size_t>(grid.voxel_count());
  if (intensity.size() != count || region.size() != count)
    throw std::invalid_argument("measure_texture_spectra: volumes of another grid");
  const auto regions = static_cast<std::size_t>(std::max(0, region_count));
  std::vector<TextureSpectrum> out(regions);
  const std::vector<int> measured =
      eroded_regions(grid.dims, region, region_count, std::max(0, options.erode_voxels), options.min_pairs,
                     options.min_eroded_share);
  auto region_of = [&](std::size_t v) -> int {
    const int r = measured[v];
    return r >= 0 && r < region_count && std::isfinite(intensity[v]) ? r : -1;
  };

  // The mean intensity, then d (clamped) and its mean and variance, per region.
  std::vector<double> sum(regions, 0.0);
  for (std::size_t v = 0; v < count; ++v) {
    const int r = region_of(v);
    if (r < 0) continue;
    sum[static_cast<std::size_t>(r)] += intensity[v];
    ++out[static_cast<std::size_t>(r)].voxels;
  }
  for (std::size_t r = 0; r < regions; ++r)
    out[r].mean = out[r].voxels ? sum[r] / static_cast<double>(out[r].voxels) : 0.0;
  std::vector<float> d(count, 0.0f);
  std::vector<double> d_sum(regions, 0.0), d_squares(regions, 0.0);
  for (std::size_t v = 0; v < count; ++v) {
    const int r = region_of(v);
    if (r < 0) continue;
    const double mean = out[static_cast<std::size_t>(r)].mean;
    const double value =
        mean != 0.0 ? std::clamp(intensity[v] / mean - 1.0, -options.max_deviation, options.max_deviation)
                    : 0.0;
    d[v] = static_cast<float>(value);
    d_sum[static_cast<std::size_t>(r)] += value;
    d_squares[static_cast<std::size_t>(r)] += value * value;
  }
  std::vector<double> d_mean(regions, 0.0), variance(regions, 0.0);
  for (std::size_t r = 0; r < regions; ++r) {
    if (!out[r].voxels) continue;
    const auto n = static_cast<double>(out[r].voxels);
    d_mean[r] = d_sum[r] / n;
    variance[r] = std::max(0.0, d_squares[r] / n - d_mean[r] * d_mean[r]);
    out[r].deviation_sd = std::sqrt(variance[r]);
  }

  // Sums of products at each lag along each axis, over pairs of voxels both in the region.
  const int lags = std::max(1, options.max_lag);
  const std::size_t per_region = 3 * static_cast<std::size_t>(lags);
  std::vector<double> products(regions * per_region, 0.0);
  std::vector<std::size_t> pairs(regions * per_region, 0);
  const Eigen::Vector3i& dims = grid.dims;
  const std::size_t stride[3] = {1, static_cast<std::size_t>(dims.x()),
                                 static_cast<std::size_t>(dims.x()) * static_cast<std::size_t>(dims.y())};
  for (int k = 0; k < dims.z(); ++k)
    for (int j = 0; j < dims.y(); ++j)
      for (int i = 0; i < dims.x(); ++i) {
        const std::size_t v = voxel_index(dims, i, j, k);
        const int r = region_of(v);
        if (r < 0) continue;
        const double a = d[v] - d_mean[static_cast<std::size_t>(r)];
        const int at[3] = {i, j, k};
        for (int axis = 0; axis < 3; ++axis) {
          const int room = std::min(lags, dims[axis] - 1 - at[axis]);
          const std::size_t base =
              static_cast<std::size_t>(r) * per_region + static_cast<std::size_t>(axis * lags);
          for (int lag = 1; lag <= room; ++lag) {
            const std::size_t w = v + static_cast<std::size_t>(lag) * stride[axis];
            if (region_of(w) != r) continue;
            products[base + static_cast<std::size_t>(lag - 1)] +=
                a * (d[w] - d_mean[static_cast<std::size_t>(r)]);
            ++pairs[base + static_cast<std::size_t>(lag - 1)];
          }
        }
      }

  for (std::size_t r = 0; r < regions; ++r) {
    TextureSpectrum& s = out[r];
    std::vector<double> r2, log_rho;
    for (int axis = 0; axis < 3; ++axis) {
      s.autocorrelation[axis].assign(static_cast<std::size_t>(lags), std::nan(""));
      bool fitting = true;
      for (int lag = 1; lag <= lags; ++lag) {
        const std::size_t at = r * per_region + static_cast<std::size_t>(axis * lags + lag - 1);
        if (pairs[at] < options.min_pairs || variance[r] <= 0.0) {
          fitting = false;
          continue;
        }
        const double rho = products[at] / static_cast<double>(pairs[at]) / variance[r];
        s.autocorrelation[axis][static_cast<std::size_t>(lag - 1)] = rho;
        // The fit ends at the first lag below min_correlation or not below the lag before.
        const double before = lag > 1 ? s.autocorrelation[axis][static_cast<std::size_t>(lag - 2)] : 1.0;
        if (!(rho >= options.min_correlation) || !(rho < before)) fitting = false;
        if (!fitting) continue;
        const double distance = lag * grid.spacing_mm[axis];
        r2.push_back(distance * distance);
        log_rho.push_back(std::log(rho));
      }
    }
    fit(r2, log_rho, s);
    s.white_share = 1.0 - s.amplitude;
    s.texture_sd = s.deviation_sd * std::sqrt(s.amplitude);
  }
  return out;
}

} // namespace phantasm
