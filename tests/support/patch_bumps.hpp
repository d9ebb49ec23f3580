// Round bumps placed in the triangles of a patch base mesh, for tests that need patch surfaces
// with bumps of known size.
#pragma once

#include "anatomy/patch_surface.hpp"
#include "geometry/triangle_mesh.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <random>
#include <vector>

namespace phantasm::testing {

/// A round bump in triangle t of `base`: centred at `center_uv` (affine coordinates over the
/// triangle's edges), of radius `fraction` times the triangle's inscribed circle's, `amplitude_mm`
/// high (< 0: inward).
inline PatchBump disc_in_triangle(const TriangleMesh& base, Eigen::Index t, const Eigen::Vector2d& center_uv,
                                  double fraction, double amplitude_mm) {
  const Eigen::Vector3d a = base.vertex(base.faces(t, 0)), e1 = base.vertex(base.faces(t, 1)) - a,
                        e2 = base.vertex(base.faces(t, 2)) - a;
  Eigen::Matrix2d metric;
  metric << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
  const double inradius = e1.cross(e2).norm() / (e1.norm() + e2.norm() + (e2 - e1).norm());
  PatchBump bump = PatchBump::disc(center_uv, fraction * inradius, metric);
  bump.amplitude_mm = amplitude_mm;
  return bump;
}

/// `count` random bumps centred anywhere in the triangle (some at its edges and corners), of any
/// orientation, round and elongated: the eigenvalues of S from `smallest` to `smallest` x `span`
/// (log-uniform), the amplitudes from `lowest` to `highest` mm.
inline std::vector<PatchBump> random_bumps(std::mt19937& random, int count, double smallest, double span,
                                           double lowest, double highest) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<PatchBump> bumps(static_cast<std::size_t>(count));
  for (PatchBump& b : bumps) {
    double u = unit(random), v = unit(random);
    if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
    b.center_uv = {u, v};
    const Eigen::Matrix2d R = Eigen::Rotation2Dd(M_PI * unit(random)).toRotationMatrix();
    const Eigen::Vector2d eigenvalues(smallest * std::pow(span, unit(random)),
                                      smallest * std::pow(span, unit(random)));
    b.shape_uv = R * eigenvalues.asDiagonal() * R.transpose();
    b.amplitude_mm = lowest + (highest - lowest) * unit(random);
  }
  return bumps;
}

/// A disc of the fitting basis of anatomy/patch_fit: centred on a sub-triangle of the triangle cut
/// into `subdivisions`^2, whose incircle is 1 / `subdivisions` of the triangle's.
struct BasisDisc {
  Eigen::Vector2d center_uv;
  int subdivisions = 1;
};

/// The fitting basis's discs of levels 0 to `last_level` (2^level subdivisions), sub-triangle by
/// sub-triangle: levels 0-2 give 21 nested discs.
inline std::vector<BasisDisc> fitting_basis_discs(int last_level) {
  std::vector<BasisDisc> discs;
  for (int level = 0; level <= last_level; ++level) {
    const int n = 1 << level;
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i + j < n; ++i) {
        const Eigen::Vector2d p(double(i) / n, double(j) / n);
        discs.push_back({p + Eigen::Vector2d(1.0, 1.0) / (3.0 * n), n});
        if (i + j < n - 1) discs.push_back({p + Eigen::Vector2d(2.0, 2.0) / (3.0 * n), n});
      }
    }
  }
  return discs;
}

} // namespace phantasm::testing
