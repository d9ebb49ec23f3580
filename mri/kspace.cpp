#include "mri/kspace.hpp"

#include "core/cancellation.hpp"
#include "mri/gaussian_noise.hpp"

#include <fftw3.h>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <random>

#include <cstdlib>
#include <cstring>
#include <new>
#include <stdexcept>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace phantasm {

std::mutex& fftw_planner_lock() {
  static std::mutex lock;
  return lock;
}

namespace {

/// Lines transformed together: gathered side by side from neighbouring memory.
constexpr int k_batch = 8;

double sinc(double x) {
  return std::abs(x) < 1e-12 ? 1.0 : std::sin(x) / x;
}

/// n rounded up to a multiple of `multiple`: strides that keep every line of a buffer at the
/// alignment of its start (64 bytes apart), so that one FFTW plan serves all of them.
int round_up(int n, int multiple) {
  return (n + multiple - 1) / multiple * multiple;
}

/// Single-precision complex buffers from FFTW's allocator, freed on scope exit.
struct FloatBuffer {
  explicit FloatBuffer(std::size_t count)
      : data(reinterpret_cast<std::complex<float>*>(fftwf_alloc_complex(std::max<std::size_t>(count, 1)))) {}
  ~FloatBuffer() { fftwf_free(data); }
  FloatBuffer(const FloatBuffer&) = delete;
  FloatBuffer& operator=(const FloatBuffer&) = delete;
  std::complex<float>* data;
};

fftwf_complex* as_fftwf(std::complex<float>* data) {
  return reinterpret_cast<fftwf_complex*>(data);
}

/// Copies one single-precision complex value in one 8-byte move (the compiler moves the two
/// floats of a std::complex<float> one at a time).
inline void move_complex(std::complex<float>* to, const std::complex<float>* from) {
  std::uint64_t bits;
  std::memcpy(&bits, from, sizeof bits);
  std::memcpy(static_cast<void*>(to), &bits, sizeof bits);
}

/// out[i] = float(sqrt(sum[i] + add[i])) for i < n, and float(sqrt(0.0 + add[i])) without `sum`:
/// two values at a time with SSE2, where the compiler takes one at a time (std::sqrt may set
/// errno, so it checks each value). The square root is correctly rounded either way, and the
/// conversions to float round alike: the same values.
void root_of_sum(const double* sum, const double* add, int n, float* out) {
  int i = 0;
#ifdef __SSE2__
  for (; i + 2 <= n; i += 2) {
    const __m128d total = _mm_add_pd(sum ? _mm_loadu_pd(sum + i) : _mm_setzero_pd(), _mm_loadu_pd(add + i));
    _mm_store_sd(reinterpret_cast<double*>(out + i), _mm_castps_pd(_mm_cvtpd_ps(_mm_sqrt_pd(total))));
  }
#endif
  for (; i < n; ++i)
    out[i] = static_cast<float>(std::sqrt((sum ? sum[i] : 0.0) + add[i]));
}

/// out[i] = a[i] x s[i] (conj(a[i]) x s[i] when `conjugate`) for i < n, with the formula that
/// g++ uses for std::complex<float> multiplication, (ar sr - ai si, ar si + ai sr): the same
/// values for finite operands (tested bit for bit), without the check of the product for NaN
/// (and the call to __mulsc3 behind it) that keeps the compiler from vectorizing the loop.
/// The complex values are read and written as their pairs of floats, which the standard allows.
void multiply_row(const std::complex<float>* a, const std::complex<float>* s, bool conjugate, int n,
                  std::complex<float>* out) {
  const auto* x = reinterpret_cast<const float*>(a);
  const auto* y = reinterpret_cast<const float*>(s);
  auto* z = reinterpret_cast<float*>(out);
  if (conjugate) {
    for (int i = 0; i < 2 * n; i += 2) {
      const float ar = x[i], ai = -x[i + 1], sr = y[i], si = y[i + 1];
      z[i] = ar * sr - ai * si;
      z[i + 1] = ar * si + ai * sr;
    }
  } else {
    for (int i = 0; i < 2 * n; i += 2) {
      const float ar = x[i], ai = x[i + 1], sr = y[i], si = y[i + 1];
      z[i] = ar * sr - ai * si;
      z[i + 1] = ar * si + ai * sr;
    }
  }
}

/// `count` single-precision complex values for the planes that every coil passes through, in
/// 2 MiB pages where the system offers them (fewer page-table misses on the strided passes).
/// Freed with std::free.
std::complex<float>* allocate_planes(std::size_t count) {
  constexpr std::size_t huge_page = std::size_t{1} << 21;
  const std::size_t bytes =
      (std::max<std::size_t>(count, 1) * sizeof(std::complex<float>) + huge_page - 1) / huge_page * huge_page;
  void* memory = std::aligned_alloc(huge_page, bytes);
  if (!memory) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
  madvise(memory, bytes, MADV_HUGEPAGE); // advice only: ignore a refusal
#endif
  return static_cast<std::complex<float>*>(memory);
}

} // namespace

