// The former k-space acquisition, one complex image at a time in double precision: the reference
// that tests and benchmarks compare KspacePipeline (mri/kspace.hpp) with. Built only for them (the
// library phantasm::kspace_reference, which no stage links).
#pragma once

#include "mri/kspace.hpp"

#include <complex>
#include <cstdint>
#include <vector>

namespace phantasm::reference {

/// Acquires `image` (the complex object on the grid, x fastest) in place: forward DFT, keeps the
/// central samples of `sampling` weighted by the slice profile, adds complex Gaussian noise to
/// every kept sample such that each of the real and imaginary parts of a reconstructed voxel has
/// standard deviation `noise_sigma`, and reconstructs on the object grid by inverse DFT of the
/// zero-filled k-space (unit gain: a constant object is reproduced). Noise is drawn per k-space
/// line from streams seeded by `noise_seed`, and the lines are transformed in parallel with one
/// FFTW plan per axis, so the result does not depend on the number of threads.
void acquire_in_kspace(std::vector<std::complex<double>>& image, const KspaceSampling& sampling,
                       double noise_sigma, std::uint64_t noise_seed);

} // namespace phantasm::reference
