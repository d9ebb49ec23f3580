// Implicit shapes from files: closed triangle meshes and label volumes.

#include "anatomy/mesh_distance.hpp"
#include "anatomy/phantom.hpp"
#include "anatomy/trilinear_volume.hpp"
#include "core/error.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <optional>

namespace phantasm {
namespace {

/// Central differences of a shape's value; the step is small against the shape's size.
Eigen::Vector3d numeric_gradient(const ImplicitShape& shape, const Eigen::Vector3d& x, double step) {
  Eigen::Vector3d g;
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d[a] = step;
    g[a] = (shape.value(x + d) - shape.value(x - d)) / (2.0 * step);
  }
  return g;
}

class MeshShape final : public ImplicitShape {
public:
  MeshShape(const TriangleMesh& mesh, const std::string& what) : m_distance(mesh) {
    check_closed_manifold(mesh, what);
    m_center = mesh.vertices.colwise().mean().transpose();
    m_radius = (mesh.vertices.rowwise() - m_center.transpose()).rowwise().norm().maxCoeff();
    m_volume = enclosed_volume(mesh);
    m_step = 1e-4 * m_radius;
    // A closed mesh is star-shaped about a point exactly when the point lies on the inner side
    // of every face's plane (it is then in the mesh's kernel).
    m_star_shaped = true;
    for (Eigen::Index f = 0; f < mesh.face_count() && m_star_shaped; ++f) {
      const Eigen::Vector3d a = mesh.vertex(mesh.faces(f, 0)), b = mesh.vertex(mesh.faces(f, 1)),
                            c = mesh.vertex(mesh.faces(f, 2));
      m_star_shaped = (b - a).cross(c - a).dot(m_center - a) < 0.0;
    }
  }
  bool star_shaped() const override { return m_star_shaped; }
  double value(const Eigen::Vector3d& x) const override { return -m_distance.signed_distance(x); }
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const override {
    return numeric_gradient(*this, x, m_step);
  }
  Eigen::Vector3d center() const override { return m_center; }
  double bounding_radius() const override { return m_radius; }
  double volume() const override { return m_volume; }

private:
  MeshDistance m_distance;
  Eigen::Vector3d m_center;
  double m_radius = 0.0, m_volume = 0.0, m_step = 1e-3;
  bool m_star_shaped = false;
};

class LabelShape final : public ImplicitShape {
public:
  LabelShape(const ImageGrid& grid, const std::vector<std::int32_t>& labels,
             const std::vector<std::int32_t>& label_set, double smoothing_mm, const std::string& what)
      : m_grid(grid) {
    if (static_cast<std::int64_t>(labels.size()) != grid.voxel_count()) {
      throw InputError(what + ": expected " + std::to_string(grid.voxel_count()) + " label values, found " +
                       std::to_string(labels.size()));
    }
    const auto in_set = [&label_set](std::int32_t l) {
      return std::find(label_set.begin(), label_set.end(), l) != label_set.end();
    };
    // First pass: the union's voxel box, its centre and volume.
    Eigen::Vector3i low = grid.dims, high = Eigen::Vector3i::Constant(-1);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::int64_t count = 0;
    for (int k = 0; k < grid.dims.z(); ++k)
      for (int j = 0; j < grid.dims.y(); ++j)
        for (int i = 0; i < grid.dims.x(); ++i) {
          const std::size_t index =
              static_cast<std::size_t>((std::int64_t{k} * grid.dims.y() + j) * grid.dims.x() + i);
          if (!in_set(labels[index])) continue;
          const Eigen::Vector3i at(i, j, k);
          low = low.cwiseMin(at);
          high = high.cwiseMax(at);
          sum += grid.world_from_index(at.cast<double>());
          ++count;
        }
    if (count == 0) {
      std::string names;
      for (const std::int32_t l : label_set)
        names += (names.empty() ? "" : ", ") + std::to_string(l);
      throw InputError(what + ": expected voxels with label " + names + ", found none");
    }
    // Keep the box one voxel wider (the interpolation reaches it), and wider by the smoothing
    // kernel's reach.
    const Eigen::Vector3i reach =
        (3.0 * smoothing_mm * grid.spacing_mm.cwiseInverse()).array().ceil().cast<int>().matrix() +
        Eigen::Vector3i::Ones();
    m_low = (low - reach).cwiseMax(Eigen::Vector3i::Zero());
    const Eigen::Vector3i top = (high + reach).cwiseMin(grid.dims - Eigen::Vector3i::Ones());
    m_dims = top - m_low + Eigen::Vector3i::Ones();
    m_trilinear.emplace(grid.world_from_voxel, m_low, m_dims);
    for (int k = 0; k < m_dims.z(); ++k)
      for (int j = 0; j < m_dims.y(); ++j)
        for (int i = 0; i < m_dims.x(); ++i) {
          const std::size_t index = static_cast<std::size_t>(
              (std::int64_t{k + m_low.z()} * grid.dims.y() + j + m_low.y()) * grid.dims.x() + i + m_low.x());
          if (in_set(labels[index])) m_trilinear->values()[local_index(Eigen::Vector3i(i, j, k))] = 1.0f;
        }
    if (smoothing_mm > 0.0) smooth(smoothing_mm);
    measure_max_difference();
    m_center = sum / static_cast<double>(count);
    const double voxel_volume = std::abs(grid.world_from_voxel.topLeftCorner<3, 3>().determinant());
    m_volume = static_cast<double>(count) * voxel_volume;
    // The farthest voxel centre lies at a corner of the voxel box at most.
    m_radius = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
      Eigen::Vector3d at;
      for (int a = 0; a < 3; ++a)
        at[a] = ((corner >> a) & 1) ? high[a] : low[a];
      m_radius = std::max(m_radius, (grid.world_from_index(at) - m_center).norm());
    }
    m_radius += grid.spacing_mm.norm();
    m_step = 0.05 * grid.spacing_mm.minCoeff();
    // Star-shaped when every ray from the centre (icosphere directions, steps of a quarter
    // voxel) leaves the label once and never comes back.
    const TriangleMesh directions = unit_icosphere(3);
    const double step = 0.25 * grid.spacing_mm.minCoeff();
    m_star_shaped = value(m_center) > 0.0;
    for (Eigen::Index v = 0; v < directions.vertex_count() && m_star_shaped; ++v) {
      bool inside = true;
      for (double t = step; t < m_radius && m_star_shaped; t += step) {
        const bool now = value(m_center + t * directions.vertex(v)) > 0.0;
        m_star_shaped = inside || !now;
        inside = now;
      }
    }
  }
  bool star_shaped() const override { return m_star_shaped; }
  bool smoothed_indicator() const override { return true; }

