// The within-tissue texture of a scan, measured: per region (a tissue's voxels), the spread of the
// relative deviation d = intensity / the region's mean - 1 and its spatial correlation, fitted by
// the autocorrelation of white noise smoothed by a Gaussian, so that a seeded random field can be
// drawn with the scan's spectrum (docs/volumes-and-images.md, "Tissue regions and texture").
#pragma once

#include "core/grid.hpp"

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace phantasm {

/// How texture is measured.
struct TextureSpectrumOptions {
  int max_lag = 12; ///< the largest lag fitted, in voxels along each axis
  /// Along an axis, the lags from the first whose correlation falls below this, or does not fall
  /// below the lag before's, are left out of the fit (the far lags' correlation is mostly noise).
  double min_correlation = 0.1;
  std::size_t min_pairs = 100; ///< a lag with fewer voxel pairs within the region is left out
  double max_deviation = std::numeric_limits<double>::infinity(); ///< d clamped to +-max_deviation first
  /// A voxel is measured only if every voxel within this many steps along the axes is of its
  /// region (the region eroded by a 6-connected element this many times; the grid's edge is no
  /// border): a voxel at a region's border mixes two tissues (partial volume), whose contrast
  /// would count as texture. A region is eroded only as deep as it keeps min_pairs voxels and
  /// min_eroded_share of its own (a thin one, as the skull's marrow, is measured whole).
  int erode_voxels = 1;
  double min_eroded_share = 0.25; ///< see erode_voxels
};

/// The texture of one region.
struct TextureSpectrum {
  std::size_t voxels = 0;    ///< voxels measured: of the region (eroded), with a finite intensity
  double mean = 0.0;         ///< their mean intensity
  double deviation_sd = 0.0; ///< standard deviation of d over them (white noise included)
  /// The autocorrelation of d at lags 1..max_lag voxels, per axis (i, j, k): the mean of d(x) d(x + lag)
  /// over the pairs of voxels both in the region, over the variance of d; NaN for a lag without enough pairs.
  std::vector<double> autocorrelation[3];
  /// The fit rho(r) = amplitude exp(-r^2 / (4 s^2)) to the autocorrelation at lags >= 1 (r in mm):
  /// the autocorrelation of white noise smoothed by a Gaussian of standard deviation s, the
  /// amplitude below 1 by the share of the variance that is uncorrelated from voxel to voxel
  /// (the scan's noise and detail finer than a voxel), which lag 0 alone holds.
  double correlation_mm = 0.0; ///< s
  double amplitude = 0.0;      ///< the fitted correlated share of the variance, at most 1
  double white_share = 1.0;    ///< 1 - amplitude
  double texture_sd = 0.0;     ///< deviation_sd sqrt(amplitude): the correlated part's standard deviation
  int lags_fitted = 0;         ///< lags (over all axes) the fit used
};

/// Measures each region's texture in `intensity` (one value per voxel of `grid`; NaN values are
/// left out): region[v] is the region of voxel v, in [0, region_count), or -1 for none; each region
/// eroded by options.erode_voxels first.
/// With no lag fitted (the correlation at one voxel already below min_correlation), s is 0 and
/// the amplitude 0; with one, the amplitude is taken as 1; with several, both are fitted (least
/// squares on log rho against r^2, weighted by rho^2), the amplitude capped at 1.
/// @throws std::invalid_argument for volumes of another grid
std::vector<TextureSpectrum> measure_texture_spectra(const ImageGrid& grid,
                                                     const std::vector<float>& intensity,
                                                     const std::vector<int>& region, int region_count,
                                                     const TextureSpectrumOptions& options = {});

} // namespace phantasm
