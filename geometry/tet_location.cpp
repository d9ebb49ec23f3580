// Barycentric coordinates of points in tetrahedra and point location in tet meshes; see
// tet_location.hpp.
#include "geometry/tet_location.hpp"

#include <Eigen/LU>

#include <limits>

namespace phantasm {

Eigen::Vector4d tet_barycentric(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  Eigen::Matrix3d D;
  D << b - a, c - a, d - a;
  const Eigen::Vector3d l = D.inverse() * (x - a);
  return {1.0 - l.sum(), l[0], l[1], l[2]};
}

TetMeshLocator::TetMeshLocator(const Eigen::MatrixX3d& x, const Eigen::MatrixX4i& tets) {
  const auto n = static_cast<std::size_t>(tets.rows());
  m_inverse.reserve(n);
  m_origin.reserve(n);
  m_tet_low.reserve(n);
  m_tet_high.reserve(n);
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    Eigen::Matrix3d D;
    Eigen::Vector3d low = x.row(tets(t, 0)).transpose(), high = low;
    for (int k = 0; k < 3; ++k) {
      D.col(k) = (x.row(tets(t, k + 1)) - x.row(tets(t, 0))).transpose();
      low = low.cwiseMin(x.row(tets(t, k + 1)).transpose());
      high = high.cwiseMax(x.row(tets(t, k + 1)).transpose());
    }
    m_inverse.push_back(D.inverse());
    m_origin.push_back(x.row(tets(t, 0)).transpose());
    m_tet_low.push_back(low);
    m_tet_high.push_back(high);
    m_low = m_low.cwiseMin(low);
    m_high = m_high.cwiseMax(high);
  }
}

std::optional<TetLocation> TetMeshLocator::find(const Eigen::Vector3d& x, double weight_tolerance,
                                                double box_tolerance_mm) const {
  if ((x.array() < m_low.array() - box_tolerance_mm).any() ||
      (x.array() > m_high.array() + box_tolerance_mm).any())
    return std::nullopt;
  for (std::size_t t = 0; t < m_inverse.size(); ++t) {
    if ((x.array() < m_tet_low[t].array() - box_tolerance_mm).any() ||
        (x.array() > m_tet_high[t].array() + box_tolerance_mm).any())
      continue;
    const Eigen::Vector4d w = barycentric(static_cast<Eigen::Index>(t), x);
    if (w.minCoeff() >= -weight_tolerance) return TetLocation{static_cast<Eigen::Index>(t), w};
  }
  return std::nullopt;
}

TetLocation TetMeshLocator::nearest(const Eigen::Vector3d& x) const {
  double best = -std::numeric_limits<double>::infinity();
  TetLocation result;
  for (std::size_t t = 0; t < m_inverse.size(); ++t) {
    const Eigen::Vector4d w = barycentric(static_cast<Eigen::Index>(t), x);
    const double smallest = w.minCoeff();
    if (smallest > best) {
      best = smallest;
      result = {static_cast<Eigen::Index>(t), w};
      if (smallest >= 0.0) break;
    }
  }
  return result;
}

} // namespace phantasm
