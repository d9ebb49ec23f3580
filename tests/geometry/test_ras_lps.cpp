// RAS <-> LPS: x and y negate, z stays, for points, matrices and component-major arrays; every
// conversion undoes itself.
#include "geometry/ras_lps.hpp"

#include <gtest/gtest.h>

using namespace phantasm;

TEST(RasLps, PointsAndVectorsRoundTrip) {
  const Eigen::Vector3d ras(12.5, -3.25, 40.0);
  EXPECT_EQ(lps_from_ras(ras), Eigen::Vector3d(-12.5, 3.25, 40.0));
  EXPECT_EQ(ras_from_lps(lps_from_ras(ras)), ras);
  EXPECT_EQ(lps_from_ras(ras_from_lps(ras)), ras);
  EXPECT_EQ(Eigen::Vector3d(ras_lps_flip() * ras), lps_from_ras(ras));
  const Eigen::Matrix3d m = Eigen::Matrix3d::Random();
  EXPECT_EQ(Eigen::Matrix3d(ras_lps_flip() * (ras_lps_flip() * m)), m);
}

TEST(RasLps, ComponentArraysRoundTrip) {
  // Two voxels, component-major: x0 x1 y0 y1 z0 z1.
  const std::vector<float> ras = {1.0f, -2.0f, 3.0f, -4.0f, 5.0f, -6.0f};
  const std::vector<float> lps = lps_from_ras_components(ras);
  EXPECT_EQ(lps, (std::vector<float>{-1.0f, 2.0f, -3.0f, 4.0f, 5.0f, -6.0f}));
  std::vector<float> back = lps;
  flip_ras_lps_components(back);
  EXPECT_EQ(back, ras);
}
