#include "anatomy/implicit_shape.hpp"

#include <Eigen/Geometry>

#include <cmath>

namespace phantasm {

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
};

} // namespace

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