int signed_frequency(int index, int n) {
  return index < (n + 1) / 2 ? index : index - n;
}

bool is_kept_frequency(int index, int n, int kept) {
  const int f = signed_frequency(index, n);
  return f >= -(kept / 2) && f <= (kept - 1) / 2;
}

std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/// One-line out-of-place plans, each executed on many lines of the same alignment (FFTW_ESTIMATE:
/// the same algorithm, hence the same bytes, on every run).
struct KspacePipeline::Plans {
  fftwf_plan z_forward = nullptr;  ///< real to complex along z
  fftwf_plan x_forward = nullptr;  ///< along x
  fftwf_plan x_backward = nullptr; ///< along x
  fftwf_plan y_forward = nullptr;  ///< along y (transposed columns)
  fftwf_plan y_backward = nullptr; ///< along y
  fftwf_plan z_backward = nullptr; ///< along z
};

namespace {
constexpr int k_real_multiple = 16;   ///< floats per 64 bytes
constexpr int k_complex_multiple = 8; ///< complex floats per 64 bytes
} // namespace

KspacePipeline::KspacePipeline(const KspaceSampling& sampling, int coils_together)
    : m_sampling(sampling), m_coils_together(std::max(1, coils_together)) {
  const Eigen::Vector3i& dims = sampling.dims;
  const Eigen::Vector3i& kept = sampling.acquired;
  m_row = round_up(dims.x(), k_complex_multiple);
  m_plane = static_cast<std::size_t>(m_row) * static_cast<std::size_t>(dims.y());
  m_column = round_up(dims.y(), k_complex_multiple);
  for (int i = 0; i < dims.x(); ++i)
    if (is_kept_frequency(i, dims.x(), kept.x())) m_kept_x.push_back(i);
  for (int j = 0; j < dims.y(); ++j)
    (is_kept_frequency(j, dims.y(), kept.y()) ? m_kept_y : m_dropped_y).push_back(j);
  for (int t = 0; t < dims.z(); ++t)
    if (is_kept_frequency(t, dims.z(), kept.z())) m_kept_z.push_back(t);
  // Kept frequencies along z run from -(kept / 2) to (kept - 1) / 2: magnitudes up to kept / 2.
  m_half = kept.z() / 2 + 1;
  m_spectrum = allocate_planes(static_cast<std::size_t>(m_half) * m_plane);
  m_coil = allocate_planes(static_cast<std::size_t>(m_coils_together) * m_kept_z.size() * m_plane);
  m_plans = new Plans;
  std::lock_guard<std::mutex> guard(fftw_planner_lock());
  const int longest = std::max({m_row, m_column, round_up(dims.z(), k_complex_multiple)});
  float* real = fftwf_alloc_real(static_cast<std::size_t>(round_up(dims.z(), k_real_multiple)));
  fftwf_complex* in = fftwf_alloc_complex(static_cast<std::size_t>(longest));
  fftwf_complex* out = fftwf_alloc_complex(static_cast<std::size_t>(longest));
  m_plans->z_forward = fftwf_plan_dft_r2c_1d(dims.z(), real, out, FFTW_ESTIMATE);
  m_plans->x_forward = fftwf_plan_dft_1d(dims.x(), in, out, FFTW_FORWARD, FFTW_ESTIMATE);
  m_plans->x_backward = fftwf_plan_dft_1d(dims.x(), in, out, FFTW_BACKWARD, FFTW_ESTIMATE);
  m_plans->y_forward = fftwf_plan_dft_1d(dims.y(), in, out, FFTW_FORWARD, FFTW_ESTIMATE);
  m_plans->y_backward = fftwf_plan_dft_1d(dims.y(), in, out, FFTW_BACKWARD, FFTW_ESTIMATE);
  m_plans->z_backward = fftwf_plan_dft_1d(dims.z(), in, out, FFTW_BACKWARD, FFTW_ESTIMATE);
  fftwf_free(out);
  fftwf_free(in);
  fftwf_free(real);
}

