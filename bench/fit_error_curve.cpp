// Fit error against base mesh size: the 60 x 45 x 30 mm ellipsoid of the README's table, plain
// base mesh against fitted patches, as CSV (for scripts/accuracy_plots.py).
// Usage: fit_error_curve

#include "anatomy/patch_fit.hpp"

#include <chrono>
#include <cstdio>

int main() {
  using namespace phantasm;
  const Eigen::Vector3d radii(60, 45, 30);
  const auto ellipsoid = make_ellipsoid({0, 0, 0}, radii, Eigen::Matrix3d::Identity());
  std::printf("base_triangles,plain_hausdorff_mm,fitted_hausdorff_mm,fitted_volume_error,fit_seconds\n");
  for (int triangles : {20, 80, 320, 1280}) {
    PatchFitOptions options;
    options.base_triangles = triangles;
    PatchFitReport fitted;
    const auto start = std::chrono::steady_clock::now();
    fit_patch_surface(*ellipsoid, radii, Eigen::Matrix3d::Identity(), options, "ellipsoid", &fitted);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const PatchSurface plain(target_base_mesh(*ellipsoid, triangles, radii, Eigen::Matrix3d::Identity()),
                             "plain");
    const PatchFitReport plain_fit = measure_fit(plain, *ellipsoid, 0.05);
    std::printf("%d,%.4f,%.4f,%.3g,%.3f\n", triangles, plain_fit.hausdorff_mm, fitted.hausdorff_mm,
                fitted.volume_error, seconds);
    std::fflush(stdout);
  }
  return 0;
}
