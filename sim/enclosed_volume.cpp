#include "sim/enclosed_volume.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace phantasm {
namespace {

double bump_height(const EnclosedVolume& c, std::size_t t) {
  return c.bump_height_m.empty() ? 0.0 : c.bump_height_m[t];
}

Eigen::Vector3d row(const Eigen::MatrixX3d& X, int i) {
  return X.row(i).transpose();
}

} // namespace

Eigen::MatrixX3d gather_vertices(const EnclosedVolume& c, const Eigen::MatrixX3d& p) {
  Eigen::MatrixX3d X(static_cast<Eigen::Index>(c.vertices.size()), 3);
  for (std::size_t i = 0; i < c.vertices.size(); ++i)
    X.row(static_cast<Eigen::Index>(i)) = p.row(c.vertices[i]);
  return X;
}

double enclosed_volume(const EnclosedVolume& c, const Eigen::MatrixX3d& X) {
  double volume = 0.0;
  for (std::size_t t = 0; t < c.triangles.size(); ++t) {
    const auto& [a, b, d] = c.triangles[t];
    const Eigen::Vector3d x0 = row(X, a), x1 = row(X, b), x2 = row(X, d);
    volume += x0.dot(x1.cross(x2)) / 6.0;
    const double h = bump_height(c, t);
    if (h != 0.0) volume += h * 0.5 * (x1 - x0).cross(x2 - x0).norm();
  }
  return volume;
}

Eigen::MatrixX3d enclosed_volume_gradient(const EnclosedVolume& c, const Eigen::MatrixX3d& X) {
  Eigen::MatrixX3d g = Eigen::MatrixX3d::Zero(X.rows(), 3);
  for (std::size_t t = 0; t < c.triangles.size(); ++t) {
    const std::array<int, 3>& v = c.triangles[t];
    const Eigen::Vector3d x[3] = {row(X, v[0]), row(X, v[1]), row(X, v[2])};
    const double h = bump_height(c, t);
    Eigen::Vector3d unit_normal = Eigen::Vector3d::Zero();
    if (h != 0.0) {
      const Eigen::Vector3d n = (x[1] - x[0]).cross(x[2] - x[0]);
      const double length = n.norm();
      if (length > 0.0) unit_normal = n / length; // a collapsed triangle's area has no gradient
    }
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& next = x[(k + 1) % 3];
      const Eigen::Vector3d& last = x[(k + 2) % 3];
      // d(x0 . (x1 x x2))/dx_k = x_k+1 x x_k+2 (cyclic); dA/dx_k = n x (x_k+2 - x_k+1) / 2.
      Eigen::Vector3d d = next.cross(last) / 6.0;
      if (h != 0.0) d += h * 0.5 * unit_normal.cross(last - next);
      g.row(v[static_cast<std::size_t>(k)]) += d.transpose();
    }
  }
  return g;
}

Eigen::MatrixX3d project_enclosed_volume(const EnclosedVolume& c, const Eigen::MatrixX3d& X) {
  const double V0 = c.rest_volume_m3;
  const double volume = enclosed_volume(c, X);
  const double target = std::clamp(volume, c.range.min * V0, c.range.max * V0);
  if (volume == target || X.rows() == 0) return X;
  const double size = (X.rowwise() - X.colwise().mean()).rowwise().norm().maxCoeff() + 1e-300;
  Eigen::MatrixX3d Y = X;
  double mu = 0.0;
  for (int outer = 0; outer < 100; ++outer) {
    const Eigen::MatrixX3d G = enclosed_volume_gradient(c, Y);
    // mu with V(X + mu G) = target: Newton along G from the last multiplier.
    for (int inner = 0; inner < 50; ++inner) {
      const Eigen::MatrixX3d Z = X + mu * G;
      const double f = enclosed_volume(c, Z) - target;
      if (std::abs(f) <= 1e-15 * V0) break;
      const double slope = enclosed_volume_gradient(c, Z).cwiseProduct(G).sum();
      if (!(std::abs(slope) > 0.0)) break;
      mu -= f / slope;
    }
    const Eigen::MatrixX3d next = X + mu * G;
    const double change = (next - Y).rowwise().norm().maxCoeff();
    Y = next;
    if (!(change > 1e-13 * size)) break;
  }
  return Y;
}

EnclosedVolume enclosed_volume_constraint(std::vector<int> vertices,
                                          std::vector<std::array<int, 3>> triangles,
                                          std::vector<double> bump_height_m, const Eigen::MatrixX3d& rest_m,
                                          double bulk_modulus_Pa, const SingularValueRange& range) {
  EnclosedVolume c;
  c.vertices = std::move(vertices);
  c.triangles = std::move(triangles);
  c.bump_height_m = std::move(bump_height_m);
  c.range = range;
  if (!c.bump_height_m.empty() && c.bump_height_m.size() != c.triangles.size())
    throw std::invalid_argument("enclosed volume: one bump height per triangle expected");
  const Eigen::MatrixX3d X = gather_vertices(c, rest_m);
  c.rest_volume_m3 = enclosed_volume(c, X);
  if (!(c.rest_volume_m3 > 0.0)) {
    throw std::invalid_argument("enclosed volume: the surface encloses " + std::to_string(c.rest_volume_m3) +
                                " m^3 (expected a closed surface with outward triangles)");
  }
  c.weight = bulk_modulus_Pa * enclosed_volume_gradient(c, X).squaredNorm() / c.rest_volume_m3;
  return c;
}

} // namespace phantasm
