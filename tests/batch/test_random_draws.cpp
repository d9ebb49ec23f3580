// Declared distributions of a sweep's values: a draw is the same for the same seed, subject and
// key, and the draws follow the distribution the sweep file declares (Kolmogorov-Smirnov).

#include "batch/random_draw.hpp"
#include "batch/sweep.hpp"
#include "tests/support/error_message.hpp"
#include "tests/support/files.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

using namespace phantasm;
using namespace phantasm::testing;
namespace fs = std::filesystem;

namespace {

const fs::path k_growth_scene =
    fs::path(PHANTASM_SOURCE_DIR) / "tests" / "data" / "scenes" / "growth-balls.yaml";

std::string growth_sweep_text(std::uint64_t seed, const std::string& vary) {
  return "phantasm_sweep: 1\nbase_scene: " + k_growth_scene.string() + "\nseed: " + std::to_string(seed) +
         "\nrepeats: 6\nvary:\n" + vary;
}

/// The largest distance between the draws' empirical CDF and the declared one.
double ks_statistic(const RandomDistribution& d, const RandomDistribution& declared, std::size_t n) {
  std::vector<double> draws(n);
  for (std::size_t s = 0; s < n; ++s)
    draws[s] = draw_value(d, 2026, s, 1);
  std::sort(draws.begin(), draws.end());
  double largest = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double f = distribution_cdf(declared, draws[i]);
    largest = std::max({largest, std::abs(f - static_cast<double>(i) / n), std::abs(f - (i + 1.0) / n)});
  }
  return largest;
}

RandomDistribution declared(const std::string& kind, double a, double b) {
  RandomDistribution d;
  d.kind = kind;
  d.a = a;
  d.b = b;
  return d;
}

} // namespace

// The same sweep file makes the same bytes; another seed draws other values; each draw lies in
// its declared range.
TEST(RandomDraws, AreTheSameForTheSameSeedAndSubjectAndOtherwiseDiffer) {
  const std::string vary =
      "  deformation.loads[0].volume_change: {normal: [-0.05, 0.02], within: [-0.12, 0.02]}\n"
      "  deformation.loads[1].volume_change: {log_normal: [0, 0.4], add: -1, within: [-0.5, 1]}\n";
  const fs::path folder = fresh_folder("random-draws");
  write_text_file(folder / "a.yaml", growth_sweep_text(7, vary));
  write_text_file(folder / "b.yaml", growth_sweep_text(7, vary));
  write_text_file(folder / "c.yaml", growth_sweep_text(8, vary));
  const Sweep a = load_sweep(folder / "a.yaml"), b = load_sweep(folder / "b.yaml"),
              c = load_sweep(folder / "c.yaml");
  ASSERT_EQ(a.subjects.size(), 6u);
  std::set<std::string> values;
  for (std::size_t s = 0; s < a.subjects.size(); ++s) {
    EXPECT_EQ(a.subjects[s].scene_text, b.subjects[s].scene_text) << s;
    EXPECT_NE(a.subjects[s].values, c.subjects[s].values) << s;
    const double shrink = std::stod(a.subjects[s].values[0].second);
    const double grow = std::stod(a.subjects[s].values[1].second);
    EXPECT_GE(shrink, -0.12);
    EXPECT_LE(shrink, 0.02);
    EXPECT_GE(grow, -0.5);
    EXPECT_LE(grow, 1.0);
    values.insert(a.subjects[s].values[0].second);
  }
  EXPECT_EQ(values.size(), 6u) << "each subject draws its own value";
}

// 20 000 draws of each declared distribution: the Kolmogorov-Smirnov distance to its CDF is below
// the 1 % critical value (1.63 / sqrt(n)), and a distribution with a 10 % wider spread is
// rejected, so the check tells them apart.
TEST(RandomDraws, FollowTheirDeclaredDistribution) {
  const std::size_t n = 20000;
  const double critical = 1.63 / std::sqrt(static_cast<double>(n));
  RandomDistribution normal = declared("normal", 0.0, 0.10);
  RandomDistribution truncated = declared("normal", -0.02, 0.10);
  truncated.truncated = true;
  truncated.low = -0.15;
  truncated.high = 0.05;
  RandomDistribution ratio = declared("log_normal", 0.0, 0.43);
  ratio.add = -1.0;
  RandomDistribution ratio_within = ratio;
  ratio_within.truncated = true;
  ratio_within.low = -0.5;
  ratio_within.high = 1.0;
  const RandomDistribution uniform = declared("uniform", -1.0, 3.0);
  const RandomDistribution log_uniform = declared("log_uniform", 0.5, 20.0);
  for (const RandomDistribution& d : {normal, truncated, ratio, ratio_within, uniform, log_uniform}) {
    EXPECT_LT(ks_statistic(d, d, n), critical) << d.kind << " " << d.a << " " << d.b << " add " << d.add;
    RandomDistribution wider = d;
    wider.b *= 1.1;
    if (d.kind == "uniform" || d.kind == "log_uniform") wider.b = d.b * 1.1 + 0.1;
    EXPECT_GT(ks_statistic(d, wider, n), critical) << d.kind << ": the check would not see a wrong spread";
  }
  // Moments of the untruncated normal: mean within 3 standard errors, sd within 3 %.
  double sum = 0.0, squares = 0.0;
  for (std::size_t s = 0; s < n; ++s) {
    const double x = draw_value(normal, 11, s, 0);
    sum += x;
    squares += x * x;
  }
  const double mean = sum / n, sd = std::sqrt(squares / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 3.0 * 0.10 / std::sqrt(static_cast<double>(n)));
  EXPECT_NEAR(sd, 0.10, 0.003);
}

// Mistakes in a declared distribution are named at the key with what was expected.
TEST(RandomDraws, MistakesAreNamedAtTheirKey) {
  const fs::path folder = fresh_folder("random-draw-errors");
  const auto message = [&](const std::string& vary) {
    write_text_file(folder / "sweep.yaml", growth_sweep_text(1, vary));
    return input_error_message([&] { load_sweep(folder / "sweep.yaml"); });
  };
  EXPECT_NE(
      message("  deformation.loads[0].volume_change: {normal: [0, 0.1], within: [3, 4]}\n")
          .find("sweep.yaml:6:39: vary.deformation.loads[0].volume_change.within: expected a range holding "
                "at least 1/1000 of the draws"),
      std::string::npos);
  EXPECT_NE(message("  deformation.loads[0].volume_change: {normal: [0, -0.1]}\n")
                .find("vary.deformation.loads[0].volume_change.normal: expected a spread >= 0"),
            std::string::npos);
  EXPECT_NE(message("  deformation.loads[0].volume_change: {normal: [0, 0.1], sd: 2}\n")
                .find("expected add or within beside normal, found 'sd'"),
            std::string::npos);
  EXPECT_NE(message("  deformation.loads[0].volume_change: {uniform: [0, 0.1], within: [0, 1]}\n")
                .find("expected only uniform: [a, b] (add and within go with normal and log_normal)"),
            std::string::npos);
  EXPECT_NE(message("  deformation.loads[0].volume_change: {gamma: [1, 2]}\n")
                .find("expected a list of values or one of {uniform: [a, b]}"),
            std::string::npos);
}
