// The former k-space acquisition, kept as the reference that tests and benchmarks compare
// KspacePipeline with (mri/kspace_reference.hpp): each image transformed on its own in double
// precision, a batch of lines at a time.

#include "mri/kspace_reference.hpp"

#include "core/cancellation.hpp"

#include <fftw3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <random>

namespace phantasm::reference {
namespace {

/// Lines transformed together: gathered side by side from neighbouring memory.
constexpr int k_batch = 8;

/// One FFTW plan for k_batch in-place transforms of length n, in one direction.
class BatchPlan {
public:
  BatchPlan(int n, int direction) : m_n(n) {
    std::lock_guard<std::mutex> guard(fftw_planner_lock());
    auto* buffer = fftw_alloc_complex(static_cast<std::size_t>(n) * k_batch);
    m_plan = fftw_plan_many_dft(1, &m_n, k_batch, buffer, nullptr, 1, n, buffer, nullptr, 1, n, direction,
                                FFTW_ESTIMATE);
    fftw_free(buffer);
  }
  ~BatchPlan() {
    std::lock_guard<std::mutex> guard(fftw_planner_lock());
    fftw_destroy_plan(m_plan);
  }
  BatchPlan(const BatchPlan&) = delete;
  BatchPlan& operator=(const BatchPlan&) = delete;
  /// Transforms k_batch lines of n samples held one after the other in an fftw_malloc buffer.
  void execute(std::complex<double>* lines) const {
    auto* data = reinterpret_cast<fftw_complex*>(lines);
    fftw_execute_dft(m_plan, data, data);
  }

private:
  int m_n;
  fftw_plan m_plan;
};

/// The lines along `axis` that a pass transforms: for each, the indices (u, v) along the two
/// other axes (u the lower one).
struct LineSet {
  int axis;
  std::vector<std::array<int, 2>> lines;
};

/// One pass of 1-D transforms along set.axis over the listed lines: each line is gathered,
/// transformed, handed to `after(u, v, line)`, and scattered back.
template <class After>
void transform_lines(std::vector<std::complex<double>>& image, const Eigen::Vector3i& dims,
                     const LineSet& set, int direction, const After& after) {
  const int a = set.axis, b = a == 0 ? 1 : 0, c = a == 2 ? 1 : 2;
  const std::array<std::int64_t, 3> stride{1, dims.x(), std::int64_t{dims.x()} * dims.y()};
  const int n = dims[a];
  const BatchPlan plan(n, direction);
  const auto batches = static_cast<std::int64_t>((set.lines.size() + k_batch - 1) / k_batch);
#pragma omp parallel
  {
    auto* buffer =
        reinterpret_cast<std::complex<double>*>(fftw_alloc_complex(static_cast<std::size_t>(n) * k_batch));
#pragma omp for schedule(static)
    for (std::int64_t batch = 0; batch < batches; ++batch) {
      if (cancellation_requested()) continue; // no exception may leave an OpenMP region
      const std::size_t first = static_cast<std::size_t>(batch) * k_batch;
      const std::size_t count = std::min<std::size_t>(k_batch, set.lines.size() - first);
      std::array<std::int64_t, k_batch> base{};
      for (std::size_t l = 0; l < count; ++l)
        base[l] = set.lines[first + l][0] * stride[b] + set.lines[first + l][1] * stride[c];
      for (int t = 0; t < n; ++t)
        for (std::size_t l = 0; l < k_batch; ++l)
          buffer[l * n + t] = l < count ? image[static_cast<std::size_t>(base[l] + t * stride[a])] : 0.0;
      plan.execute(buffer);
      for (std::size_t l = 0; l < count; ++l)
        after(set.lines[first + l][0], set.lines[first + l][1], buffer + l * n);
      for (int t = 0; t < n; ++t)
        for (std::size_t l = 0; l < count; ++l)
          image[static_cast<std::size_t>(base[l] + t * stride[a])] = buffer[l * n + t];
    }
    fftw_free(buffer);
  }
  throw_if_cancelled(); // a cut-short transform is garbage: nobody may read it
}

/// Lines along `axis` whose indices along the two other axes pass `keep(u, v)`.
template <class Keep>
LineSet lines_along(int axis, const Eigen::Vector3i& dims, const Keep& keep) {
  const int b = axis == 0 ? 1 : 0, c = axis == 2 ? 1 : 2;
  LineSet set{axis, {}};
  for (int v = 0; v < dims[c]; ++v)
    for (int u = 0; u < dims[b]; ++u)
      if (keep(u, v)) set.lines.push_back({u, v});
  return set;
}

/// sin(x) / x, 1 at 0.
double sinc(double x) {
  return std::abs(x) < 1e-12 ? 1.0 : std::sin(x) / x;
}

} // namespace

void acquire_in_kspace(std::vector<std::complex<double>>& image, const KspaceSampling& sampling,
                       double noise_sigma, std::uint64_t noise_seed) {
  const Eigen::Vector3i& dims = sampling.dims;
  const Eigen::Vector3i& kept = sampling.acquired;
  auto kept_along = [&](int axis, int index) { return is_kept_frequency(index, dims[axis], kept[axis]); };
  const double total = static_cast<double>(dims.x()) * dims.y() * dims.z();
  const double kept_count = static_cast<double>(kept.x()) * kept.y() * kept.z();
  // Per part noise of each kept sample for sigma per part in the reconstructed voxel (the
  // inverse transform is scaled by 1 / total).
  const double sample_sigma = noise_sigma * total / std::sqrt(kept_count);

  const LineSet all_x = lines_along(0, dims, [](int, int) { return true; });
  const LineSet kept_x = lines_along(1, dims, [&](int i, int) { return kept_along(0, i); });
  const LineSet kept_xy =
      lines_along(2, dims, [&](int i, int j) { return kept_along(0, i) && kept_along(1, j); });

  auto crop = [&](int axis) {
    return [&, axis](int, int, std::complex<double>* line) {
      for (int t = 0; t < dims[axis]; ++t)
        if (!kept_along(axis, t)) line[t] = 0.0;
    };
  };
  transform_lines(image, dims, all_x, FFTW_FORWARD, crop(0));
  transform_lines(image, dims, kept_x, FFTW_FORWARD, crop(1));
  transform_lines(image, dims, kept_xy, FFTW_FORWARD, [&](int i, int j, std::complex<double>* line) {
    std::mt19937_64 random(mix_seed(noise_seed, static_cast<std::uint64_t>(j) * dims.x() + i));
    std::normal_distribution<double> noise(0.0, 1.0);
    for (int t = 0; t < dims.z(); ++t) {
      if (!kept_along(2, t)) {
        line[t] = 0.0;
        continue;
      }
      if (sampling.slice_thickness_voxels > 0.0) {
        const double cycles_per_voxel = static_cast<double>(signed_frequency(t, dims.z())) / dims.z();
        line[t] *= sinc(M_PI * cycles_per_voxel * sampling.slice_thickness_voxels);
      }
      if (noise_sigma > 0.0) {
        const double re = noise(random), im = noise(random);
        line[t] += sample_sigma * std::complex<double>(re, im);
      }
    }
  });
  auto nothing = [](int, int, std::complex<double>*) {};
  transform_lines(image, dims, kept_xy, FFTW_BACKWARD, nothing);
  transform_lines(image, dims, kept_x, FFTW_BACKWARD, nothing);
  const double scale = 1.0 / total;
  transform_lines(image, dims, all_x, FFTW_BACKWARD, [&](int, int, std::complex<double>* line) {
    for (int t = 0; t < dims.x(); ++t)
      line[t] *= scale;
  });
}

} // namespace phantasm::reference
