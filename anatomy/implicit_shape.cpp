#include "anatomy/implicit_shape.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <limits>

namespace phantasm {

double ImplicitShape::slope_bound(const Eigen::Vector3d& /*direction*/) const {
  return std::numeric_limits<double>::infinity();
}

Eigen::Vector3d ImplicitShape::ray_from_center(const Eigen::Vector3d& direction) const {
  const Eigen::Vector3d c = center();
  double inside = 0.0, outside = 1.01 * bounding_radius();
  for (int i = 0; i < 200 && outside - inside > 1e-12; ++i) {
    const double middle = 0.5 * (inside + outside);
    (value(c + middle * direction) > 0.0 ? inside : outside) = middle;
  }
  return c + 0.5 * (inside + outside) * direction;
}

Eigen::Vector3d ImplicitShape::project(const Eigen::Vector3d& x) const {
  Eigen::Vector3d p = x;
  for (int i = 0; i < 50; ++i) {
    const double f = value(p);
    const Eigen::Vector3d g = gradient(p);
    const double g2 = g.squaredNorm();
    if (g2 == 0.0) break;
    const Eigen::Vector3d step = f / g2 * g;
    p -= step;
    if (step.norm() < 1e-13 * (1.0 + bounding_radius())) break;
  }
  return p;
}

Eigen::Matrix3d rotation_from_degrees(const Eigen::Vector3d& rotation_deg) {
  constexpr double degree = M_PI / 180.0;
  return (Eigen::AngleAxisd(rotation_deg.z() * degree, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rotation_deg.y() * degree, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rotation_deg.x() * degree, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

namespace {

/// Shared frame handling: local = R^T (x - c).
class FramedShape : public ImplicitShape {
public:
  FramedShape(const Eigen::Vector3d& center_mm, const Eigen::Vector3d& radii_mm,
              const Eigen::Matrix3d& rotation)
      : m_center(center_mm), m_radii(radii_mm), m_rotation(rotation) {}
  Eigen::Vector3d center() const override { return m_center; }
  double bounding_radius() const override { return m_radii.maxCoeff(); }
  /// The solid lies in its frame's box of half sizes m_radii (an ellipsoid, a superquadric of any
  /// exponents, a box): the world box holding that box, rotated.
  Eigen::Vector3d half_extents() const override { return m_rotation.cwiseAbs() * m_radii; }

protected:
  Eigen::Vector3d local(const Eigen::Vector3d& x) const { return m_rotation.transpose() * (x - m_center); }
  Eigen::Vector3d m_center, m_radii;
  Eigen::Matrix3d m_rotation;
};

class Ellipsoid final : public FramedShape {
public:
  using FramedShape::FramedShape;
  // 1 - |x/r|^2: exact zero set, and for a sphere value * r / 2 approximates signed distance.
  double value(const Eigen::Vector3d& x) const override {
    return 1.0 - local(x).cwiseQuotient(m_radii).squaredNorm();
  }
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const override {
    const Eigen::Vector3d l = local(x);
    return m_rotation * (-2.0 * l.cwiseQuotient(m_radii.cwiseProduct(m_radii)));
  }
  double volume() const override { return 4.0 / 3.0 * M_PI * m_radii.prod(); }
  bool star_shaped() const override { return true; }
};

class Superquadric final : public FramedShape {
public:
  Superquadric(const Eigen::Vector3d& c, const Eigen::Vector3d& r, double e1, double e2,
               const Eigen::Matrix3d& rot)
      : FramedShape(c, r, rot), m_e1(e1), m_e2(e2) {}

  // value = 1 - f^(e1/2): f is Barr's inside-outside function; the power makes it grow
  // linearly with scale, which keeps Newton projection well-conditioned.
  double value(const Eigen::Vector3d& x) const override {
    return 1.0 - std::pow(inside_outside(local(x)), 0.5 * m_e1);
  }

  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const override {
    const Eigen::Vector3d l = local(x);
    const Eigen::Vector3d q = l.cwiseQuotient(m_radii);
    const double sxy = std::pow(std::abs(q.x()), 2.0 / m_e2) + std::pow(std::abs(q.y()), 2.0 / m_e2);
    const double f = inside_outside(l);
    if (f <= 0.0) return Eigen::Vector3d::Zero();
    const double outer = -0.5 * m_e1 * std::pow(f, 0.5 * m_e1 - 1.0);
    Eigen::Vector3d df; // d f / d q
    const double dsxy = sxy > 0.0 ? (m_e2 / m_e1) * std::pow(sxy, m_e2 / m_e1 - 1.0) : 0.0;
    df.x() = dsxy * (2.0 / m_e2) * sign_power(q.x(), 2.0 / m_e2 - 1.0);
    df.y() = dsxy * (2.0 / m_e2) * sign_power(q.y(), 2.0 / m_e2 - 1.0);
    df.z() = (2.0 / m_e1) * sign_power(q.z(), 2.0 / m_e1 - 1.0);
    return m_rotation * (outer * df.cwiseQuotient(m_radii));
  }

  bool star_shaped() const override { return true; }
  double volume() const override {
    // Jaklic, Leonardis, Solina (2000): V = 2 a b c e1 e2 B(e1/2 + 1, e1) B(e2/2, e2/2).
    return 2.0 * m_radii.prod() * m_e1 * m_e2 * std::beta(0.5 * m_e1 + 1.0, m_e1) *
           std::beta(0.5 * m_e2, 0.5 * m_e2);
  }

private:
  static double sign_power(double v, double p) {
    return v == 0.0 ? 0.0 : std::copysign(std::pow(std::abs(v), p), v);
  }

  double inside_outside(const Eigen::Vector3d& l) const {
    const Eigen::Vector3d q = l.cwiseQuotient(m_radii).cwiseAbs();
    const double sxy = std::pow(q.x(), 2.0 / m_e2) + std::pow(q.y(), 2.0 / m_e2);
    return std::pow(sxy, m_e2 / m_e1) + std::pow(q.z(), 2.0 / m_e1);
  }

  double m_e1, m_e2;
};

class Box final : public FramedShape {
public:
  Box(const Eigen::Vector3d& c, const Eigen::Vector3d& size, const Eigen::Matrix3d& rot)
      : FramedShape(c, 0.5 * size, rot) {}
  double value(const Eigen::Vector3d& x) const override { return (m_radii - local(x).cwiseAbs()).minCoeff(); }
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const override {
    const Eigen::Vector3d l = local(x);
    Eigen::Index axis = 0;
    (m_radii - l.cwiseAbs()).minCoeff(&axis);
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    g[axis] = l[axis] >= 0.0 ? -1.0 : 1.0;
    return m_rotation * g;
  }
  double bounding_radius() const override { return m_radii.norm(); }
  double volume() const override { return 8.0 * m_radii.prod(); }
  bool star_shaped() const override { return true; }
};

/// Central differences of value(); for shapes whose gradient has no short closed form.
class NumericGradientShape : public ImplicitShape {
public:
  explicit NumericGradientShape(double step_mm) : m_step(step_mm) {}
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const override {
    Eigen::Vector3d g;
    for (int a = 0; a < 3; ++a) {
      Eigen::Vector3d d = Eigen::Vector3d::Zero();
      d[a] = m_step;
      g[a] = (value(x + d) - value(x - d)) / (2.0 * m_step);
    }
    return g;
  }

private:
  double m_step;
};

class Torus final : public NumericGradientShape {
public:
  Torus(const Eigen::Vector3d& c, double major, double tube)
      : NumericGradientShape(1e-6 * (major + tube)), m_center(c), m_major(major), m_tube(tube) {}
  double value(const Eigen::Vector3d& x) const override {
    const Eigen::Vector3d l = x - m_center;
    return m_tube - Eigen::Vector2d(l.head<2>().norm() - m_major, l.z()).norm();
  }
  Eigen::Vector3d center() const override { return m_center; }
  double bounding_radius() const override { return m_major + m_tube; }
  double volume() const override { return 2.0 * M_PI * M_PI * m_major * m_tube * m_tube; }

private:
  Eigen::Vector3d m_center;
  double m_major, m_tube;
};

class Horseshoe final : public NumericGradientShape {
public:
  Horseshoe(double major, double tube)
      : NumericGradientShape(1e-6 * (major + tube)), m_major(major), m_tube(tube) {}
  double value(const Eigen::Vector3d& x) const override {
    if (x.y() >= 0.0) return m_tube - Eigen::Vector2d(x.head<2>().norm() - m_major, x.z()).norm();
    const double to_end =
        std::min((x - Eigen::Vector3d(m_major, 0, 0)).norm(), (x - Eigen::Vector3d(-m_major, 0, 0)).norm());
    return m_tube - to_end;
  }
  // The middle of the bounding box, which lies outside the shape (in the horseshoe's gap).
  Eigen::Vector3d center() const override { return Eigen::Vector3d(0.0, 0.5 * m_major, 0.0); }
  double bounding_radius() const override { return std::hypot(m_major + m_tube, 0.5 * m_major + m_tube); }
  double volume() const override {
    return M_PI * m_tube * m_tube * M_PI * m_major + 4.0 / 3.0 * M_PI * std::pow(m_tube, 3);
  }

private:
  double m_major, m_tube;
};

class FoldedSpheroid final : public NumericGradientShape {
public:
  FoldedSpheroid(double radius, double depth, int lobes, double half_height, double twist)
      : NumericGradientShape(1e-6 * radius), m_radius(radius), m_depth(depth), m_lobes(lobes),
        m_half_height(half_height), m_twist(twist) {}
  double value(const Eigen::Vector3d& x) const override {
    const double rho = x.head<2>().norm();
    const double phi = std::atan2(x.y(), x.x()) - m_twist * rho; // undo the twist
    const double g = m_radius * (1.0 + m_depth * std::cos(m_lobes * phi));
    const double q = (rho / g) * (rho / g) + (x.z() / m_half_height) * (x.z() / m_half_height);
    // 1 - sqrt(q), scaled to mm near the surface (the zero set is exact).
    return std::min(m_radius, m_half_height) * (1.0 - std::sqrt(q));
  }
  Eigen::Vector3d center() const override { return Eigen::Vector3d::Zero(); }
  double bounding_radius() const override { return std::max(m_radius * (1.0 + m_depth), m_half_height); }
  double volume() const override {
    return 4.0 * M_PI / 3.0 * m_half_height * m_radius * m_radius * (1.0 + 0.5 * m_depth * m_depth);
  }

private:
  double m_radius, m_depth;
  int m_lobes;
  double m_half_height, m_twist;
};

class EllipsoidShell final : public NumericGradientShape {
public:
  EllipsoidShell(const Eigen::Vector3d& radii, double thickness)
      : NumericGradientShape(1e-6 * radii.maxCoeff()), m_outer(radii),
        m_inner(radii - Eigen::Vector3d::Constant(thickness)) {}
  double value(const Eigen::Vector3d& x) const override {
    // (1 - |x / r|) min(r): zero on each ellipsoid, about the distance near it.
    const double outer = (1.0 - x.cwiseQuotient(m_outer).norm()) * m_outer.minCoeff();
    const double inner = (1.0 - x.cwiseQuotient(m_inner).norm()) * m_inner.minCoeff();
    return std::min(outer, -inner);
  }
  Eigen::Vector3d center() const override { return Eigen::Vector3d::Zero(); }
  double bounding_radius() const override { return m_outer.maxCoeff(); }
  double volume() const override { return 4.0 / 3.0 * M_PI * (m_outer.prod() - m_inner.prod()); }

private:
  Eigen::Vector3d m_outer, m_inner;
};

} // namespace

std::unique_ptr<ImplicitShape> make_torus(const Eigen::Vector3d& center_mm, double major_mm, double tube_mm) {
  return std::make_unique<Torus>(center_mm, major_mm, tube_mm);
}

std::unique_ptr<ImplicitShape> make_horseshoe(double major_mm, double tube_mm) {
  return std::make_unique<Horseshoe>(major_mm, tube_mm);
}

std::unique_ptr<ImplicitShape> make_folded_spheroid(double radius_mm, double lobe_depth, int lobes,
                                                    double half_height_mm, double twist_per_mm) {
  return std::make_unique<FoldedSpheroid>(radius_mm, lobe_depth, lobes, half_height_mm, twist_per_mm);
}

std::unique_ptr<ImplicitShape> make_ellipsoid_shell(const Eigen::Vector3d& radii_mm, double thickness_mm) {
  return std::make_unique<EllipsoidShell>(radii_mm, thickness_mm);
}

std::unique_ptr<ImplicitShape> make_box(const Eigen::Vector3d& center_mm, const Eigen::Vector3d& size_mm,
                                        const Eigen::Matrix3d& rotation) {
  return std::make_unique<Box>(center_mm, size_mm, rotation);
}

std::unique_ptr<ImplicitShape> make_ellipsoid(const Eigen::Vector3d& center_mm,
                                              const Eigen::Vector3d& radii_mm,
                                              const Eigen::Matrix3d& rotation) {
  return std::make_unique<Ellipsoid>(center_mm, radii_mm, rotation);
}

std::unique_ptr<ImplicitShape> make_superquadric(const Eigen::Vector3d& center_mm,
                                                 const Eigen::Vector3d& radii_mm, double exponent_1,
                                                 double exponent_2, const Eigen::Matrix3d& rotation) {
  return std::make_unique<Superquadric>(center_mm, radii_mm, exponent_1, exponent_2, rotation);
}

} // namespace phantasm
