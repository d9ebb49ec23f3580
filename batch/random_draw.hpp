// Seeded random draws of a sweep's values (docs/batch.md, Random draws): the declared
// distribution of a varied key, and the value a subject draws from it. A draw depends only on
// the sweep's seed, the subject's index and the key's place in `vary`, so every shard, job and
// restart draws the same value.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace phantasm {

/// A declared distribution: `{uniform: [a, b]}`, `{log_uniform: [a, b]}`,
/// `{random_integer: [a, b]}`, `{normal: [mean, sd]}` or `{log_normal: [mu, sigma]}` (the value is
/// exp(mu + sigma Z)); normal and log_normal optionally with `add: c` (a constant added to the
/// draw, e.g. -1 to turn a volume ratio into a volume change) and `within: [low, high]` (the
/// distribution truncated to the range, after the constant is added).
struct RandomDistribution {
  std::string kind; ///< uniform, log_uniform, random_integer, normal, log_normal
  double a = 0.0, b = 0.0;
  double add = 0.0;
  bool truncated = false;
  double low = 0.0, high = 0.0; ///< the range `within` keeps (truncated only)
};

/// True for the kinds that take `add` and `within`.
bool takes_shape_options(const std::string& kind);

/// The probability that a draw of the untruncated distribution (with `add`) lies within
/// [low, high]: 1 when not truncated.
double probability_within(const RandomDistribution& distribution);

/// Subject `subject`'s draw of the key at place `key` of a sweep seeded with `seed`.
/// A truncated draw is drawn again until it lies within its range (sweeps refuse a range whose
/// probability is below 1e-3, so this ends).
double draw_value(const RandomDistribution& distribution, std::uint64_t seed, std::size_t subject,
                  std::size_t key);

/// The cumulative distribution function of a declared distribution at x (truncation included):
/// what the draws follow (tests compare them with it).
double distribution_cdf(const RandomDistribution& distribution, double x);

} // namespace phantasm
