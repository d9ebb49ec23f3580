#include "sim/surface_constraints.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>

namespace phantasm {
namespace {

/// A unit vector perpendicular to u (|u| = 1).
Eigen::Vector3d perpendicular(const Eigen::Vector3d& u) {
  const Eigen::Vector3d axis = std::abs(u.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return u.cross(axis).normalized();
}

double cotangent(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double sine = a.cross(b).norm();
  return sine > 0.0 ? a.dot(b) / sine : 0.0;
}

/// P for a vector: its direction (or `fallback` where it vanishes) with the length clamped to
/// reference * [min, max].
Eigen::Vector3d clamp_length(const Eigen::Vector3d& f, double reference, const SingularValueRange& range,
                             const Eigen::Vector3d& fallback) {
  const double length = f.norm();
  const Eigen::Vector3d direction = length > 0.0 ? Eigen::Vector3d(f / length) : fallback;
  const double target = std::clamp(length, reference * range.min, reference * range.max);
  return target * direction;
}

/// The SVD of a 3x2 matrix, F = s1 u1 v1^T + s2 u2 v2^T (s1 >= s2 >= 0), from the closed-form
/// eigen-decomposition of F^T F. Where a singular value vanishes its left vector is any unit
/// vector perpendicular to the other, so targets built from it stay in their sets.
struct ThinSvd {
  Eigen::Vector3d u1, u2;
  Eigen::Vector2d v1, v2, s;
};

ThinSvd thin_svd(const SurfaceMatrix& F) {
  const Eigen::Matrix2d C = F.transpose() * F;
  const double half_trace = 0.5 * (C(0, 0) + C(1, 1));
  const double half_difference = 0.5 * (C(0, 0) - C(1, 1));
  const double radius = std::hypot(half_difference, C(0, 1));
  // Eigenvector of the larger eigenvalue: (cos t, sin t) with tan 2t = 2 C01 / (C00 - C11).
  const double angle = 0.5 * std::atan2(C(0, 1), half_difference);
  ThinSvd svd;
  svd.v1 = Eigen::Vector2d(std::cos(angle), std::sin(angle));
  svd.v2 = Eigen::Vector2d(-svd.v1.y(), svd.v1.x());
  svd.s = Eigen::Vector2d(std::sqrt(std::max(half_trace + radius, 0.0)),
                          std::sqrt(std::max(half_trace - radius, 0.0)));
  svd.u1 = svd.s[0] > 0.0 ? Eigen::Vector3d(F * svd.v1 / svd.s[0]) : Eigen::Vector3d::UnitX();
  svd.u2 = svd.s[1] > 1e-8 * svd.s[0] ? Eigen::Vector3d(F * svd.v2 / svd.s[1]) : perpendicular(svd.u1);
  return svd;
}

SurfaceMatrix compose(const ThinSvd& svd, const Eigen::Vector2d& values) {
  return values[0] * svd.u1 * svd.v1.transpose() + values[1] * svd.u2 * svd.v2.transpose();
}

} // namespace

SurfaceMatrix surface_deformation(const SurfaceElement& e, const Eigen::MatrixX3d& p) {
  SurfaceMatrix F = SurfaceMatrix::Zero();
  for (int k = 0; k < e.count; ++k)
    F.noalias() += p.row(e.vertices[static_cast<std::size_t>(k)]).transpose() * e.Q.row(k);
  return F;
}

SurfaceMatrix project_surface(const SurfaceElement& e, const SurfaceMatrix& F) {
  SurfaceMatrix T = SurfaceMatrix::Zero();
  switch (e.kind) {
  case SurfaceConstraintKind::edge_strain: T.col(0) = clamp_length(F.col(0), 1.0, e.range, e.rest); break;
  case SurfaceConstraintKind::triangle_strain: {
    const ThinSvd svd = thin_svd(F);
    T = compose(svd, svd.s.cwiseMax(e.range.min).cwiseMin(e.range.max));
    break;
  }
  case SurfaceConstraintKind::triangle_area: {
    const ThinSvd svd = thin_svd(F);
    T = compose(svd, project_area(svd.s, e.range));
    break;
  }
  case SurfaceConstraintKind::bending: {
    const double rest_length = e.rest.norm();
    if (rest_length > 0.0) T.col(0) = clamp_length(F.col(0), rest_length, e.range, e.rest / rest_length);
    break; // a flat rest state: the target is e = 0
  }
  }
  return T;
}

SurfaceElement edge_strain_element(int i, int j, const Eigen::MatrixX3d& rest_m, double stiffness,
                                   const SingularValueRange& range) {
  const Eigen::Vector3d d = (rest_m.row(j) - rest_m.row(i)).transpose();
  const double length = d.norm();
  if (!(length > 0.0)) throw std::invalid_argument("edge strain: the rest edge has zero length");
  SurfaceElement e;
  e.kind = SurfaceConstraintKind::edge_strain;
  e.vertices = {i, j, 0, 0};
  e.count = 2;
  e.columns = 1;
  e.Q(0, 0) = -1.0 / length;
  e.Q(1, 0) = 1.0 / length;
  e.weight = stiffness * length;
  e.range = range;
  e.rest = d / length;
  return e;
}

SurfaceElement triangle_strain_element(const std::array<int, 3>& v, const Eigen::MatrixX3d& rest_m,
                                       double mu_thickness, const SingularValueRange& range) {
  const Eigen::Vector3d x0 = rest_m.row(v[0]).transpose();
  const Eigen::Vector3d e1 = rest_m.row(v[1]).transpose() - x0, e2 = rest_m.row(v[2]).transpose() - x0;
  const Eigen::Vector3d normal = e1.cross(e2);
  const double area = 0.5 * normal.norm();
  if (!(area > 1e-12 * e1.squaredNorm()))
    throw std::invalid_argument("triangle strain: degenerate rest triangle");
  // An orthonormal frame of the rest plane; Dm the rest edges in it.
  const Eigen::Vector3d a = e1.normalized(), b = normal.normalized().cross(a);
  Eigen::Matrix2d Dm;
  Dm << e1.dot(a), e2.dot(a), e1.dot(b), e2.dot(b);
  const Eigen::Matrix2d inverse = Dm.inverse();
  SurfaceElement e;
  e.kind = SurfaceConstraintKind::triangle_strain;
  e.vertices = {v[0], v[1], v[2], 0};
  e.count = 3;
  e.columns = 2;
  // F = [x1 - x0, x2 - x0] Dm^-1 = X Q with Q = [-1 -1; 1 0; 0 1] Dm^-1.
  e.Q.row(0) = -inverse.row(0) - inverse.row(1);
  e.Q.row(1) = inverse.row(0);
  e.Q.row(2) = inverse.row(1);
  e.weight = 2.0 * mu_thickness * area;
  e.range = range;
  return e;
}

SurfaceElement triangle_area_element(const std::array<int, 3>& v, const Eigen::MatrixX3d& rest_m,
                                     double weight, const SingularValueRange& range) {
  SurfaceElement e = triangle_strain_element(v, rest_m, 1.0, range);
  e.kind = SurfaceConstraintKind::triangle_area;
  e.weight = weight;
  return e;
}

SurfaceElement bending_element(const std::array<int, 4>& v, const Eigen::MatrixX3d& rest_m, double stiffness,
                               const SingularValueRange& range) {
  Eigen::Vector3d x[4];
  for (int k = 0; k < 4; ++k)
    x[k] = rest_m.row(v[static_cast<std::size_t>(k)]).transpose();
  // Bergou et al. 2006: e0 = x1 - x0, e1 = x2 - x0, e2 = x3 - x0, e3 = x2 - x1, e4 = x3 - x1;
  // K = [c03 + c04, c01 + c02, -c01 - c03, -c02 - c04] with c_jk = cot of the angle between
  // e_j and e_k.
  const Eigen::Vector3d e0 = x[1] - x[0], e1 = x[2] - x[0], e2 = x[3] - x[0], e3 = x[2] - x[1],
                        e4 = x[3] - x[1];
  const double c01 = cotangent(e0, e1), c02 = cotangent(e0, e2), c03 = cotangent(-e0, e3),
               c04 = cotangent(-e0, e4);
  const double areas = 0.5 * (e0.cross(e1).norm() + e0.cross(e2).norm());
  if (!(areas > 0.0)) throw std::invalid_argument("bending: degenerate rest triangles");
  const double scale = std::sqrt(3.0 / areas);
  SurfaceElement e;
  e.kind = SurfaceConstraintKind::bending;
  e.vertices = v;
  e.count = 4;
  e.columns = 1;
  e.Q.col(0) << scale * (c03 + c04), scale * (c01 + c02), -scale * (c01 + c03), -scale * (c02 + c04);
  e.weight = stiffness;
  e.range = range;
  for (int k = 0; k < 4; ++k)
    e.rest += e.Q(k, 0) * x[k];
  return e;
}

} // namespace phantasm