KspacePipeline::~KspacePipeline() {
  {
    std::lock_guard<std::mutex> guard(fftw_planner_lock());
    for (fftwf_plan plan : {m_plans->z_forward, m_plans->x_forward, m_plans->x_backward, m_plans->y_forward,
                            m_plans->y_backward, m_plans->z_backward})
      if (plan) fftwf_destroy_plan(plan);
  }
  delete m_plans;
  std::free(m_coil);
  std::free(m_spectrum);
}

void KspacePipeline::set_object(const std::vector<double>& object) {
  transform_object(object.data());
}

void KspacePipeline::set_object(const float* object) {
  transform_object(object);
}

template <class Value>
void KspacePipeline::transform_object(const Value* object) {
  const Eigen::Vector3i& dims = m_sampling.dims;
  const int nx = dims.x(), ny = dims.y(), nz = dims.z();
  const std::size_t slice = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  const int real_stride = round_up(nz, k_real_multiple);
  const int half_stride = round_up(nz / 2 + 1, k_complex_multiple);
  // The slice profile's transform is real and even: the half spectrum keeps its symmetry.
  std::vector<float> weight(static_cast<std::size_t>(m_half), 1.0f);
  if (m_sampling.slice_thickness_voxels > 0.0)
    for (int f = 0; f < m_half; ++f)
      weight[static_cast<std::size_t>(f)] =
          static_cast<float>(sinc(M_PI * static_cast<double>(f) / nz * m_sampling.slice_thickness_voxels));
  m_row_used.assign(static_cast<std::size_t>(ny), 0);
  const fftwf_plan plan = m_plans->z_forward;
  // One in-plane row j at a time: its nz rows of the object are read whole (far apart in memory,
  // each contiguous), its lines along z are transformed from that copy, and its half spectrum
  // is written whole into the planes.
#pragma omp parallel
  {
    std::vector<float> rows(static_cast<std::size_t>(nz) * static_cast<std::size_t>(nx));
    std::vector<std::complex<float>> spectrum(static_cast<std::size_t>(m_half) *
                                              static_cast<std::size_t>(nx));
    float* in = fftwf_alloc_real(static_cast<std::size_t>(k_batch) * real_stride);
    FloatBuffer out(static_cast<std::size_t>(k_batch) * half_stride);
#pragma omp for schedule(dynamic, 1) nowait
    for (int j = 0; j < ny; ++j) {
      if (cancellation_requested()) continue; // no exception may leave an OpenMP region
      const std::size_t first = static_cast<std::size_t>(j) * static_cast<std::size_t>(nx);
      bool used = false;
      for (int t = 0; t < nz; ++t) {
        const Value* from = object + static_cast<std::size_t>(t) * slice + first;
        float* to = rows.data() + static_cast<std::size_t>(t) * nx;
        for (int i = 0; i < nx; ++i)
          to[i] = static_cast<float>(from[i]);
      }
      for (int i0 = 0; i0 < nx; i0 += k_batch) {
        const int count = std::min(k_batch, nx - i0);
        for (int t = 0; t < nz; ++t)
          for (int b = 0; b < count; ++b)
            in[b * real_stride + t] =
                rows[static_cast<std::size_t>(t) * nx + static_cast<std::size_t>(i0 + b)];
        for (int b = 0; b < count; ++b) {
          const float* line = in + b * real_stride;
          // An empty line's transform is zero: most of a field of view around a head.
          const bool nonzero = std::any_of(line, line + nz, [](float x) { return x != 0.0f; });
          if (nonzero)
            fftwf_execute_dft_r2c(plan, in + b * real_stride, as_fftwf(out.data + b * half_stride));
          used = used || nonzero;
          for (int f = 0; f < m_half; ++f)
            spectrum[static_cast<std::size_t>(f) * nx + static_cast<std::size_t>(i0 + b)] =
                nonzero ? out.data[b * half_stride + f] * weight[static_cast<std::size_t>(f)]
                        : std::complex<float>(0.0f);
        }
      }
      for (int f = 0; f < m_half; ++f) {
        const std::complex<float>* from = spectrum.data() + static_cast<std::size_t>(f) * nx;
        std::copy(from, from + nx,
                  m_spectrum + static_cast<std::size_t>(f) * m_plane + static_cast<std::size_t>(j) * m_row);
      }
      m_row_used[static_cast<std::size_t>(j)] = used ? 1 : 0;
    }
    fftwf_free(in);
  }
  throw_if_cancelled(); // a cut-short spectrum is garbage: nobody may read it
}

