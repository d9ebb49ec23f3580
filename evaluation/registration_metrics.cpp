#include "evaluation/registration_metrics.hpp"

#include "core/cancellation.hpp"
#include "geometry/distance_transform.hpp"
#include "geometry/ras_lps.hpp"
#include "io/nifti_file.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

namespace phantasm {
namespace {

/// Voxels of a label with a face neighbour outside it (or on the grid's border).
std::vector<bool> label_surface(const std::vector<std::int32_t>& labels, const Eigen::Vector3i& dims,
                                std::int32_t label) {
  std::vector<bool> surface(labels.size(), false);
  for (int k = 0; k < dims.z(); ++k)
    for (int j = 0; j < dims.y(); ++j)
      for (int i = 0; i < dims.x(); ++i) {
        const std::size_t v = voxel_index(dims, i, j, k);
        if (labels[v] != label) continue;
        const int n[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k},
                             {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
        for (const auto& m : n) {
          if (m[0] < 0 || m[1] < 0 || m[2] < 0 || m[0] >= dims.x() || m[1] >= dims.y() || m[2] >= dims.z() ||
              labels[voxel_index(dims, m[0], m[1], m[2])] != label) {
            surface[v] = true;
            break;
          }
        }
      }
  return surface;
}

/// 95th percentile of the distances from the voxels of `from` to the nearest voxel of `to`.
double directed_p95(const std::vector<bool>& from, const std::vector<bool>& to, const ImageGrid& grid) {
  if (std::find(to.begin(), to.end(), true) == to.end()) return std::numeric_limits<double>::infinity();
  const std::vector<double> distance = distance_to(to, grid);
  std::vector<double> values;
  for (std::size_t v = 0; v < from.size(); ++v)
    if (from[v]) values.push_back(distance[v]);
  if (values.empty()) return std::numeric_limits<double>::infinity();
  return summarize(std::move(values)).p95;
}

} // namespace

Eigen::Vector3d DisplacementField::at(const Eigen::Vector3d& ras_mm) const {
  const Eigen::Vector3d index = grid.index_from_world(ras_mm);
  Eigen::Vector3i low;
  Eigen::Vector3d t;
  for (int a = 0; a < 3; ++a) {
    const double x = std::clamp(index[a], 0.0, static_cast<double>(grid.dims[a] - 1));
    low[a] = std::min(static_cast<int>(std::floor(x)), std::max(grid.dims[a] - 2, 0));
    t[a] = grid.dims[a] > 1 ? x - low[a] : 0.0;
  }
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  for (int corner = 0; corner < 8; ++corner) {
    double weight = 1.0;
    int c[3];
    for (int a = 0; a < 3; ++a) {
      const int bit = (corner >> a) & 1;
      c[a] = std::min(low[a] + bit, grid.dims[a] - 1);
      weight *= bit ? t[a] : 1.0 - t[a];
    }
    if (weight != 0.0) u += weight * lps_mm[voxel_index(grid.dims, c[0], c[1], c[2])];
  }
  return u;
}

Eigen::Vector3d DisplacementField::moved(const Eigen::Vector3d& ras_mm) const {
  return ras_mm + ras_from_lps(at(ras_mm));
}

DisplacementField read_displacement_field(const std::filesystem::path& path) {
  const NiftiVolume volume = read_nifti_vectors(path, 3);
  DisplacementField field;
  field.grid = volume.grid;
  const auto count = static_cast<std::size_t>(volume.grid.voxel_count());
  field.lps_mm.resize(count);
  for (std::size_t v = 0; v < count; ++v)
    field.lps_mm[v] =
        Eigen::Vector3d(volume.values[v], volume.values[count + v], volume.values[2 * count + v]);
  return field;
}

DisplacementField zero_field(const ImageGrid& grid) {
  return DisplacementField{grid, std::vector<Eigen::Vector3d>(static_cast<std::size_t>(grid.voxel_count()),
                                                              Eigen::Vector3d::Zero())};
}

Summary summarize(std::vector<double> values) {
  Summary s;
  s.count = values.size();
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  double sum = 0.0;
  for (double x : values)
    sum += x;
  s.mean = sum / static_cast<double>(values.size());
  double squares = 0.0;
  for (double x : values)
    squares += (x - s.mean) * (x - s.mean);
  s.sd = values.size() > 1 ? std::sqrt(squares / static_cast<double>(values.size() - 1)) : 0.0;
  const double position = 0.95 * static_cast<double>(values.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, values.size() - 1);
  s.p95 = values[below] + (position - static_cast<double>(below)) * (values[above] - values[below]);
  s.max = values.back();
  return s;
}

std::vector<StructureSummary> summarize_by_structure(const std::vector<std::string>& structures,
                                                     const std::vector<double>& values) {
  std::vector<std::string> order;
  std::map<std::string, std::vector<double>> grouped;
  for (std::size_t i = 0; i < values.size() && i < structures.size(); ++i) {
    if (!grouped.count(structures[i])) order.push_back(structures[i]);
    grouped[structures[i]].push_back(values[i]);
  }
  std::vector<StructureSummary> out;
  for (const std::string& structure : order)
    out.push_back({structure, summarize(grouped[structure])});
  return out;
}

std::vector<std::int32_t> warp_labels(const std::vector<std::int32_t>& moving, const ImageGrid& moving_grid,
                                      const DisplacementField& field) {
  const ImageGrid& grid = field.grid;
  std::vector<std::int32_t> warped(static_cast<std::size_t>(grid.voxel_count()), 0);
#pragma omp parallel for schedule(static)
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const std::size_t v = voxel_index(grid.dims, i, j, k);
        const Eigen::Vector3d x = grid.world_from_index(Eigen::Vector3d(i, j, k));
        const Eigen::Vector3d target = moving_grid.index_from_world(x + ras_from_lps(field.lps_mm[v]));
        const Eigen::Vector3i nearest(static_cast<int>(std::lround(target.x())),
                                      static_cast<int>(std::lround(target.y())),
                                      static_cast<int>(std::lround(target.z())));
        if ((nearest.array() >= 0).all() && (nearest.array() < moving_grid.dims.array()).all())
          warped[v] = moving[voxel_index(moving_grid.dims, nearest.x(), nearest.y(), nearest.z())];
      }
  return warped;
}

LabelOverlap label_overlap(const std::vector<std::int32_t>& fixed, const std::vector<std::int32_t>& warped,
                           const ImageGrid& grid, std::int32_t label) {
  LabelOverlap overlap;
  overlap.label = label;
  std::int64_t both = 0;
  for (std::size_t v = 0; v < fixed.size(); ++v) {
    const bool a = fixed[v] == label, b = warped[v] == label;
    overlap.fixed_voxels += a;
    overlap.warped_voxels += b;
    both += a && b;
  }
  const std::int64_t total = overlap.fixed_voxels + overlap.warped_voxels;
  overlap.dice = total > 0 ? 2.0 * static_cast<double>(both) / static_cast<double>(total) : 1.0;
  const std::vector<bool> fixed_surface = label_surface(fixed, grid.dims, label);
  const std::vector<bool> warped_surface = label_surface(warped, grid.dims, label);
  overlap.hd95_mm = std::max(directed_p95(fixed_surface, warped_surface, grid),
                             directed_p95(warped_surface, fixed_surface, grid));
  return overlap;
}

JacobianStatistics jacobian_statistics(const DisplacementField& field, const std::vector<bool>& region) {
  const ImageGrid& grid = field.grid;
  const Eigen::Vector3i& dims = grid.dims;
  // d(LPS position) / d(index), inverted: index derivatives of u become world derivatives.
  const Eigen::Matrix3d lps_from_index = ras_lps_flip() * grid.world_from_voxel.topLeftCorner<3, 3>();
  const Eigen::Matrix3d index_from_lps = lps_from_index.inverse();
  std::vector<double> determinants;
  JacobianStatistics stats;
  stats.min_determinant = std::numeric_limits<double>::infinity();
  stats.max_determinant = -stats.min_determinant;
  for (int k = 0; k < dims.z(); ++k)
    for (int j = 0; j < dims.y(); ++j)
      for (int i = 0; i < dims.x(); ++i) {
        const std::size_t v = voxel_index(dims, i, j, k);
        if (!region[v]) continue;
        const int at[3] = {i, j, k};
        Eigen::Matrix3d gradient; // column a: du / d index_a
        for (int a = 0; a < 3; ++a) {
          int lo[3] = {i, j, k}, hi[3] = {i, j, k};
          lo[a] = std::max(at[a] - 1, 0);
          hi[a] = std::min(at[a] + 1, dims[a] - 1);
          const int step = hi[a] - lo[a];
          gradient.col(a) = step > 0 ? ((field.lps_mm[voxel_index(dims, hi[0], hi[1], hi[2])] -
                                         field.lps_mm[voxel_index(dims, lo[0], lo[1], lo[2])]) /
                                        static_cast<double>(step))
                                           .eval()
                                     : Eigen::Vector3d::Zero().eval();
        }
        const double det = (Eigen::Matrix3d::Identity() + gradient * index_from_lps).determinant();
        stats.min_determinant = std::min(stats.min_determinant, det);
        stats.max_determinant = std::max(stats.max_determinant, det);
        ++stats.voxels;
        if (det <= 0.0) ++stats.folding_voxels;
        determinants.push_back(std::log(std::clamp(det, 1e-9, 1e9)));
      }
  if (stats.voxels > 0) {
    stats.folding_fraction = static_cast<double>(stats.folding_voxels) / static_cast<double>(stats.voxels);
    stats.log_jacobian_sd = summarize(std::move(determinants)).sd;
  }
  return stats;
}

} // namespace phantasm