  double value(const Eigen::Vector3d& x) const override { return m_trilinear->value(x); }
  const TrilinearVolume* trilinear_volume() const override { return &*m_trilinear; }
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const override {
    return numeric_gradient(*this, x, m_step);
  }
  Eigen::Vector3d center() const override { return m_center; }
  double slope_bound(const Eigen::Vector3d& direction) const override {
    // Along each voxel axis the interpolant's slope is a weighted mean of differences of
    // neighbouring values, so at most their largest difference along that axis.
    return (m_trilinear->voxel_from_world() * direction).cwiseAbs().dot(m_max_difference);
  }
  double bounding_radius() const override { return m_radius; }
  double volume() const override { return m_volume; }
  Eigen::AlignedBox3d solid_box() const override {
    // A point's cell has a corner in the kept box only within a voxel of it; elsewhere the value
    // is 0 - 1/2. The box's corners a voxel out, in world coordinates.
    Eigen::AlignedBox3d box;
    for (int corner = 0; corner < 8; ++corner) {
      Eigen::Vector3d at;
      for (int a = 0; a < 3; ++a)
        at[a] = ((corner >> a) & 1) ? m_low[a] + m_dims[a] : m_low[a] - 1;
      box.extend(m_grid.world_from_index(at));
    }
    return box;
  }

private:
  /// The largest difference of neighbouring values along each voxel axis, the values outside the
  /// box counting as 0 (slope_bound).
  void measure_max_difference() {
    m_max_difference.setZero();
    for (int k = 0; k < m_dims.z(); ++k)
      for (int j = 0; j < m_dims.y(); ++j)
        for (int i = 0; i < m_dims.x(); ++i) {
          const Eigen::Vector3i at(i, j, k);
          const double v = m_trilinear->values()[local_index(at)];
          for (int a = 0; a < 3; ++a) {
            Eigen::Vector3i next = at;
            ++next[a];
            const double w = next[a] < m_dims[a] ? m_trilinear->values()[local_index(next)] : 0.0;
            m_max_difference[a] = std::max(m_max_difference[a], std::abs(w - v));
            if (at[a] == 0) m_max_difference[a] = std::max(m_max_difference[a], std::abs(v));
          }
        }
  }