namespace {

/// Adds noise of sigma per part to the kept samples of a k-space column along y. One stream per
/// coil and kept column, named by its frequencies along x and z (`seed`), drawn in the order of
/// the column's kept samples: real, imaginary, next sample.
void add_column_noise(std::uint64_t seed, double sigma, const std::vector<int>& kept_y,
                      std::vector<double>& deviates, std::complex<float>* column) {
  NormalStream noise(seed);
  noise.fill(deviates.data(), deviates.size());
  const auto kept = static_cast<int>(kept_y.size());
  for (int k = 0; k < kept; ++k)
    column[kept_y[static_cast<std::size_t>(k)]] +=
        std::complex<float>(static_cast<float>(sigma * deviates[2 * static_cast<std::size_t>(k)]),
                            static_cast<float>(sigma * deviates[2 * static_cast<std::size_t>(k) + 1]));
}

} // namespace

void KspacePipeline::transform_in_plane(const KspaceCoil* coils, int count) {
  const Eigen::Vector3i& dims = m_sampling.dims;
  const int nx = dims.x(), ny = dims.y(), nz = dims.z();
  const auto kept_x = static_cast<int>(m_kept_x.size());
  const auto kept_y = static_cast<int>(m_kept_y.size());
  const auto kept_z = static_cast<int>(m_kept_z.size());
  const double total = static_cast<double>(nx) * ny * nz;
  const double kept_count = static_cast<double>(m_sampling.acquired.prod());
  const std::size_t coil_planes = static_cast<std::size_t>(kept_z) * m_plane;
  const std::size_t slice = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  constexpr int k_block = 8; // rows moved together by the transposes
  // Locals, not members, in the loops that move values: the compiler cannot tell that a store
  // through a byte copy leaves the members alone, and would load them again for every value.
  const std::size_t row_stride = static_cast<std::size_t>(m_row);
  const std::size_t column_stride = static_cast<std::size_t>(m_column);
  const int* const kept_x_index = m_kept_x.data();

  // The sensitivities rounded to single precision once per coil, not once per plane: the
  // values that the products take.
  std::vector<std::complex<float>> sensitivities(static_cast<std::size_t>(count) * slice);
  for (int p = 0; p < count; ++p) {
    if (const std::complex<double>* s = coils[p].sensitivity)
      std::transform(s, s + slice, sensitivities.begin() + static_cast<std::ptrdiff_t>(p * slice),
                     [](const std::complex<double>& value) { return std::complex<float>(value); });
  }

  // In-plane, one kept plane along z at a time (it stays in cache), for each coil: multiply,
  // transform along x, move the kept columns aside, transform them along y, truncate, add noise,
  // transform back along y, and along x into the coil's plane. Out-of-place transforms: faster.
#pragma omp parallel
  {
    FloatBuffer columns(static_cast<std::size_t>(kept_x) * m_column);
    FloatBuffer rows(static_cast<std::size_t>(k_block) * m_row);
    // Rows for the backward transforms along x: only the kept columns are ever written, the
    // others stay zero.
    FloatBuffer back(static_cast<std::size_t>(k_block) * m_row);
    std::fill_n(back.data, static_cast<std::size_t>(k_block) * m_row, std::complex<float>(0.0f));
    FloatBuffer staged(static_cast<std::size_t>(std::max(m_row, m_column)));
    std::vector<double> deviates(2 * static_cast<std::size_t>(kept_y));
#pragma omp for schedule(dynamic, 1) nowait
    for (int q = 0; q < kept_z; ++q) {
      if (cancellation_requested()) continue; // no exception may leave an OpenMP region
      const int t = m_kept_z[static_cast<std::size_t>(q)];
      const int f = signed_frequency(t, nz);
      // The object is real: its spectrum at -f is the conjugate of the one at f.
      const std::complex<float>* source = m_spectrum + static_cast<std::size_t>(std::abs(f)) * m_plane;
      for (int p = 0; p < count; ++p) {
        const std::complex<float>* sensitivity =
            coils[p].sensitivity ? sensitivities.data() + static_cast<std::size_t>(p) * slice : nullptr;
        // Per part noise of each kept sample for sigma per part in the reconstructed voxel (the
        // inverse transform is scaled by 1 / total), as in reference::acquire_in_kspace().
        const double sample_sigma = coils[p].noise_sigma * total / std::sqrt(kept_count);
        std::complex<float>* plane =
            m_coil + static_cast<std::size_t>(p) * coil_planes + static_cast<std::size_t>(q) * m_plane;
        for (int j0 = 0; j0 < ny; j0 += k_block) {
          const int block = std::min(k_block, ny - j0);
          for (int r = 0; r < block; ++r) {
            const int j = j0 + r;
            std::complex<float>* row = rows.data + static_cast<std::size_t>(r) * m_row;
            if (!m_row_used[static_cast<std::size_t>(j)]) { // the object never reaches it: zero
              std::fill_n(row, nx, std::complex<float>(0.0f));
              continue;
            }
            const std::complex<float>* from = source + static_cast<std::size_t>(j) * m_row;
            if (sensitivity)
              multiply_row(from, sensitivity + static_cast<std::size_t>(j) * nx, f < 0, nx, staged.data);
            else if (f < 0)
              for (int i = 0; i < nx; ++i)
                staged.data[i] = std::conj(from[i]);
            else
              std::copy(from, from + nx, staged.data);
            fftwf_execute_dft(m_plans->x_forward, as_fftwf(staged.data), as_fftwf(row));
          }
          for (int c = 0; c < kept_x; ++c) {
            std::complex<float>* column = columns.data + static_cast<std::size_t>(c) * column_stride + j0;
            const std::complex<float>* from = rows.data + kept_x_index[c];
            for (int r = 0; r < block; ++r)
              move_complex(column + r, from + static_cast<std::size_t>(r) * row_stride);
          }
        }
        for (int c = 0; c < kept_x; ++c) {
          std::complex<float>* column = columns.data + static_cast<std::size_t>(c) * m_column;
          fftwf_execute_dft(m_plans->y_forward, as_fftwf(column), as_fftwf(staged.data));
          for (int j : m_dropped_y)
            staged.data[j] = 0.0f;
          if (coils[p].noise_sigma > 0.0) {
            const int i = m_kept_x[static_cast<std::size_t>(c)];
            add_column_noise(mix_seed(coils[p].noise_seed,
                                      static_cast<std::uint64_t>(t) * nx + static_cast<std::uint64_t>(i)),
                             sample_sigma, m_kept_y, deviates, staged.data);
          }
          fftwf_execute_dft(m_plans->y_backward, as_fftwf(staged.data), as_fftwf(column));
        }
        for (int j0 = 0; j0 < ny; j0 += k_block) {
          const int block = std::min(k_block, ny - j0);
          for (int c = 0; c < kept_x; ++c) {
            const std::complex<float>* column =
                columns.data + static_cast<std::size_t>(c) * column_stride + j0;
            std::complex<float>* into = back.data + kept_x_index[c];
            for (int r = 0; r < block; ++r)
              move_complex(into + static_cast<std::size_t>(r) * row_stride, column + r);
          }
          for (int r = 0; r < block; ++r) {
            fftwf_execute_dft(m_plans->x_backward, as_fftwf(back.data + static_cast<std::size_t>(r) * m_row),
                              as_fftwf(plane + static_cast<std::size_t>(j0 + r) * m_row));
          }
        }
      }
    }
  }
}

