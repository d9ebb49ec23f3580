// k-space acquisition: the identity without truncation, Gibbs ringing of a truncated step, the
// noise level of the reconstruction, the slice profile, independence from the thread count, the
// pipeline against the per-coil acquisition, and the normal deviates of its noise.

#include "mri/gaussian_noise.hpp"
#include "mri/kspace.hpp"
#include "mri/kspace_reference.hpp"

#include <fftw3.h>
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

using namespace phantasm;
using phantasm::reference::acquire_in_kspace;

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

namespace {

std::vector<double> random_real_object(const Eigen::Vector3i& dims, unsigned seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<double> object(static_cast<std::size_t>(dims.prod()));
  for (auto& value : object)
    value = uniform(random);
  // Empty rows and lines, as around a head: the pipeline skips their transforms.
  for (int k = 0; k < dims.z(); ++k)
    for (int i = 0; i < dims.x(); ++i)
      object[static_cast<std::size_t>((k * dims.y() + 0) * dims.x() + i)] = 0.0;
  for (int k = 0; k < dims.z(); ++k)
    object[static_cast<std::size_t>((k * dims.y() + 1) * dims.x() + 1)] = 0.0;
  return object;
}

} // namespace

// The pipeline (real object transformed along z once, sensitivities in-plane, plane by plane)
// equals acquire_in_kspace() of the complex product, for even and odd lengths and kept counts,
// with and without a slice profile and a sensitivity, to 1e-6 of the largest value: the planes
// are held in single precision between the passes (the images are single precision).
TEST(Kspace, PipelineEqualsThePerCoilAcquisition) {
  struct Case {
    Eigen::Vector3i dims, acquired;
    double slice;
  };
  for (const Case& c : {Case{{24, 17, 10}, {17, 12, 7}, 0.0}, Case{{40, 36, 20}, {20, 30, 11}, 2.0},
                        Case{{16, 16, 16}, {16, 16, 16}, 0.0}, Case{{12, 9, 8}, {6, 4, 8}, 1.5},
                        Case{{8, 8, 1}, {5, 6, 1}, 0.0}}) {
    KspaceSampling sampling;
    sampling.dims = c.dims;
    sampling.acquired = c.acquired;
    sampling.slice_thickness_voxels = c.slice;
    const auto object = random_real_object(c.dims, 4);
    const auto sensitivity = random_object(Eigen::Vector3i(c.dims.x(), c.dims.y(), 1), 8);
    KspacePipeline pipeline(sampling);
    pipeline.set_object(object);
    for (const std::complex<double>* s :
         {static_cast<const std::complex<double>*>(nullptr), sensitivity.data()}) {
      std::vector<std::complex<double>> expected(object.size());
      const std::size_t plane = static_cast<std::size_t>(c.dims.x()) * c.dims.y();
      for (std::size_t v = 0; v < object.size(); ++v)
        expected[v] = (s ? s[v % plane] : 1.0) * object[v];
      acquire_in_kspace(expected, sampling, 0.0, 1);
      std::vector<std::complex<double>> image;
      pipeline.acquire(s, 0.0, 1, image);
      double worst = 0.0, largest = 0.0;
      for (std::size_t v = 0; v < image.size(); ++v) {
        worst = std::max(worst, std::abs(image[v] - expected[v]));
        largest = std::max(largest, std::abs(expected[v]));
      }
      EXPECT_LT(worst, 1e-6 * largest) << c.dims.transpose() << " / " << c.acquired.transpose();
    }
  }
}

