#include "anatomy/patch_fit.hpp"
#include "anatomy/surface_extraction.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <set>
#include <utility>
#include <vector>

using namespace phantasm;

namespace {

PatchFitReport plain_report(const ImplicitShape& target, const Eigen::Vector3d& radii, int triangles) {
  PatchSurface plain(target_base_mesh(target, triangles, radii, Eigen::Matrix3d::Identity()), "plain");
  return measure_fit(plain, target, 0.05);
}

void expect_fit_beats_plain(const ImplicitShape& target, const Eigen::Vector3d& radii,
                            double max_volume_error, double max_hausdorff_ratio, const char* name) {
  PatchFitOptions options;
  options.base_triangles = 320;
  PatchFitReport fitted;
  const PatchSurface surface =
      fit_patch_surface(target, radii, Eigen::Matrix3d::Identity(), options, name, &fitted);
  const PatchFitReport plain = plain_report(target, radii, 320);
  std::printf("%s: plain Hausdorff %.4g mm volume error %.3g %%; fitted Hausdorff %.4g mm mean %.3g mm "
              "volume error %.3g %% "
              "(offset factor %.3f)\n",
              name, plain.hausdorff_mm, 100 * plain.volume_error, fitted.hausdorff_mm,
              fitted.mean_distance_mm, 100 * fitted.volume_error, fitted.vertex_offset_factor);
  EXPECT_EQ(surface.patch_count(), 320);
  EXPECT_LT(std::abs(fitted.volume_error), max_volume_error) << name;
  EXPECT_LE(fitted.hausdorff_mm, max_hausdorff_ratio * plain.hausdorff_mm) << name;
}

} // namespace

TEST(PatchFit, FittedSphereOn320TrianglesHasUnderOneThousandthVolumeErrorAndHalfThePlainHausdorff) {
  const auto sphere = make_ellipsoid({1, 2, 3}, {50, 50, 50}, Eigen::Matrix3d::Identity());
  expect_fit_beats_plain(*sphere, {50, 50, 50}, 1e-3, 0.5, "sphere");
}

// Anisotropic curvature leaves larger chord errors along some edges than the per-vertex offset
// can balance: measured ratios are 0.55 (ellipsoid) and 0.50 (superquadric), bounded at 0.6.
TEST(PatchFit,
     FittedEllipsoidOn320TrianglesHasUnderOneThousandthVolumeErrorAndUnder60PercentOfThePlainHausdorff) {
  const auto ellipsoid = make_ellipsoid({0, 0, 0}, {60, 45, 30}, Eigen::Matrix3d::Identity());
  expect_fit_beats_plain(*ellipsoid, {60, 45, 30}, 1e-3, 0.6, "ellipsoid");
}

TEST(PatchFit,
     FittedSuperquadricOn320TrianglesHasUnderOneThousandthVolumeErrorAndUnder60PercentOfThePlainHausdorff) {
  const auto superquadric = make_superquadric({0, 0, 0}, {40, 30, 25}, 0.8, 0.9, Eigen::Matrix3d::Identity());
  expect_fit_beats_plain(*superquadric, {40, 30, 25}, 1e-3, 0.6, "superquadric");
}

TEST(PatchFit, FitErrorFallsWithBaseMeshSize) {
  // The anatomy's speed/accuracy trade: base triangles against Hausdorff distance.
  const auto ellipsoid = make_ellipsoid({0, 0, 0}, {60, 45, 30}, Eigen::Matrix3d::Identity());
  double previous = 1e9;
  for (int triangles : {20, 80, 320}) {
    PatchFitOptions options;
    options.base_triangles = triangles;
    PatchFitReport report;
    fit_patch_surface(*ellipsoid, {60, 45, 30}, Eigen::Matrix3d::Identity(), options, "ellipsoid", &report);
    const PatchFitReport plain = plain_report(*ellipsoid, {60, 45, 30}, triangles);
    std::printf(
        "%5d base triangles: fitted Hausdorff %.3f mm (plain %.3f mm), mean %.3f mm, volume error %.2e\n",
        triangles, report.hausdorff_mm, plain.hausdorff_mm, report.mean_distance_mm, report.volume_error);
    EXPECT_EQ(report.base_triangles, triangles);
    EXPECT_LT(report.hausdorff_mm, previous);
    EXPECT_LT(report.hausdorff_mm, plain.hausdorff_mm);
    previous = report.hausdorff_mm;
  }
}