  /// Separable Gaussian blur of the indicator (standard deviation sigma_mm, kernel cut at 3
  /// sigma, renormalized at the box's faces): its 1/2-level drops voxel steps and one-voxel
  /// bridges, which the surface mesher would otherwise chase.
  void smooth(double sigma_mm) {
    for (int axis = 0; axis < 3; ++axis) {
      const double sigma = sigma_mm / m_grid.spacing_mm[axis];
      const int half = static_cast<int>(std::ceil(3.0 * sigma));
      std::vector<float> kernel(static_cast<std::size_t>(2 * half + 1));
      for (int t = -half; t <= half; ++t)
        kernel[static_cast<std::size_t>(t + half)] =
            static_cast<float>(std::exp(-0.5 * t * t / (sigma * sigma)));
      const int n = m_dims[axis];
      std::vector<float> line(static_cast<std::size_t>(n));
      // Running counts of the values other than 0 and other than 1: a window of 0s gives exactly
      // 0 and one of 1s exactly 1 (its sum adds the same weights as its normalizer), so most of
      // the box, away from the surface, needs no sum.
      std::vector<int> not_zero(static_cast<std::size_t>(n) + 1), not_one(static_cast<std::size_t>(n) + 1);
      Eigen::Vector3i at(0, 0, 0);
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      for (at[a2] = 0; at[a2] < m_dims[a2]; ++at[a2])
        for (at[a1] = 0; at[a1] < m_dims[a1]; ++at[a1]) {
          Eigen::Vector3i p = at;
          for (p[axis] = 0; p[axis] < n; ++p[axis]) {
            const auto q = static_cast<std::size_t>(p[axis]);
            line[q] = m_trilinear->values()[local_index(p)];
            not_zero[q + 1] = not_zero[q] + (line[q] != 0.0f);
            not_one[q + 1] = not_one[q] + (line[q] != 1.0f);
          }
          if (not_zero[static_cast<std::size_t>(n)] == 0 || not_one[static_cast<std::size_t>(n)] == 0)
            continue;
          for (p[axis] = 0; p[axis] < n; ++p[axis]) {
            const auto first = static_cast<std::size_t>(std::max(0, p[axis] - half));
            const auto end = static_cast<std::size_t>(std::min(n, p[axis] + half + 1));
            if (not_zero[end] == not_zero[first]) {
              m_trilinear->values()[local_index(p)] = 0.0f;
              continue;
            }
            if (not_one[end] == not_one[first]) {
              m_trilinear->values()[local_index(p)] = 1.0f;
              continue;
            }
            double sum = 0.0, weight = 0.0;
            for (int t = -half; t <= half; ++t) {
              const int q = p[axis] + t;
              if (q < 0 || q >= n) continue;
              const double w = kernel[static_cast<std::size_t>(t + half)];
              sum += w * line[static_cast<std::size_t>(q)];
              weight += w;
            }
            m_trilinear->values()[local_index(p)] = static_cast<float>(sum / weight);
          }
        }
    }
  }

  std::size_t local_index(const Eigen::Vector3i& at) const { return m_trilinear->local_index(at); }

  ImageGrid m_grid;
  Eigen::Vector3i m_low{0, 0, 0};  ///< the kept box's first voxel in the volume
  Eigen::Vector3i m_dims{0, 0, 0}; ///< the kept box's size in voxels
  /// The indicator of the labels (smoothed when asked) over the kept box, and value()'s sampling.
  std::optional<TrilinearVolume> m_trilinear;
  Eigen::Vector3d m_max_difference{0, 0, 0}; ///< measure_max_difference
  Eigen::Vector3d m_center;
  double m_radius = 0.0, m_volume = 0.0, m_step = 0.05;
  bool m_star_shaped = false;
};

} // namespace

std::unique_ptr<ImplicitShape> make_mesh_shape(const TriangleMesh& mesh, const std::string& what) {
  return std::make_unique<MeshShape>(mesh, what);
}

std::unique_ptr<ImplicitShape> make_label_shape(const ImageGrid& grid,
                                                const std::vector<std::int32_t>& labels,
                                                const std::vector<std::int32_t>& label_set,
                                                double smoothing_mm, const std::string& what) {
  return std::make_unique<LabelShape>(grid, labels, label_set, smoothing_mm, what);
}

} // namespace phantasm