namespace {

/// The pipeline's arithmetic written out plainly, one coil, one plane and one line at a time,
/// with FFTW plans of the same sizes, kinds and flags on buffers of FFTW's alignment (what
/// decides which codelets run): the pipeline must give these bytes, however it schedules,
/// batches, transposes and delivers its work.
class PlainAcquisition {
public:
  explicit PlainAcquisition(const KspaceSampling& sampling) : m_sampling(sampling) {
    const Eigen::Vector3i& d = sampling.dims;
    auto* real = fftwf_alloc_real(static_cast<std::size_t>(d.z()));
    auto* in = fftwf_alloc_complex(static_cast<std::size_t>(d.maxCoeff()));
    auto* out = fftwf_alloc_complex(static_cast<std::size_t>(d.maxCoeff()));
    m_z_forward = fftwf_plan_dft_r2c_1d(d.z(), real, out, FFTW_ESTIMATE);
    for (int axis = 0; axis < 3; ++axis)
      for (int direction : {FFTW_FORWARD, FFTW_BACKWARD})
        m_plan[axis][direction == FFTW_FORWARD ? 0 : 1] =
            fftwf_plan_dft_1d(d[axis], in, out, direction, FFTW_ESTIMATE);
    fftwf_free(out);
    fftwf_free(in);
    fftwf_free(real);
    m_in =
        reinterpret_cast<std::complex<float>*>(fftwf_alloc_complex(static_cast<std::size_t>(d.maxCoeff())));
    m_out =
        reinterpret_cast<std::complex<float>*>(fftwf_alloc_complex(static_cast<std::size_t>(d.maxCoeff())));
  }
  ~PlainAcquisition() {
    fftwf_destroy_plan(m_z_forward);
    for (auto& pair : m_plan)
      for (fftwf_plan plan : pair)
        fftwf_destroy_plan(plan);
    fftwf_free(m_in);
    fftwf_free(m_out);
  }
  PlainAcquisition(const PlainAcquisition&) = delete;
  PlainAcquisition& operator=(const PlainAcquisition&) = delete;

  /// The half spectrum along z of the real object, truncated and slice-weighted.
  void set_object(const std::vector<double>& object) {
    const Eigen::Vector3i& d = m_sampling.dims;
    const int nx = d.x(), ny = d.y(), nz = d.z(), half = m_sampling.acquired.z() / 2 + 1;
    m_spectrum.assign(static_cast<std::size_t>(half) * nx * ny, 0.0f);
    m_row_used.assign(static_cast<std::size_t>(ny), false);
    auto* real = fftwf_alloc_real(static_cast<std::size_t>(nz));
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        bool nonzero = false;
        for (int t = 0; t < nz; ++t) {
          real[t] = static_cast<float>(object[at(i, j, t)]);
          nonzero = nonzero || real[t] != 0.0f;
        }
        if (!nonzero) continue; // an empty line's spectrum is zero, untransformed
        m_row_used[static_cast<std::size_t>(j)] = true;
        fftwf_execute_dft_r2c(m_z_forward, real, reinterpret_cast<fftwf_complex*>(m_out));
        for (int f = 0; f < half; ++f) {
          const float weight =
              m_sampling.slice_thickness_voxels > 0.0 && f > 0
                  ? static_cast<float>(std::sin(M_PI * f / nz * m_sampling.slice_thickness_voxels) /
                                       (M_PI * f / nz * m_sampling.slice_thickness_voxels))
                  : 1.0f;
          m_spectrum[(static_cast<std::size_t>(f) * ny + j) * nx + i] = m_out[f] * weight;
        }
      }
    fftwf_free(real);
  }

