#pragma once

#include <Eigen/Core>

#include <memory>

namespace phantasm {

/// A closed target surface given implicitly: value(x) > 0 inside, < 0 outside, 0 on the surface
/// (the sign convention of patch functions). Positions are RAS mm. Shapes are star-shaped about
/// center(), which the fit uses to place base vertices along rays.
class ImplicitShape {
public:
  virtual ~ImplicitShape() = default;
  virtual double value(const Eigen::Vector3d& x) const = 0;
  virtual Eigen::Vector3d gradient(const Eigen::Vector3d& x) const = 0;
  virtual Eigen::Vector3d center() const = 0;
  /// Half the extent along each principal axis, mm (an upper bound of the distance from the
  /// centre to the surface).
  virtual double bounding_radius() const = 0;
  /// Enclosed volume in mm^3, exact where a closed form exists.
  virtual double volume() const = 0;

  /// The surface point on the ray center() + t d (d unit, t > 0), by bisection, to 1e-12 mm.
  Eigen::Vector3d ray_from_center(const Eigen::Vector3d& direction) const;
  /// A surface point near x by Newton steps along the gradient (for points near the surface).
  Eigen::Vector3d project(const Eigen::Vector3d& x) const;
  /// The outward unit normal at a surface point.
  Eigen::Vector3d outward_normal(const Eigen::Vector3d& x) const { return -gradient(x).normalized(); }
};

/// Ellipsoid: semi-axes `radii_mm` along the columns of `rotation`, centred at `center_mm`.
std::unique_ptr<ImplicitShape> make_ellipsoid(const Eigen::Vector3d& center_mm,
                                              const Eigen::Vector3d& radii_mm,
                                              const Eigen::Matrix3d& rotation);

/// Superquadric (Barr): (|x/a|^(2/e2) + |y/b|^(2/e2))^(e2/e1) + |z/c|^(2/e1) = 1 in its own frame.
std::unique_ptr<ImplicitShape> make_superquadric(const Eigen::Vector3d& center_mm,
                                                 const Eigen::Vector3d& radii_mm, double exponent_1,
                                                 double exponent_2, const Eigen::Matrix3d& rotation);

/// Box of edge lengths `size_mm` along the columns of `rotation`: value = min_i (size_i / 2 - |x_i|),
/// the signed distance inside (exact there) and its lower bound outside.
std::unique_ptr<ImplicitShape> make_box(const Eigen::Vector3d& center_mm, const Eigen::Vector3d& size_mm,
                                        const Eigen::Matrix3d& rotation);

/// Rotation about x, then y, then z, by angles in degrees (the scene's rotation_deg).
Eigen::Matrix3d rotation_from_degrees(const Eigen::Vector3d& rotation_deg);

} // namespace phantasm
