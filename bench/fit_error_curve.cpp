// Fit error against base mesh size, as CSV (for scripts/accuracy_plots.py): the 60 x 45 x 30 mm
// ellipsoid of docs/performance.md's table on both base meshes (icosphere cast from the centre, the
// default for star shapes, and the extracted surface), and shapes rays from a centre cannot
// sample on the extracted surface: a torus (R 30, r 10 mm, genus 1), a folded spheroid (spiral
// folds rays from its centre cross up to three times) and a horseshoe (a bent capsule).
// Plain is the base mesh as it comes (vertices on the target), fitted the patch surface.
// Usage: fit_error_curve [shape [quick]]   (only that shape's rows; quick: without the largest base
// mesh of each case, for the test of the plotting command)

#include "anatomy/patch_fit.hpp"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <vector>

int main(int argc, char** argv) {
  using namespace phantasm;
  struct Case {
    const char* name;
    std::unique_ptr<ImplicitShape> shape;
    Eigen::Vector3d radii;
    BaseMeshSource source;
    std::vector<int> sizes;
  };
  const Eigen::Vector3d radii(60, 45, 30);
  std::vector<Case> cases;
  cases.push_back({"ellipsoid",
                   make_ellipsoid({0, 0, 0}, radii, Eigen::Matrix3d::Identity()),
                   radii,
                   BaseMeshSource::icosphere,
                   {20, 80, 320, 1280}});
  cases.push_back({"ellipsoid",
                   make_ellipsoid({0, 0, 0}, radii, Eigen::Matrix3d::Identity()),
                   radii,
                   BaseMeshSource::surface,
                   {80, 320, 1280}});
  cases.push_back({"torus",
                   make_torus({0, 0, 0}, 30, 10),
                   Eigen::Vector3d::Ones(),
                   BaseMeshSource::surface,
                   {160, 320, 640, 1280}});
  cases.push_back({"folded_spheroid",
                   make_folded_spheroid(40, 0.3, 5, 30, 0.04),
                   Eigen::Vector3d::Ones(),
                   BaseMeshSource::surface,
                   {320, 640, 1280, 2560}});
  cases.push_back({"horseshoe",
                   make_horseshoe(30, 8),
                   Eigen::Vector3d::Ones(),
                   BaseMeshSource::surface,
                   {160, 320, 640, 1280}});
  std::printf(
      "shape,base_mesh,base_triangles,mean_edge_mm,plain_hausdorff_mm,fitted_hausdorff_mm,fitted_mean_mm,"
      "fitted_volume_error,fit_seconds\n");
  for (const Case& c : cases) {
    if (argc > 1 && std::strcmp(argv[1], c.name) != 0) continue;
    const bool quick = argc > 2 && std::strcmp(argv[2], "quick") == 0;
    for (std::size_t size = 0; size + (quick ? 1 : 0) < c.sizes.size(); ++size) {
      const int triangles = c.sizes[size];
      PatchFitOptions options;
      options.base_triangles = triangles;
      options.base_mesh = c.source;
      PatchFitReport fitted;
      const auto start = std::chrono::steady_clock::now();
      const PatchSurface surface =
          fit_patch_surface(*c.shape, c.radii, Eigen::Matrix3d::Identity(), options, c.name, &fitted);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const PatchSurface plain(fit_base_mesh(*c.shape, options, c.radii, Eigen::Matrix3d::Identity()),
                               "plain");
      // The plain mesh's patches are flat: any tessellation tolerance is exact for them.
      const PatchFitReport plain_fit = c.source == BaseMeshSource::icosphere
                                           ? measure_fit(plain, *c.shape, 0.05)
                                           : measure_fit(plain, *c.shape, 0.05, 5);
      std::printf("%s,%s,%d,%.3f,%.4f,%.4f,%.4f,%.3g,%.3f\n", c.name,
                  c.source == BaseMeshSource::icosphere ? "icosphere" : "surface", fitted.base_triangles,
                  mean_edge_length(surface.base_mesh()), plain_fit.hausdorff_mm, fitted.hausdorff_mm,
                  fitted.mean_distance_mm, fitted.volume_error, seconds);
      std::fflush(stdout);
    }
  }
  return 0;
}