  /// One coil's image, as KspacePipeline::acquire() delivers it.
  std::vector<std::complex<double>> acquire(const std::complex<double>* sensitivity, double sigma,
                                            std::uint64_t seed) {
    const Eigen::Vector3i& d = m_sampling.dims;
    const int nx = d.x(), ny = d.y(), nz = d.z();
    const double total = static_cast<double>(nx) * ny * nz;
    const double sample_sigma = sigma * total / std::sqrt(static_cast<double>(m_sampling.acquired.prod()));
    auto kept = [&](int axis, int index) {
      return is_kept_frequency(index, d[axis], m_sampling.acquired[axis]);
    };
    // Per kept frequency along z, the plane of the coil's image after the in-plane passes.
    std::vector<std::vector<std::complex<float>>> planes(static_cast<std::size_t>(nz));
    std::vector<std::complex<float>> x_spectrum(static_cast<std::size_t>(nx) * ny), column(ny);
    for (int t = 0; t < nz; ++t) {
      if (!kept(2, t)) continue;
      const int f = signed_frequency(t, nz);
      const std::complex<float>* source = m_spectrum.data() + static_cast<std::size_t>(std::abs(f)) * nx * ny;
      // Along x: the object's spectrum (its conjugate for f < 0) times the sensitivities.
      for (int j = 0; j < ny; ++j) {
        std::complex<float>* row = x_spectrum.data() + static_cast<std::size_t>(j) * nx;
        if (!m_row_used[static_cast<std::size_t>(j)]) {
          std::fill_n(row, nx, 0.0f);
          continue;
        }
        for (int i = 0; i < nx; ++i) {
          m_in[i] = source[static_cast<std::size_t>(j) * nx + i];
          if (f < 0) m_in[i] = std::conj(m_in[i]);
          if (sensitivity) m_in[i] *= std::complex<float>(sensitivity[static_cast<std::size_t>(j) * nx + i]);
        }
        transform(0, FFTW_FORWARD, row, nx);
      }
      // Along y, the kept columns: truncation and noise, then back.
      std::vector<std::complex<float>> truncated(static_cast<std::size_t>(nx) * ny, 0.0f);
      for (int i = 0; i < nx; ++i) {
        if (!kept(0, i)) continue;
        for (int j = 0; j < ny; ++j)
          m_in[j] = x_spectrum[static_cast<std::size_t>(j) * nx + i];
        transform(1, FFTW_FORWARD, column.data(), ny);
        NormalStream noise(
            mix_seed(seed, static_cast<std::uint64_t>(t) * nx + static_cast<std::uint64_t>(i)));
        for (int j = 0; j < ny; ++j) {
          if (!kept(1, j)) {
            column[static_cast<std::size_t>(j)] = 0.0f;
          } else if (sigma > 0.0) {
            const double re = noise(), im = noise();
            column[static_cast<std::size_t>(j)] += std::complex<float>(static_cast<float>(sample_sigma * re),
                                                                       static_cast<float>(sample_sigma * im));
          }
        }
        std::copy(column.begin(), column.end(), m_in);
        transform(1, FFTW_BACKWARD, column.data(), ny);
        for (int j = 0; j < ny; ++j)
          truncated[static_cast<std::size_t>(j) * nx + i] = column[static_cast<std::size_t>(j)];
      }
      std::vector<std::complex<float>>& plane = planes[static_cast<std::size_t>(t)];
      plane.resize(static_cast<std::size_t>(nx) * ny);
      for (int j = 0; j < ny; ++j) {
        std::copy_n(truncated.data() + static_cast<std::size_t>(j) * nx, nx, m_in);
        transform(0, FFTW_BACKWARD, plane.data() + static_cast<std::size_t>(j) * nx, nx);
      }
    }
    // Along z: the kept frequencies, zero-filled, back onto the grid.
    std::vector<std::complex<double>> image(static_cast<std::size_t>(d.prod()));
    std::vector<std::complex<float>> line(static_cast<std::size_t>(nz));
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        for (int t = 0; t < nz; ++t)
          m_in[t] = kept(2, t) ? planes[static_cast<std::size_t>(t)][static_cast<std::size_t>(j) * nx + i]
                               : std::complex<float>(0.0f);
        transform(2, FFTW_BACKWARD, line.data(), nz);
        for (int t = 0; t < nz; ++t)
          image[at(i, j, t)] = std::complex<double>(line[static_cast<std::size_t>(t)]) * (1.0 / total);
      }
    return image;
  }

  /// The sum of squares of the coils' images, `together` coils added up at a time and each
  /// group's sum added to the total, as KspacePipeline::add_squared_magnitude() adds them.
  std::vector<double> sum_of_squares(const std::vector<KspaceCoil>& coils, int together) {
    std::vector<double> energy(static_cast<std::size_t>(m_sampling.dims.prod()), 0.0);
    for (std::size_t first = 0; first < coils.size(); first += static_cast<std::size_t>(together)) {
      std::vector<double> group(energy.size(), 0.0);
      for (std::size_t c = first; c < std::min(coils.size(), first + together); ++c) {
        const auto image = acquire(coils[c].sensitivity, coils[c].noise_sigma, coils[c].noise_seed);
        for (std::size_t v = 0; v < image.size(); ++v)
          group[v] += std::norm(image[v]);
      }
      for (std::size_t v = 0; v < energy.size(); ++v)
        energy[v] += group[v];
    }
    return energy;
  }

