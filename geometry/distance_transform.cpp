#include "geometry/distance_transform.hpp"

#include "core/cancellation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace phantasm {
namespace {

/// Squared distances along one line: d(p) = min_q (spacing (p - q))^2 + f(q) (lower envelope of
/// parabolas). `f` holds the input and receives the output; v, z are scratch.
void distance_line(std::vector<double>& f, double spacing, std::vector<int>& v, std::vector<double>& z,
                   std::vector<double>& out) {
  const int n = static_cast<int>(f.size());
  const double inf = std::numeric_limits<double>::infinity();
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (f[static_cast<std::size_t>(q)] == inf) continue;
    const double fq = f[static_cast<std::size_t>(q)], xq = q * spacing;
    while (k >= 0) {
      const int p = v[static_cast<std::size_t>(k)];
      const double xp = p * spacing;
      const double s = ((fq + xq * xq) - (f[static_cast<std::size_t>(p)] + xp * xp)) / (2.0 * (xq - xp));
      if (s <= z[static_cast<std::size_t>(k)]) {
        --k;
      } else {
        ++k;
        v[static_cast<std::size_t>(k)] = q;
        z[static_cast<std::size_t>(k)] = s;
        z[static_cast<std::size_t>(k) + 1] = inf;
        break;
      }
    }
    if (k < 0) {
      k = 0;
      v[0] = q;
      z[0] = -inf;
      z[1] = inf;
    }
  }
  if (k < 0) {
    std::fill(out.begin(), out.end(), inf);
    return;
  }
  int j = 0;
  for (int p = 0; p < n; ++p) {
    const double x = p * spacing;
    while (z[static_cast<std::size_t>(j) + 1] < x)
      ++j;
    const int q = v[static_cast<std::size_t>(j)];
    const double d = x - q * spacing;
    out[static_cast<std::size_t>(p)] = d * d + f[static_cast<std::size_t>(q)];
  }
}

} // namespace

std::vector<double> distance_to(const std::vector<bool>& feature, const ImageGrid& grid) {
  const Eigen::Vector3i& dims = grid.dims;
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> squared(feature.size());
  for (std::size_t v = 0; v < feature.size(); ++v)
    squared[v] = feature[v] ? 0.0 : inf;
  const std::array<std::int64_t, 3> stride{1, dims.x(), std::int64_t{dims.x()} * dims.y()};
  for (int a = 0; a < 3; ++a) {
    const int b = a == 0 ? 1 : 0, c = a == 2 ? 1 : 2;
    const int n = dims[a];
    const std::int64_t lines = std::int64_t{dims[b]} * dims[c];
#pragma omp parallel
    {
      std::vector<double> f(static_cast<std::size_t>(n)), out(static_cast<std::size_t>(n)),
          z(static_cast<std::size_t>(n) + 1);
      std::vector<int> v(static_cast<std::size_t>(n));
#pragma omp for schedule(static)
      for (std::int64_t line = 0; line < lines; ++line) {
        const std::int64_t base = (line % dims[b]) * stride[b] + (line / dims[b]) * stride[c];
        for (int t = 0; t < n; ++t)
          f[static_cast<std::size_t>(t)] = squared[static_cast<std::size_t>(base + t * stride[a])];
        distance_line(f, grid.spacing_mm[a], v, z, out);
        for (int t = 0; t < n; ++t)
          squared[static_cast<std::size_t>(base + t * stride[a])] = out[static_cast<std::size_t>(t)];
      }
    }
    throw_if_cancelled(); // between passes: no exception may leave an OpenMP region
  }
  for (double& d : squared)
    d = std::sqrt(d);
  return squared;
}

} // namespace phantasm
