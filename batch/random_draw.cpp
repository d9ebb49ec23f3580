#include "batch/random_draw.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace phantasm {
namespace {

std::mt19937_64 generator(std::uint64_t seed, std::size_t subject, std::size_t key) {
  std::seed_seq mix{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(subject), static_cast<std::uint32_t>(key)};
  return std::mt19937_64(mix);
}

/// A uniform number in (0, 1) from 53 random bits: the same on every standard library (the
/// standard's real distributions are not specified bit for bit).
double open_unit(std::mt19937_64& random) {
  return (static_cast<double>(random() >> 11) + 0.5) * 0x1.0p-53;
}

/// A standard normal number (Box-Muller, the cosine branch).
double standard_normal(std::mt19937_64& random) {
  const double u = open_unit(random), v = open_unit(random);
  return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * M_PI * v);
}

double normal_cdf(double z) {
  return 0.5 * std::erfc(-z / std::sqrt(2.0));
}

/// The untruncated distribution's CDF (with `add`) at x.
double plain_cdf(const RandomDistribution& d, double x) {
  if (d.kind == "normal")
    return d.b > 0.0 ? normal_cdf((x - d.add - d.a) / d.b) : (x - d.add >= d.a ? 1.0 : 0.0);
  if (d.kind == "log_normal") {
    const double y = x - d.add;
    if (y <= 0.0) return 0.0;
    return d.b > 0.0 ? normal_cdf((std::log(y) - d.a) / d.b) : (std::log(y) >= d.a ? 1.0 : 0.0);
  }
  if (d.kind == "uniform")
    return d.b > d.a ? std::clamp((x - d.a) / (d.b - d.a), 0.0, 1.0) : (x >= d.a ? 1.0 : 0.0);
  if (d.kind == "log_uniform") {
    if (x <= 0.0) return 0.0;
    return d.b > d.a ? std::clamp(std::log(x / d.a) / std::log(d.b / d.a), 0.0, 1.0) : (x >= d.a ? 1.0 : 0.0);
  }
  if (d.kind == "random_integer") {
    const double k = std::floor(x);
    return std::clamp((k - d.a + 1.0) / (d.b - d.a + 1.0), 0.0, 1.0);
  }
  throw std::logic_error("distribution_cdf: unknown kind " + d.kind);
}

} // namespace

bool takes_shape_options(const std::string& kind) {
  return kind == "normal" || kind == "log_normal";
}

double probability_within(const RandomDistribution& d) {
  if (!d.truncated) return 1.0;
  // The lower end is open for a continuous distribution: the CDF just below low.
  return plain_cdf(d, d.high) - plain_cdf(d, std::nextafter(d.low, -INFINITY));
}

double draw_value(const RandomDistribution& d, std::uint64_t seed, std::size_t subject, std::size_t key) {
  std::mt19937_64 random = generator(seed, subject, key);
  if (d.kind == "random_integer")
    return static_cast<double>(std::uniform_int_distribution<long long>(static_cast<long long>(d.a),
                                                                        static_cast<long long>(d.b))(random));
  if (d.kind == "uniform") return std::uniform_real_distribution<double>(d.a, d.b)(random);
  if (d.kind == "log_uniform")
    return std::exp(std::uniform_real_distribution<double>(std::log(d.a), std::log(d.b))(random));
  if (!takes_shape_options(d.kind)) throw std::logic_error("draw_value: unknown kind " + d.kind);
  // Redrawn until within the range: at least 1e-3 of the draws are (the sweep checks), so
  // 10^5 tries miss with a probability below 10^-43.
  for (int attempt = 0; attempt < 100000; ++attempt) {
    const double z = standard_normal(random);
    const double value = (d.kind == "normal" ? d.a + d.b * z : std::exp(d.a + d.b * z)) + d.add;
    if (!d.truncated || (value >= d.low && value <= d.high)) return value;
  }
  throw std::logic_error("draw_value: no draw within the range");
}

double distribution_cdf(const RandomDistribution& d, double x) {
  if (!d.truncated) return plain_cdf(d, x);
  if (x < d.low) return 0.0;
  if (x >= d.high) return 1.0;
  return (plain_cdf(d, x) - plain_cdf(d, std::nextafter(d.low, -INFINITY))) / probability_within(d);
}

} // namespace phantasm