private:
  std::size_t at(int i, int j, int t) const {
    return (static_cast<std::size_t>(t) * m_sampling.dims.y() + j) * m_sampling.dims.x() + i;
  }
  /// The transform of the n values in m_in along `axis` into `out`.
  void transform(int axis, int direction, std::complex<float>* out, int n) {
    fftwf_execute_dft(m_plan[axis][direction == FFTW_FORWARD ? 0 : 1], reinterpret_cast<fftwf_complex*>(m_in),
                      reinterpret_cast<fftwf_complex*>(m_out));
    std::copy_n(m_out, n, out);
  }

  KspaceSampling m_sampling;
  fftwf_plan m_z_forward;
  fftwf_plan m_plan[3][2];
  std::complex<float>* m_in;
  std::complex<float>* m_out;
  std::vector<std::complex<float>> m_spectrum; ///< half x ny x nx
  std::vector<bool> m_row_used;
};

bool same_bytes(const void* a, const void* b, std::size_t bytes) {
  return std::memcmp(a, b, bytes) == 0;
}

} // namespace

// The pipeline gives, byte for byte, the plain acquisition above: one coil's complex image and
// the sum of squares of several, in groups of 1 to 3 coils through the call that adds to a sum
// and through the one that starts it, adds to it and ends with its root, for even and odd
// lengths, with and without a slice profile, sensitivities and noise, on one and two threads.
TEST(Kspace, PipelineGivesTheBytesOfThePlainAcquisition) {
  struct Case {
    Eigen::Vector3i dims, acquired;
    double slice;
  };
  const int threads = omp_get_max_threads();
  for (const Case& c : {Case{{24, 17, 10}, {17, 12, 7}, 0.0}, Case{{20, 18, 12}, {10, 15, 7}, 2.0},
                        Case{{9, 12, 8}, {9, 12, 8}, 1.5}, Case{{8, 8, 1}, {5, 6, 1}, 0.0}}) {
    KspaceSampling sampling;
    sampling.dims = c.dims;
    sampling.acquired = c.acquired;
    sampling.slice_thickness_voxels = c.slice;
    const auto object = random_real_object(c.dims, 4);
    const auto s1 = random_object(Eigen::Vector3i(c.dims.x(), c.dims.y(), 1), 8);
    const auto s2 = random_object(Eigen::Vector3i(c.dims.x(), c.dims.y(), 1), 9);
    PlainAcquisition plain(sampling);
    plain.set_object(object);
    const std::size_t voxels = object.size();
    for (int t : {1, 2}) {
      omp_set_num_threads(t);
      KspacePipeline pipeline(sampling, 3);
      pipeline.set_object(object);
      for (const std::complex<double>* s : {static_cast<const std::complex<double>*>(nullptr), s1.data()})
        for (double sigma : {0.0, 0.4}) {
          std::vector<std::complex<double>> image;
          pipeline.acquire(s, sigma, 21, image);
          const auto expected = plain.acquire(s, sigma, 21);
          EXPECT_TRUE(same_bytes(image.data(), expected.data(), voxels * sizeof(image[0])))
              << c.dims.transpose() << " / " << c.acquired.transpose() << ", " << t << " threads, "
              << (s ? "" : "no ") << "sensitivity, sigma " << sigma;
        }
      const std::vector<KspaceCoil> coils{{s1.data(), 0.3, 5}, {nullptr, 0.3, 6}, {s2.data(), 0.0, 7}};
      for (int together : {1, 2, 3}) {
        const std::vector<double> expected = plain.sum_of_squares(coils, together);
        KspacePipeline grouped(sampling, together);
        grouped.set_object(object);
        std::vector<double> energy(voxels, 0.0);
        grouped.add_squared_magnitude(coils, energy);
        EXPECT_TRUE(same_bytes(energy.data(), expected.data(), voxels * sizeof(double)))
            << c.dims.transpose() << ", " << together << " coils together, " << t << " threads";
        // Started, added to and ended in one pass each: the root of the same sum.
        std::vector<double> running(voxels, -1.0);
        std::vector<float> magnitude(voxels, -1.0f), root(voxels);
        for (int first = 0; first < 3; first += together) {
          const int count = std::min(together, 3 - first);
          grouped.add_squared_magnitude(coils.data() + first, count, first == 0, running.data(),
                                        first + count == 3 ? magnitude.data() : nullptr);
        }
        for (std::size_t v = 0; v < voxels; ++v)
          root[v] = static_cast<float>(std::sqrt(expected[v]));
        EXPECT_TRUE(same_bytes(magnitude.data(), root.data(), voxels * sizeof(float)))
            << c.dims.transpose() << ", " << together << " coils together, " << t << " threads";
      }
    }
    omp_set_num_threads(threads);
  }
}