namespace {

/// V - E + F of a closed triangle mesh (2 - 2 genus per component).
long euler_characteristic(const TriangleMesh& mesh) {
  std::set<std::pair<int, int>> edges;
  for (Eigen::Index t = 0; t < mesh.face_count(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.faces(t, k), b = mesh.faces(t, (k + 1) % 3);
      edges.emplace(std::min(a, b), std::max(a, b));
    }
  }
  return static_cast<long>(mesh.vertex_count()) - static_cast<long>(edges.size()) +
         static_cast<long>(mesh.face_count());
}

/// Fits a target on the extracted-surface base mesh at several sizes; returns the log-log slope
/// of the fitted Hausdorff distance against the mean base edge (least squares over the sizes).
double hausdorff_order(const ImplicitShape& target, const std::vector<int>& sizes, const char* name) {
  std::vector<double> log_edge, log_hausdorff;
  for (int triangles : sizes) {
    PatchFitOptions options;
    options.base_triangles = triangles;
    PatchFitReport report;
    const PatchSurface surface = fit_patch_surface(target, Eigen::Vector3d::Ones(),
                                                   Eigen::Matrix3d::Identity(), options, name, &report);
    const double edge = mean_edge_length(surface.base_mesh());
    std::printf("%s, %5d patches (edge %.2f mm): fitted Hausdorff %.4f mm, mean %.5f mm, volume error %.2e\n",
                name, report.base_triangles, edge, report.hausdorff_mm, report.mean_distance_mm,
                report.volume_error);
    EXPECT_LT(std::abs(report.volume_error), 1e-9) << name << " " << triangles;
    log_edge.push_back(std::log(edge));
    log_hausdorff.push_back(std::log(report.hausdorff_mm));
  }
  const Eigen::Index n = static_cast<Eigen::Index>(sizes.size());
  const Eigen::Map<const Eigen::VectorXd> x(log_edge.data(), n), y(log_hausdorff.data(), n);
  const Eigen::VectorXd xc = x.array() - x.mean(), yc = y.array() - y.mean();
  const double order = xc.dot(yc) / xc.dot(xc);
  std::printf("%s: Hausdorff order %.2f in the base edge length\n", name, order);
  return order;
}

} // namespace

// Shapes rays from a centre cannot sample, on base meshes extracted from their own surfaces: the
// fitted error falls at least as edge^1.5 (measured orders are printed) over three sizes, each
// twice the patches of the one before. Measured with a fourth, finer size (twice the time of the
// three): torus 1.88, folded spheroid 1.88, horseshoe 1.84; over the three: 2.0, 2.1, 1.7. The
// folded spheroid's finer pair alone (404 and 842 patches) gives 1.71, above the bound too.
TEST(PatchFit, TorusFitConvergesWithOrderAtLeastOneAndAHalf) {
  const auto torus = make_torus({0, 0, 0}, 30, 10);
  EXPECT_GE(hausdorff_order(*torus, {160, 320, 640}, "torus"), 1.5);
}

TEST(PatchFit, FoldedSpheroidFitConvergesWithOrderAtLeastOneAndAHalf) {
  const auto folded = make_folded_spheroid(40, 0.3, 5, 30, 0.04);
  EXPECT_GE(hausdorff_order(*folded, {160, 320, 640}, "folded spheroid"), 1.5);
}

TEST(PatchFit, HorseshoeFitConvergesWithOrderAtLeastOneAndAHalf) {
  const auto horseshoe = make_horseshoe(30, 8);
  EXPECT_GE(hausdorff_order(*horseshoe, {160, 320, 640}, "horseshoe"), 1.5);
}

