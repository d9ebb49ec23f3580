// The patch fit's height search (anatomy/height_search.hpp): the crossing nearest the base point
// within the limit, and the same heights, bit for bit, whether a patch's searches run one after
// another or interleaved (each fed one value per round).

#include "anatomy/height_search.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

using namespace phantasm;

namespace {

/// A folded target: positive inside, |gradient| <= sqrt(3^2 + 2^2 + 2.5^2) < 4.4.
double folded(const Eigen::Vector3d& x) {
  return std::sin(3.0 * x.x()) * std::cos(2.0 * x.y()) + 0.5 * std::sin(5.0 * x.z()) - 0.2;
}
constexpr double k_folded_slope = 4.4;

std::uint64_t bits_of(double x) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &x, sizeof x);
  return bits;
}

/// A target whose value along the line from the origin along z is (h - low)(high - h): positive
/// between its two crossings, slope at most |high - low| + 2 max(|low|, |high|) within +-1.
struct TwoCrossings {
  double low, high;
  double operator()(const Eigen::Vector3d& x) const { return (x.z() - low) * (high - x.z()); }
  double slope() const { return std::abs(high - low) + 2.0 * std::max(std::abs(low), std::abs(high)) + 2.0; }
};

double search_along_z(const TwoCrossings& target, double limit) {
  return height_search(target, target.slope(), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), limit);
}

} // namespace

TEST(HeightSearch, FindsTheFirstCrossingSteppingOutwardUpThenDown) {
  EXPECT_NEAR(search_along_z({-0.5, 0.3}, 1.0), 0.3, 1e-10);
  EXPECT_NEAR(search_along_z({-0.2, 0.7}, 1.0), -0.2, 1e-10);
  // The steps are 1/32 of the limit: below wins when its crossing lies a step nearer...
  EXPECT_NEAR(search_along_z({-0.31, 0.32}, 1.0), -0.31, 1e-10);
  // ...and above when both lie between the same two steps (0.28125 and 0.3125).
  EXPECT_NEAR(search_along_z({-0.30, 0.31}, 1.0), 0.31, 1e-10);
  // Within the first step.
  EXPECT_NEAR(search_along_z({-0.9, 0.0101}, 1.0), 0.0101, 1e-10);
}

TEST(HeightSearch, IsNotANumberWithoutACrossingWithinTheLimitAndZeroOnTheSurface) {
  EXPECT_TRUE(std::isnan(search_along_z({-2.0, 2.0}, 1.0)));
  EXPECT_TRUE(std::isnan(search_along_z({-0.5, 0.3}, 0.25)));
  EXPECT_EQ(search_along_z({0.0, 0.5}, 1.0), 0.0);
}

TEST(HeightSearch, TheHeightFoundIsOnTheSurface) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-2.0, 2.0);
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  int found = 0;
  for (int k = 0; k < 2000; ++k) {
    const Eigen::Vector3d b(coordinate(random), coordinate(random), coordinate(random));
    const double h = height_search(folded, k_folded_slope, b, n, 0.4);
    if (std::isnan(h)) continue;
    ++found;
    ASSERT_LE(std::abs(h), 0.4);
    EXPECT_NEAR(folded(b + h * n), 0.0, 1e-9) << "base " << b.transpose() << ", height " << h;
    // Every step nearer the base point, on both sides, has the base point's sign: the steps the
    // slope bound let the search skip as well as those it evaluated.
    const double base_sign = folded(b) > 0.0 ? 1.0 : -1.0;
    for (int step = 1; 0.4 * step / 32 < std::abs(h); ++step)
      for (const double side : {1.0, -1.0})
        ASSERT_GT(base_sign * folded(b + side * (0.4 * step / 32) * n), 0.0)
            << "base " << b.transpose() << ", step " << side * step << ", height " << h;
  }
  EXPECT_GT(found, 500);
}

TEST(HeightSearch, InterleavedSearchesGiveTheHeightsOfOneSearchAfterAnother) {
  // Searches of very different lengths (no crossing, one at the base point's step, crossings
  // refined over many rounds), so that the interleaved rounds drop searches at different times.
  std::mt19937 random(11);
  std::uniform_real_distribution<double> coordinate(-2.0, 2.0);
  std::vector<Eigen::Vector3d> bases(3000);
  for (Eigen::Vector3d& b : bases)
    b = Eigen::Vector3d(coordinate(random), coordinate(random), coordinate(random));
  const Eigen::Vector3d n = Eigen::Vector3d(-0.6, 0.2, 0.7).normalized();
  for (const double limit : {0.05, 0.3, 1.0}) {
    std::vector<HeightSearch> searches;
    std::vector<std::uint32_t> running;
    std::vector<double> values, heights;
    int evaluations = 0;
    const auto counted = [&evaluations](const Eigen::Vector3d& x) {
      ++evaluations;
      return folded(x);
    };
    height_searches(counted, k_folded_slope, bases, n, limit, searches, running, values, heights);
    const int interleaved = evaluations;
    evaluations = 0;
    ASSERT_EQ(heights.size(), bases.size());
    int none = 0;
    for (std::size_t k = 0; k < bases.size(); ++k) {
      const double alone = height_search(counted, k_folded_slope, bases[k], n, limit);
      EXPECT_EQ(bits_of(heights[k]), bits_of(alone)) << "search " << k << ", limit " << limit;
      none += std::isnan(alone) ? 1 : 0;
    }
    // The same values asked for, none twice, none skipped.
    EXPECT_EQ(interleaved, evaluations) << "limit " << limit;
    EXPECT_GT(none, 0);
    EXPECT_LT(none, static_cast<int>(bases.size()));
  }
}

TEST(HeightSearch, InterleavedSearchesReuseTheirWorkSpace) {
  // The fit keeps the vectors from one patch to the next: a smaller second call must not see the
  // first one's searches.
  std::vector<HeightSearch> searches;
  std::vector<std::uint32_t> running;
  std::vector<double> values, heights;
  const Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
  std::vector<Eigen::Vector3d> many(50, Eigen::Vector3d(0.1, 0.2, 0.3));
  height_searches(folded, k_folded_slope, many, n, 1.0, searches, running, values, heights);
  const std::vector<Eigen::Vector3d> few = {Eigen::Vector3d(-1.0, 0.5, 0.0), Eigen::Vector3d(0.4, -0.3, 1.2)};
  height_searches(folded, k_folded_slope, few, n, 1.0, searches, running, values, heights);
  ASSERT_EQ(heights.size(), few.size());
  for (std::size_t k = 0; k < few.size(); ++k)
    EXPECT_EQ(bits_of(heights[k]), bits_of(height_search(folded, k_folded_slope, few[k], n, 1.0)));
}
