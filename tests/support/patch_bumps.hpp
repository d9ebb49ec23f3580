// Round bumps placed in the triangles of a patch base mesh, for tests that need patch surfaces
// with bumps of known size.
#pragma once

#include "anatomy/patch_surface.hpp"
#include "anatomy/triangle_mesh.hpp"

#include <Eigen/Geometry>

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

} // namespace phantasm::testing