TEST(PatchFit, AFittedTorusKeepsItsGenusAndVolumeAndBeatsThePlainMesh) {
  const auto torus = make_torus({0, 0, 0}, 30, 10);
  PatchFitOptions options;
  options.base_triangles = 320;
  PatchFitReport fitted;
  const PatchSurface surface = fit_patch_surface(*torus, Eigen::Vector3d::Ones(), Eigen::Matrix3d::Identity(),
                                                 options, "torus", &fitted);
  const PatchSurface plain(surface_base_mesh(*torus, 320, 0), "plain");
  const double edge = mean_edge_length(plain.base_mesh());
  const PatchFitReport plain_fit = measure_fit(plain, *torus, 0.1 * edge * edge / 40.0, 5);
  std::printf("torus, %ld patches: plain Hausdorff %.3f mm; fitted Hausdorff %.3f mm, mean %.4f mm, volume "
              "error %.2e\n",
              static_cast<long>(surface.patch_count()), plain_fit.hausdorff_mm, fitted.hausdorff_mm,
              fitted.mean_distance_mm, fitted.volume_error);
  EXPECT_EQ(euler_characteristic(surface.base_mesh()), 0);
  EXPECT_LT(std::abs(fitted.volume_error), 1e-9);
  // Straight chords around the 10 mm tube bound both (edges of about 11 mm sag 1.6 mm).
  EXPECT_LT(fitted.hausdorff_mm, plain_fit.hausdorff_mm);
  EXPECT_LT(fitted.mean_distance_mm, plain_fit.mean_distance_mm);
}

TEST(PatchFit, AThreeMillimetreShellFitsAsTwoClosedManifoldWalls) {
  const auto shell = make_ellipsoid_shell({40, 30, 25}, 3.0);
  PatchFitOptions options;
  options.base_triangles = 1280;
  PatchFitReport fitted;
  const PatchSurface surface = fit_patch_surface(*shell, Eigen::Vector3d::Ones(), Eigen::Matrix3d::Identity(),
                                                 options, "shell", &fitted);
  std::printf("shell, %ld patches: fitted Hausdorff %.3f mm, mean %.4f mm, volume error %.2e\n",
              static_cast<long>(surface.patch_count()), fitted.hausdorff_mm, fitted.mean_distance_mm,
              fitted.volume_error);
  EXPECT_NO_THROW(check_closed_manifold(surface.base_mesh(), "shell"));
  EXPECT_EQ(euler_characteristic(surface.base_mesh()), 4); // two spheres
  EXPECT_LT(std::abs(fitted.volume_error), 1e-9);
  EXPECT_LT(fitted.hausdorff_mm, 1.0);
}

// The fit report samples small patches more sparsely (measure_fit's surface_sample_level), about
// every millimetre: on a torus of many small patches the sparser report measures the same fit as
// 16 samples per edge (the Hausdorff from the target's side is the same; the surface's side is
// sampled on a subset of the same points, so its figures can only be as large or smaller, and
// close), with a sixteenth of the distance queries.
TEST(PatchFit, SparserSurfaceSamplesOfSmallPatchesMeasureTheSameFit) {
  const auto torus = make_torus({0, 0, 0}, 30.0, 10.0);
  PatchFitOptions options;
  options.base_triangles = 2000;
  const PatchSurface surface =
      fit_patch_surface(*torus, Eigen::Vector3d::Ones(), Eigen::Matrix3d::Identity(), options, "torus");
  const double edge = mean_edge_length(surface.base_mesh());
  // Edges of about 3 mm: 4 segments give 0.75 mm at 1 mm spacing, 2 give 1.5 mm at 2 mm spacing.
  ASSERT_GT(edge, 2.0);
  ASSERT_LT(edge, 4.0);
  EXPECT_EQ(surface_sample_level_for_spacing(surface, 1.0), 2);
  EXPECT_EQ(surface_sample_level_for_spacing(surface, 2.0), 1);
  EXPECT_EQ(surface_sample_level_for_spacing(surface, 0.01), 4); // never finer than level 4
  const PatchFitReport dense = measure_fit(surface, *torus, 0.1, 4, 4);
  const PatchFitReport sparse = measure_fit(surface, *torus, 0.1, 4, 2);
  std::printf("torus, %lld patches: Hausdorff %.4g / %.4g mm, mean %.4g / %.4g mm (level 4 / 2)\n",
              static_cast<long long>(surface.patch_count()), dense.hausdorff_mm, sparse.hausdorff_mm,
              dense.mean_distance_mm, sparse.mean_distance_mm);
  // The level is used: the sparser samples are a subset, so the means differ.
  EXPECT_NE(sparse.mean_distance_mm, dense.mean_distance_mm);
  EXPECT_LE(sparse.hausdorff_mm, dense.hausdorff_mm + 1e-12);
  EXPECT_GT(sparse.hausdorff_mm, 0.8 * dense.hausdorff_mm);
  EXPECT_NEAR(sparse.mean_distance_mm, dense.mean_distance_mm, 0.2 * dense.mean_distance_mm);
  EXPECT_EQ(sparse.volume_error, dense.volume_error);
}
