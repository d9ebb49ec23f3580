// k-space acquisition: the identity without truncation, Gibbs ringing of a truncated step, the
// noise level of the reconstruction, the slice profile, and independence from the thread count.

#include "mri/kspace.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstring>
#include <random>

using namespace phantasm;

namespace {

std::vector<std::complex<double>> random_object(const Eigen::Vector3i& dims, unsigned seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<std::complex<double>> object(static_cast<std::size_t>(dims.prod()));
  for (auto& value : object)
    value = {uniform(random), uniform(random)};
  return object;
}

} // namespace

TEST(Kspace, KeptFrequenciesAreTheCentralOnes) {
  EXPECT_EQ(signed_frequency(0, 8), 0);
  EXPECT_EQ(signed_frequency(3, 8), 3);
  EXPECT_EQ(signed_frequency(4, 8), -4);
  EXPECT_EQ(signed_frequency(7, 8), -1);
  EXPECT_EQ(signed_frequency(3, 7), 3);
  EXPECT_EQ(signed_frequency(4, 7), -3);
  int kept = 0;
  for (int i = 0; i < 16; ++i)
    kept += is_kept_frequency(i, 16, 6);
  EXPECT_EQ(kept, 6);
  EXPECT_TRUE(is_kept_frequency(13, 16, 6)); // -3
  EXPECT_FALSE(is_kept_frequency(3, 16, 6)); // +3
  EXPECT_TRUE(is_kept_frequency(2, 16, 6));  // +2
  for (int i = 0; i < 9; ++i)
    EXPECT_TRUE(is_kept_frequency(i, 9, 9));
}

// Keeping every sample reproduces the object: the image equals the direct evaluation.
TEST(Kspace, WithoutTruncationTheImageIsTheObject) {
  KspaceSampling sampling;
  sampling.dims = {24, 17, 10}; // even and odd lengths
  sampling.acquired = sampling.dims;
  ASSERT_TRUE(sampling.keeps_everything());
  const auto object = random_object(sampling.dims, 3);
  auto image = object;
  acquire_in_kspace(image, sampling, 0.0, 1);
  double worst = 0.0;
  for (std::size_t v = 0; v < image.size(); ++v)
    worst = std::max(worst, std::abs(image[v] - object[v]));
  EXPECT_LT(worst, 1e-13);
}

// An unfiltered truncated step overshoots by the Gibbs fraction (1.0895 of the jump in the limit),
// on both sides of each edge, and a constant object is kept at unit gain.
TEST(Kspace, TruncatedStepRingsWithTheGibbsOvershoot) {
  KspaceSampling sampling;
  // 64 samples acquired, reconstructed 16 times finer so that the peak of the ringing is seen.
  sampling.dims = {1024, 4, 2};
  sampling.acquired = {64, 4, 2};
  std::vector<std::complex<double>> image(static_cast<std::size_t>(sampling.dims.prod()));
  for (std::size_t v = 0; v < image.size(); ++v) {
    const auto i = static_cast<int>(v % 1024);
    image[v] = i >= 256 && i < 768 ? 1.0 : 0.0;
  }
  acquire_in_kspace(image, sampling, 0.0, 1);
  double high = -1.0, low = 1.0, imaginary = 0.0;
  for (const auto& value : image) {
    high = std::max(high, value.real());
    low = std::min(low, value.real());
    imaginary = std::max(imaginary, std::abs(value.imag()));
  }
  EXPECT_NEAR(high - 1.0, 0.0895, 0.002);
  EXPECT_NEAR(-low, 0.0895, 0.002);
  // The unpaired Nyquist sample of an even count leaves a small imaginary part.
  EXPECT_LT(imaginary, 0.05);
  // Far from the edges the ringing has decayed to a few percent; the mean is kept exactly.
  double sum = 0.0;
  for (const auto& value : image)
    sum += value.real();
  EXPECT_NEAR(sum / static_cast<double>(image.size()), 0.5, 1e-12);
  EXPECT_NEAR(image[512].real(), 1.0, 0.03);
  EXPECT_NEAR(image[0].real(), 0.0, 0.03);

  std::vector<std::complex<double>> constant(image.size(), 2.5);
  acquire_in_kspace(constant, sampling, 0.0, 1);
  for (const auto& value : constant)
    ASSERT_NEAR(std::abs(value - 2.5), 0.0, 1e-12);
}

