// Simulated acquisition in k-space: the central samples an acquisition keeps, the slice profile,
// complex noise per k-space line and zero-filled reconstruction (FFTW), thread-count independent.
#pragma once

#include "core/grid.hpp"

#include <complex>
#include <cstdint>
#include <vector>

namespace phantasm {

/// What an acquisition keeps of an object sampled on the phantom grid: the central
/// acquired.x x acquired.y x acquired.z samples of its discrete Fourier transform, weighted
/// along the third axis by the transform of a rectangular slice profile.
struct KspaceSampling {
  Eigen::Vector3i dims{1, 1, 1};     ///< the object grid's samples per axis
  Eigen::Vector3i acquired{1, 1, 1}; ///< k-space samples kept per axis, 1 <= acquired <= dims
  double slice_thickness_voxels = 0; ///< rectangular slice profile along k, in object voxels; 0: none

  /// True when every sample is kept and there is no slice profile: the acquisition is the identity.
  bool keeps_everything() const { return acquired == dims && slice_thickness_voxels <= 0.0; }
};

/// The signed frequency index of DFT sample `index` of `n` (0, 1, ..., -2, -1).
int signed_frequency(int index, int n);

/// True when the signed frequency of DFT sample `index` of `n` is among the `kept` central ones:
/// [-kept/2, (kept - 1)/2] after rounding down, so an even count keeps one more negative frequency,
/// as scanners do.
bool is_kept_frequency(int index, int n, int kept);

/// Acquires `image` (the complex object on the grid, x fastest) in place: forward DFT, keeps the
/// central samples of `sampling` weighted by the slice profile, adds complex Gaussian noise to
/// every kept sample such that each of the real and imaginary parts of a reconstructed voxel has
/// standard deviation `noise_sigma`, and reconstructs on the object grid by inverse DFT of the
/// zero-filled k-space (unit gain: a constant object is reproduced). Noise is drawn per k-space
/// line from streams seeded by `noise_seed`, and the lines are transformed in parallel with one
/// FFTW plan per axis, so the result does not depend on the number of threads.
void acquire_in_kspace(std::vector<std::complex<double>>& image, const KspaceSampling& sampling,
                       double noise_sigma, std::uint64_t noise_seed);

/// A seed mixed from a base seed and a stream number (splitmix64): independent streams for
/// images, coils and lines that every run repeats.
std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t stream);

} // namespace phantasm