// The pipeline's noise: each part of a reconstructed voxel has the requested sigma whatever the
// truncation, pure noise has a Rayleigh magnitude, the same seed gives the same bytes on one and
// two threads, another seed other noise, and the sum of squares of two coils at once equals the
// one of each coil in turn.
TEST(Kspace, PipelineNoiseHasTheRequestedSigmaOnAnyThreadCount) {
  for (const Eigen::Vector3i& acquired : {Eigen::Vector3i(64, 64, 32), Eigen::Vector3i(32, 40, 16)}) {
    KspaceSampling sampling;
    sampling.dims = {64, 64, 32};
    sampling.acquired = acquired;
    KspacePipeline pipeline(sampling);
    pipeline.set_object(std::vector<double>(static_cast<std::size_t>(sampling.dims.prod()), 0.0));
    const double sigma = 2.0;
    std::vector<std::complex<double>> image;
    pipeline.acquire(nullptr, sigma, 77, image);
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

  KspaceSampling sampling;
  sampling.dims = {40, 36, 20};
  sampling.acquired = {20, 30, 11};
  sampling.slice_thickness_voxels = 2.0;
  const auto object = random_real_object(sampling.dims, 9);
  const auto sensitivity = random_object(Eigen::Vector3i(40, 36, 1), 10);
  const int threads = omp_get_max_threads();
  std::vector<std::complex<double>> one, two, other_seed;
  {
    KspacePipeline pipeline(sampling);
    pipeline.set_object(object);
    omp_set_num_threads(1);
    pipeline.acquire(sensitivity.data(), 0.3, 5, one);
    omp_set_num_threads(2);
    pipeline.acquire(sensitivity.data(), 0.3, 5, two);
    omp_set_num_threads(threads);
    pipeline.acquire(sensitivity.data(), 0.3, 6, other_seed);
  }
  EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(one[0])));
  EXPECT_NE(0, std::memcmp(one.data(), other_seed.data(), one.size() * sizeof(one[0])));

  const std::vector<KspaceCoil> coils{{sensitivity.data(), 0.3, 5}, {sensitivity.data(), 0.3, 6}};
  std::vector<double> in_turn(object.size(), 0.0), together(object.size(), 0.0);
  KspacePipeline single(sampling, 1), pair(sampling, 2);
  single.set_object(object);
  pair.set_object(object);
  single.add_squared_magnitude(coils, in_turn);
  pair.add_squared_magnitude(coils, together);
  for (std::size_t v = 0; v < object.size(); ++v) {
    ASSERT_NEAR(together[v], in_turn[v], 1e-12 * (1.0 + in_turn[v]));
    ASSERT_NEAR(in_turn[v], std::norm(one[v]) + std::norm(other_seed[v]), 1e-12 * (1.0 + in_turn[v]));
  }
}

// The ziggurat's standard normal deviates (the pipeline's noise): moments, tail fractions and a
// histogram against the normal distribution, seeded repeatability.

namespace {

double normal_cdf(double x) {
  return 0.5 * std::erfc(-x / std::sqrt(2.0));
}

} // namespace

// The layers of the ziggurat have equal areas and close at the top (x[128] = 0, f = 1).
TEST(GaussianNoise, ZigguratLayersHaveEqualAreas) {
  const NormalStream::Table& t = NormalStream::table();
  const double v = 9.91256303526217e-3;
  EXPECT_NEAR(t.x[1], 3.442619855899, 1e-12);
  for (int i = 1; i < 128; ++i)
    EXPECT_NEAR(t.x[i] * (t.f[i + 1] - t.f[i]), v, 1e-9) << i;
  EXPECT_EQ(t.x[128], 0.0);
  EXPECT_EQ(t.f[128], 1.0);
}

