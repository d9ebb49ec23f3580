// Target shapes given implicitly (positive inside, RAS mm): ellipsoid, superquadric, box, torus,
// horseshoe, folded spheroid, ellipsoidal shell. The patch fit and tet mesher sample them.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <limits>
#include <memory>

namespace phantasm {

class TrilinearVolume;

/// A closed target surface given implicitly: value(x) > 0 inside, < 0 outside, 0 on the surface
/// (the sign convention of patch functions). Positions are RAS mm. Shapes that say they are
/// star_shaped() about center() can be sampled by rays from it (the icosphere base mesh of the
/// patch fit); any other closed shape, of any genus, is sampled through its extracted surface
/// (anatomy/surface_extraction.hpp).
class ImplicitShape {
public:
  virtual ~ImplicitShape() = default;
  virtual double value(const Eigen::Vector3d& x) const = 0;
  virtual Eigen::Vector3d gradient(const Eigen::Vector3d& x) const = 0;
  virtual Eigen::Vector3d center() const = 0;
  /// Half the extent along each principal axis, mm (an upper bound of the distance from the
  /// centre to the surface).
  virtual double bounding_radius() const = 0;
  /// Half the extent along x, y and z of an axis-aligned box about center() that holds the
  /// solid, mm; a cube of bounding_radius() unless the shape knows a tighter box.
  virtual Eigen::Vector3d half_extents() const { return Eigen::Vector3d::Constant(bounding_radius()); }
  /// An axis-aligned box outside which value(x) <= 0 everywhere: lattices over half_extents()'s
  /// box (TargetBoundary) need not evaluate their points past it. The whole space unless the
  /// shape knows one (a label volume's: the voxels it keeps).
  virtual Eigen::AlignedBox3d solid_box() const {
    const double inf = std::numeric_limits<double>::infinity();
    return {Eigen::Vector3d::Constant(-inf), Eigen::Vector3d::Constant(inf)};
  }
  /// Enclosed volume in mm^3, exact where a closed form exists.
  virtual double volume() const = 0;
  /// True when every ray from center() crosses the surface once (ellipsoids, superquadrics,
  /// boxes): only then may ray_from_center() stand for the surface.
  virtual bool star_shaped() const { return false; }
  /// True when value(x) is a smoothed indicator of the solid minus 1/2 (a label volume's shape):
  /// such values may be compared across shapes (NestedShapes::innermost).
  virtual bool smoothed_indicator() const { return false; }
  /// An upper bound of |d value(x + t n) / dt| for every x and t along the unit direction n, or
  /// infinity when the shape knows none. Root searches along a line use it to skip samples whose
  /// sign an earlier sample already settles (same samples' signs, fewer evaluations).
  virtual double slope_bound(const Eigen::Vector3d& direction) const;
  /// The voxel values value() samples, when it is their trilinear interpolant minus 1/2 (a label
  /// volume's shape): searches that sample it millions of times call it inline. Null otherwise.
  virtual const TrilinearVolume* trilinear_volume() const { return nullptr; }

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

/// Torus about the z axis through `center_mm`: tube radius `tube_mm` about a circle of radius
/// `major_mm` (genus 1; value is minus the exact signed distance). V = 2 pi^2 R r^2.
std::unique_ptr<ImplicitShape> make_torus(const Eigen::Vector3d& center_mm, double major_mm, double tube_mm);

/// Horseshoe: a tube of radius `tube_mm` along the half circle of radius `major_mm` in the xy plane
/// with y >= 0, capped by half balls at (+-major_mm, 0, 0) (a bent capsule, like a lateral
/// ventricle; value is minus the exact signed distance). V = pi^2 R r^2 + 4/3 pi r^3.
std::unique_ptr<ImplicitShape> make_horseshoe(double major_mm, double tube_mm);

/// A folded spheroid: the lobed spheroid (rho / g(phi))^2 + (z / c)^2 < 1 in cylindrical
/// coordinates, g(phi) = R (1 + b cos(m phi)), twisted about z by `twist_per_mm` * rho radians
/// (a volume-preserving map), so its lobes become spiral folds that rays from the centre cross
/// several times when R b m twist > 1. V = (4 pi / 3) c R^2 (1 + b^2 / 2), exactly.
std::unique_ptr<ImplicitShape> make_folded_spheroid(double radius_mm, double lobe_depth, int lobes,
                                                    double half_height_mm, double twist_per_mm);

/// Ellipsoidal shell: inside the ellipsoid of semi-axes `radii_mm` and outside the one of semi-axes
/// `radii_mm` - `thickness_mm`, both centred at the origin (two surface components).
std::unique_ptr<ImplicitShape> make_ellipsoid_shell(const Eigen::Vector3d& radii_mm, double thickness_mm);

/// Rotation about x, then y, then z, by angles in degrees (the scene's rotation_deg).
Eigen::Matrix3d rotation_from_degrees(const Eigen::Vector3d& rotation_deg);

} // namespace phantasm
