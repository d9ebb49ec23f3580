#include "anatomy/smooth_warp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace phantasm {

namespace {

constexpr double k_pi = 3.14159265358979323846;
constexpr int k_waves = 8;
constexpr double k_shortest_wavelength_mm = 60.0;
constexpr double k_longest_wavelength_mm = 120.0;
constexpr double k_largest_gradient = 0.5;

/// 0 at 0, 1 from 1 on, C1 (smoothstep).
double smoothstep(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

} // namespace

SmoothWarp::SmoothWarp(std::uint64_t seed, double amplitude_mm, const Eigen::Vector3d& window_min,
                       const Eigen::Vector3d& window_max)
    : m_min(window_min), m_max(window_max) {
  if (!(amplitude_mm > 0.0) || !((window_max - window_min).minCoeff() > 0.0)) return;
  m_ramp = std::min(15.0, 0.25 * (window_max - window_min).minCoeff());
  // |grad d| <= sum |a_k| |w_k| + |d| |grad window| <= A (2 pi / 60 mm) + A 1.5 / ramp (the
  // smoothstep's slope is at most 1.5 per ramp): keep it below 1/2.
  const double per_mm = 2.0 * k_pi / k_shortest_wavelength_mm + 1.5 / m_ramp;
  m_amplitude = std::min(amplitude_mm, k_largest_gradient / per_mm);
  // Its own stream of the seed, so the analytic shapes' variation draws stay as they were.
  std::mt19937_64 random(seed ^ 0x9e3779b97f4a7c15ULL);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> wavelength(k_shortest_wavelength_mm, k_longest_wavelength_mm);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * k_pi);
  double sum = 0.0;
  for (int k = 0; k < k_waves; ++k) {
    Wave wave;
    wave.amplitude = Eigen::Vector3d(unit(random), unit(random), unit(random));
    Eigen::Vector3d direction(unit(random), unit(random), unit(random));
    if (direction.norm() < 1e-6) direction = Eigen::Vector3d::UnitX();
    wave.wavevector = direction.normalized() * (2.0 * k_pi / wavelength(random));
    wave.phase = angle(random);
    sum += wave.amplitude.norm();
    m_waves.push_back(wave);
  }
  for (Wave& wave : m_waves)
    wave.amplitude *= m_amplitude / sum; // sum_k |a_k| = A bounds |d|
}

double SmoothWarp::window(const Eigen::Vector3d& x) const {
  double w = 1.0;
  for (int a = 0; a < 3; ++a)
    w *= smoothstep(std::min(x[a] - m_min[a], m_max[a] - x[a]) / m_ramp);
  return w;
}

Eigen::Vector3d SmoothWarp::displacement(const Eigen::Vector3d& x) const {
  if (m_waves.empty()) return Eigen::Vector3d::Zero();
  const double w = window(x);
  if (w == 0.0) return Eigen::Vector3d::Zero();
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  for (const Wave& wave : m_waves)
    d += wave.amplitude * std::sin(wave.wavevector.dot(x) + wave.phase);
  return w * d;
}

SmoothWarp draw_shape_warp(const std::map<std::string, ShapeData>& files, double variation,
                           std::uint64_t seed) {
  if (!(variation > 0.0)) return {};
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& [organ, data] : files) {
    if (data.mesh && data.mesh->vertex_count() > 0) {
      lo = lo.cwiseMin(data.mesh->vertices.colwise().minCoeff().transpose());
      hi = hi.cwiseMax(data.mesh->vertices.colwise().maxCoeff().transpose());
    }
    if (data.label_grid) {
      const ImageGrid& grid = *data.label_grid;
      for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector3d ijk((corner & 1) ? grid.dims.x() - 1 : 0, (corner & 2) ? grid.dims.y() - 1 : 0,
                                  (corner & 4) ? grid.dims.z() - 1 : 0);
        const Eigen::Vector3d x = grid.world_from_index(ijk);
        lo = lo.cwiseMin(x);
        hi = hi.cwiseMax(x);
      }
    }
  }
  if (!(hi - lo).allFinite()) return {};
  // Meshes carry no margin of their own: their box grows by the ramp, so their surface moves too.
  bool meshes = false;
  for (const auto& [organ, data] : files)
    meshes = meshes || data.mesh.has_value();
  if (meshes) {
    lo -= Eigen::Vector3d::Constant(15.0);
    hi += Eigen::Vector3d::Constant(15.0);
  }
  return SmoothWarp(seed, 50.0 * variation, lo, hi);
}

std::map<std::string, ShapeData> warped_shapes(const std::map<std::string, ShapeData>& files,
                                               const SmoothWarp& warp) {
  if (warp.identity()) return files;
  std::map<std::string, ShapeData> out = files;
  std::map<const void*, std::shared_ptr<const std::vector<std::int32_t>>> warped_labels;
  for (auto& [organ, data] : out) {
    if (data.mesh) {
      for (Eigen::Index v = 0; v < data.mesh->vertex_count(); ++v) {
        const Eigen::Vector3d x = data.mesh->vertex(v);
        data.mesh->vertices.row(v) = (x - warp.displacement(x)).transpose();
      }
    }
    if (data.labels && data.label_grid) {
      auto& shared = warped_labels[data.labels.get()];
      if (!shared) {
        const ImageGrid& grid = *data.label_grid;
        const std::vector<std::int32_t>& source = *data.labels;
        std::vector<std::int32_t> labels(source.size(), 0);
        const Eigen::Vector3i dims = grid.dims;
        const IndexFromWorld index_from_world(grid);
#pragma omp parallel for schedule(static)
        for (int k = 0; k < dims.z(); ++k) {
          for (int j = 0; j < dims.y(); ++j) {
            for (int i = 0; i < dims.x(); ++i) {
              const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
              const Eigen::Vector3d from = index_from_world(x + warp.displacement(x));
              const Eigen::Vector3i n(static_cast<int>(std::lround(from.x())),
                                      static_cast<int>(std::lround(from.y())),
                                      static_cast<int>(std::lround(from.z())));
              if ((n.array() < 0).any() || (n.array() >= dims.array()).any()) continue;
              labels[voxel_index(dims, i, j, k)] = source[voxel_index(dims, n.x(), n.y(), n.z())];
            }
          }
        }
        shared = std::make_shared<const std::vector<std::int32_t>>(std::move(labels));
      }
      data.labels = shared;
    }
  }
  return out;
}

} // namespace phantasm