// Four million deviates: mean, variance, skewness and kurtosis within 4 standard errors, the
// fractions beyond the ziggurat's tail start and beyond 4 within 10 %, and a chi-square over 60
// bins of equal normal probability (59 degrees of freedom: 100 is beyond p = 0.001).
TEST(GaussianNoise, DeviatesFollowTheStandardNormal) {
  NormalStream normal(12345);
  const int n = 4000000;
  const int bins = 60;
  std::vector<double> edges(bins - 1);
  for (int b = 1; b < bins; ++b) {
    // Bisection for the normal quantile of b / bins.
    double low = -10.0, high = 10.0;
    for (int it = 0; it < 100; ++it) {
      const double mid = 0.5 * (low + high);
      (normal_cdf(mid) < static_cast<double>(b) / bins ? low : high) = mid;
    }
    edges[static_cast<std::size_t>(b - 1)] = 0.5 * (low + high);
  }
  std::vector<double> counts(bins, 0.0);
  double m1 = 0.0, m2 = 0.0, m3 = 0.0, m4 = 0.0, tail = 0.0, far = 0.0;
  for (int i = 0; i < n; ++i) {
    const double x = normal();
    m1 += x;
    m2 += x * x;
    m3 += x * x * x;
    m4 += x * x * x * x;
    tail += std::abs(x) > 3.442619855899;
    far += std::abs(x) > 4.0;
    counts[static_cast<std::size_t>(std::upper_bound(edges.begin(), edges.end(), x) - edges.begin())] += 1.0;
  }
  const double sqrt_n = std::sqrt(static_cast<double>(n));
  EXPECT_NEAR(m1 / n, 0.0, 4.0 / sqrt_n);
  EXPECT_NEAR(m2 / n, 1.0, 4.0 * std::sqrt(2.0) / sqrt_n);
  EXPECT_NEAR(m3 / n, 0.0, 4.0 * std::sqrt(15.0) / sqrt_n);
  EXPECT_NEAR(m4 / n, 3.0, 4.0 * std::sqrt(96.0) / sqrt_n);
  EXPECT_NEAR(tail / n / std::erfc(3.442619855899 / std::sqrt(2.0)), 1.0, 0.1);
  EXPECT_NEAR(far / n / std::erfc(4.0 / std::sqrt(2.0)), 1.0, 0.1);
  double chi_square = 0.0;
  const double expected = static_cast<double>(n) / bins;
  for (double c : counts)
    chi_square += (c - expected) * (c - expected) / expected;
  EXPECT_LT(chi_square, 100.0);
}

// fill() writes the deviates that one call after another gives, bit for bit (through the slow
// paths of the wedges and the tail, which millions of deviates reach), and leaves the stream
// where those calls would.
TEST(GaussianNoise, FillGivesTheDeviatesOfOneCallAfterAnother) {
  for (std::uint64_t seed : {1ull, 42ull, 0x9e3779b97f4a7c15ull})
    for (std::size_t count :
         {std::size_t{0}, std::size_t{1}, std::size_t{7}, std::size_t{346}, std::size_t{3000000}}) {
      NormalStream calls(seed), filled(seed);
      std::vector<double> expected(count), values(count);
      for (double& x : expected)
        x = calls();
      filled.fill(values.data(), count);
      // (memcmp of no bytes still needs pointers that are not null: an empty vector has none)
      ASSERT_TRUE(count == 0 || std::memcmp(expected.data(), values.data(), count * sizeof(double)) == 0)
          << "seed " << seed << ", " << count << " deviates";
      for (int k = 0; k < 10; ++k) {
        const double a = calls(), b = filled();
        ASSERT_EQ(0, std::memcmp(&a, &b, sizeof a)) << "seed " << seed << ", after " << count;
      }
    }
}

TEST(GaussianNoise, SameSeedSameDeviates) {
  NormalStream a(7), b(7), c(8);
  bool differs = false;
  for (int i = 0; i < 1000; ++i) {
    const double x = a(), y = b(), z = c();
    ASSERT_EQ(x, y);
    differs = differs || x != z;
  }
  EXPECT_TRUE(differs);
}