void KspacePipeline::transform_along_z(int count, const Delivery& to) {
  const Eigen::Vector3i& dims = m_sampling.dims;
  const int nx = dims.x(), ny = dims.y(), nz = dims.z();
  const auto kept_z = static_cast<int>(m_kept_z.size());
  const double total = static_cast<double>(nx) * ny * nz;
  const std::size_t coil_planes = static_cast<std::size_t>(kept_z) * m_plane;
  const std::size_t slice = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  // Along z, one in-plane row j at a time: each coil's kept planes' rows are read whole (far
  // apart in memory, each contiguous), its lines are zero-filled and transformed back from that
  // copy, and the row's voxels are delivered once for all the coils.
  const double scale = 1.0 / total;
  const int line_stride = round_up(nz, k_complex_multiple);
  const int* const kept_z_index = m_kept_z.data();
  std::complex<double>* const image = to.image;
  double* const energy = to.energy;
  float* const magnitude = to.magnitude;
  const bool first = to.first;
#pragma omp parallel
  {
    std::vector<std::complex<float>> kept_rows(static_cast<std::size_t>(kept_z) * nx);
    std::vector<std::complex<double>> image_rows(image ? static_cast<std::size_t>(nz) * nx : 0);
    std::vector<double> energy_rows(image ? 0 : static_cast<std::size_t>(nz) * nx);
    FloatBuffer lines(static_cast<std::size_t>(k_batch) * line_stride);
    FloatBuffer out(static_cast<std::size_t>(k_batch) * line_stride);
    // Frequencies that are not kept stay zero: only the kept ones are ever written.
    std::fill_n(lines.data, static_cast<std::size_t>(k_batch) * line_stride, std::complex<float>(0.0f));
#pragma omp for schedule(dynamic, 4) nowait
    for (int j = 0; j < ny; ++j) {
      if (cancellation_requested()) continue;
      for (int p = 0; p < count; ++p) {
        for (int q = 0; q < kept_z; ++q) {
          const std::complex<float>* from = m_coil + static_cast<std::size_t>(p) * coil_planes +
                                            static_cast<std::size_t>(q) * m_plane +
                                            static_cast<std::size_t>(j) * m_row;
          std::copy(from, from + nx, kept_rows.data() + static_cast<std::size_t>(q) * nx);
        }
        for (int i0 = 0; i0 < nx; i0 += k_batch) {
          const int batch = std::min(k_batch, nx - i0);
          for (int q = 0; q < kept_z; ++q) {
            const std::complex<float>* from = kept_rows.data() + static_cast<std::size_t>(q) * nx + i0;
            std::complex<float>* into = lines.data + kept_z_index[q];
            for (int b = 0; b < batch; ++b)
              move_complex(into + b * line_stride, from + b);
          }
          for (int b = 0; b < batch; ++b)
            fftwf_execute_dft(m_plans->z_backward, as_fftwf(lines.data + b * line_stride),
                              as_fftwf(out.data + b * line_stride));
          for (int t = 0; t < nz; ++t) {
            const std::size_t at = static_cast<std::size_t>(t) * nx + static_cast<std::size_t>(i0);
            const std::complex<float>* from = out.data + t;
            if (image) {
              for (int b = 0; b < batch; ++b)
                image_rows[at + static_cast<std::size_t>(b)] =
                    std::complex<double>(from[b * line_stride]) * scale;
            } else if (p == 0) { // the row's sum starts at 0
              for (int b = 0; b < batch; ++b)
                energy_rows[at + static_cast<std::size_t>(b)] =
                    0.0 + std::norm(std::complex<double>(from[b * line_stride]) * scale);
            } else {
              for (int b = 0; b < batch; ++b)
                energy_rows[at + static_cast<std::size_t>(b)] +=
                    std::norm(std::complex<double>(from[b * line_stride]) * scale);
            }
          }
        }
      }
      const std::size_t row = static_cast<std::size_t>(j) * static_cast<std::size_t>(nx);
      for (int t = 0; t < nz; ++t) {
        const std::size_t at = static_cast<std::size_t>(t) * nx;
        const std::size_t v = static_cast<std::size_t>(t) * slice + row;
        if (image) {
          std::copy(image_rows.data() + at, image_rows.data() + at + nx, image + v);
        } else if (magnitude) { // the last group: the root of the sum, which is not stored
          root_of_sum(first ? nullptr : energy + v, energy_rows.data() + at, nx, magnitude + v);
        } else if (first) {
          for (int i = 0; i < nx; ++i)
            energy[v + static_cast<std::size_t>(i)] = 0.0 + energy_rows[at + static_cast<std::size_t>(i)];
        } else {
          for (int i = 0; i < nx; ++i)
            energy[v + static_cast<std::size_t>(i)] += energy_rows[at + static_cast<std::size_t>(i)];
        }
      }
    }
  }
}