// Noise added in k-space gives each part of every reconstructed voxel the requested sigma,
// whatever fraction of k-space is kept; the magnitude of pure noise is Rayleigh.
TEST(Kspace, ReconstructedNoiseHasTheRequestedSigma) {
  for (const Eigen::Vector3i& acquired : {Eigen::Vector3i(64, 64, 32), Eigen::Vector3i(32, 40, 16)}) {
    KspaceSampling sampling;
    sampling.dims = {64, 64, 32};
    sampling.acquired = acquired;
    const double sigma = 2.0;
    std::vector<std::complex<double>> image(static_cast<std::size_t>(sampling.dims.prod()), 0.0);
    acquire_in_kspace(image, sampling, sigma, 77);
    double re2 = 0.0, im2 = 0.0, magnitude = 0.0;
    for (const auto& value : image) {
      re2 += value.real() * value.real();
      im2 += value.imag() * value.imag();
      magnitude += std::abs(value);
    }
    const auto n = static_cast<double>(image.size());
    EXPECT_NEAR(std::sqrt(re2 / n) / sigma, 1.0, 0.02) << acquired.transpose();
    EXPECT_NEAR(std::sqrt(im2 / n) / sigma, 1.0, 0.02) << acquired.transpose();
    EXPECT_NEAR(magnitude / n / (sigma * std::sqrt(M_PI / 2.0)), 1.0, 0.02) << acquired.transpose();
  }
}

// A rectangular slice profile of s voxels spreads a thin plane over about s voxels along k and
// keeps its integral; it leaves an object that is constant along k untouched.
TEST(Kspace, SliceProfileSpreadsAThinPlane) {
  KspaceSampling sampling;
  sampling.dims = {4, 4, 64};
  sampling.acquired = sampling.dims;
  sampling.slice_thickness_voxels = 5.0;
  EXPECT_FALSE(sampling.keeps_everything());
  std::vector<std::complex<double>> image(static_cast<std::size_t>(sampling.dims.prod()), 0.0);
  for (int v = 0; v < 16; ++v)
    image[static_cast<std::size_t>(32 * 16 + v)] = 1.0;
  acquire_in_kspace(image, sampling, 0.0, 1);
  std::vector<double> profile(64);
  double sum = 0.0, second = 0.0;
  for (int k = 0; k < 64; ++k) {
    profile[static_cast<std::size_t>(k)] = image[static_cast<std::size_t>(k * 16)].real();
    sum += profile[static_cast<std::size_t>(k)];
    second += (k - 32) * (k - 32) * profile[static_cast<std::size_t>(k)];
  }
  EXPECT_NEAR(sum, 1.0, 1e-12);
  // Symmetric about the plane, spread over the slice: 0.2 per voxel inside, little outside.
  for (int d = 1; d < 10; ++d)
    EXPECT_NEAR(profile[static_cast<std::size_t>(32 + d)], profile[static_cast<std::size_t>(32 - d)], 1e-12);
  for (int d = -2; d <= 2; ++d)
    EXPECT_NEAR(profile[static_cast<std::size_t>(32 + d)], 0.2, 0.03) << d;
  EXPECT_LT(std::abs(profile[36]), 0.03);
  // Second moment of a 5-voxel rectangle: 25 / 12 voxel^2.
  EXPECT_NEAR(second, 25.0 / 12.0, 0.02 * 25.0 / 12.0);

  std::vector<std::complex<double>> slab(image.size(), 1.0);
  acquire_in_kspace(slab, sampling, 0.0, 1);
  for (const auto& value : slab)
    ASSERT_NEAR(std::abs(value - 1.0), 0.0, 1e-12);
}

TEST(Kspace, SameBytesOnOneAndTwoThreads) {
  KspaceSampling sampling;
  sampling.dims = {40, 36, 20};
  sampling.acquired = {20, 30, 11};
  sampling.slice_thickness_voxels = 2.0;
  const auto object = random_object(sampling.dims, 9);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  auto one = object;
  acquire_in_kspace(one, sampling, 0.3, 5);
  omp_set_num_threads(2);
  auto two = object;
  acquire_in_kspace(two, sampling, 0.3, 5);
  omp_set_num_threads(threads);
  EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(one[0])));
  auto other_seed = object;
  acquire_in_kspace(other_seed, sampling, 0.3, 6);
  EXPECT_NE(0, std::memcmp(one.data(), other_seed.data(), one.size() * sizeof(one[0])));
}