void KspacePipeline::acquire_coils(const KspaceCoil* coils, int count, const Delivery& to) {
  transform_in_plane(coils, count);
  throw_if_cancelled(); // a cut-short coil image is garbage: nobody may read it
  transform_along_z(count, to);
  throw_if_cancelled();
}

void KspacePipeline::acquire(const std::complex<double>* sensitivity, double noise_sigma,
                             std::uint64_t noise_seed, std::vector<std::complex<double>>& image) {
  image.resize(static_cast<std::size_t>(m_sampling.dims.prod()));
  const KspaceCoil coil{sensitivity, noise_sigma, noise_seed};
  Delivery to;
  to.image = image.data();
  acquire_coils(&coil, 1, to);
}

void KspacePipeline::add_squared_magnitude(const std::vector<KspaceCoil>& coils,
                                           std::vector<double>& energy) {
  for (std::size_t first = 0; first < coils.size(); first += static_cast<std::size_t>(m_coils_together)) {
    const auto count = static_cast<int>(std::min<std::size_t>(m_coils_together, coils.size() - first));
    add_squared_magnitude(coils.data() + first, count, false, energy.data(), nullptr);
  }
}

void KspacePipeline::add_squared_magnitude(const KspaceCoil* coils, int count, bool first, double* energy,
                                           float* magnitude) {
  if (count < 1 || count > m_coils_together)
    throw std::invalid_argument("KspacePipeline: 1 to coils_together() coils at a time");
  Delivery to;
  to.energy = energy;
  to.first = first;
  to.magnitude = magnitude;
  acquire_coils(coils, count, to);
}

} // namespace phantasm
