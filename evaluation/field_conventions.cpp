#include "evaluation/field_conventions.hpp"

#include "core/error.hpp"
#include "geometry/ras_lps.hpp"
#include "io/nifti_file.hpp"

#include <cmath>

namespace phantasm {
namespace {

struct ConventionName {
  FieldConvention convention;
  const char* name;
};
constexpr ConventionName k_names[] = {{FieldConvention::itk, "itk"},
                                      {FieldConvention::learn2reg, "learn2reg"},
                                      {FieldConvention::mrtrix_deformation, "mrtrix-deformation"},
                                      {FieldConvention::mrtrix_displacement, "mrtrix-displacement"}};

/// d(RAS mm) / d(voxel index): the linear part of the grid's affine.
Eigen::Matrix3d ras_from_index(const ImageGrid& grid) {
  return grid.world_from_voxel.topLeftCorner<3, 3>();
}

std::string dims_text(const Eigen::Vector3i& d) {
  return std::to_string(d.x()) + " x " + std::to_string(d.y()) + " x " + std::to_string(d.z());
}

bool is_integer_datatype(int datatype) {
  return datatype != 16 && datatype != 64; // NIfTI float32 and float64
}

} // namespace

std::string to_string(FieldConvention convention) {
  for (const auto& n : k_names)
    if (n.convention == convention) return n.name;
  return "itk";
}

FieldConvention field_convention_from_string(const std::string& name, const std::string& option) {
  std::string known;
  for (const auto& n : k_names) {
    if (name == n.name) return n.convention;
    known += (known.empty() ? "" : ", ") + std::string(n.name);
  }
  throw InputError(option + ": expected one of " + known + ", found '" + name + "'");
}

std::vector<Eigen::Vector3d> ras_displacements(const DisplacementField& field) {
  std::vector<Eigen::Vector3d> ras(field.lps_mm.size());
  for (std::size_t v = 0; v < ras.size(); ++v)
    ras[v] = ras_from_lps(field.lps_mm[v]);
  return ras;
}

DisplacementField field_from_ras(const ImageGrid& grid, const std::vector<Eigen::Vector3d>& ras_mm) {
  DisplacementField field{grid, std::vector<Eigen::Vector3d>(ras_mm.size())};
  for (std::size_t v = 0; v < ras_mm.size(); ++v)
    field.lps_mm[v] = lps_from_ras(ras_mm[v]);
  return field;
}

void write_field(const std::filesystem::path& path, const DisplacementField& field,
                 FieldConvention convention) {
  const ImageGrid& grid = field.grid;
  const std::size_t count = field.lps_mm.size();
  const Eigen::Matrix3d index_from_ras = ras_from_index(grid).inverse();
  std::vector<float> values(3 * count);
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const std::size_t v = voxel_index(grid.dims, i, j, k);
        const Eigen::Vector3d ras = ras_from_lps(field.lps_mm[v]);
        Eigen::Vector3d stored = ras;
        switch (convention) {
        case FieldConvention::itk: stored = field.lps_mm[v]; break;
        case FieldConvention::learn2reg: stored = index_from_ras * ras; break;
        case FieldConvention::mrtrix_deformation:
          stored = grid.world_from_index(Eigen::Vector3d(i, j, k)) + ras;
          break;
        case FieldConvention::mrtrix_displacement: stored = ras; break;
        }
        for (int c = 0; c < 3; ++c)
          values[c * count + v] = static_cast<float>(stored[c]);
      }
  NiftiWriteOptions options;
  options.components = 3;
  options.intent = NiftiIntent::displacement;
  options.components_in_fourth_dimension = convention != FieldConvention::itk;
  options.description = "displacement, " + to_string(convention) + " convention";
  write_nifti(path, grid, values, options);
}

DisplacementField read_field(const std::filesystem::path& path, FieldConvention convention,
                             const ImageGrid& fixed) {
  const NiftiVolume volume =
      convention == FieldConvention::itk ? read_nifti_vectors(path, 3) : read_nifti_vectors_4d(path, 3);
  if (volume.grid.dims != fixed.dims) {
    throw InputError(path.string() + ": expected a field on the fixed grid (" + dims_text(fixed.dims) +
                     " voxels, 3 components), found " + dims_text(volume.grid.dims) + " voxels");
  }
  // The world-coordinate conventions (ITK, MRtrix3) read their vectors in the file's space: one on
  // another grid of the same size is another field. A Learn2Reg file's vectors are voxels of the
  // fixed grid whatever its header says (the challenge's files carry an identity or none).
  if (convention != FieldConvention::learn2reg &&
      (volume.grid.world_from_voxel - fixed.world_from_voxel).cwiseAbs().maxCoeff() > 1e-3) {
    throw InputError(path.string() + ": expected a field on the fixed grid's voxel-to-world matrix (" +
                     to_string(convention) + " vectors are in world mm), found another one");
  }
  if (is_integer_datatype(volume.datatype)) {
    throw InputError(path.string() + ": expected float32 or float64 displacements, found NIfTI datatype " +
                     std::to_string(volume.datatype) +
                     " (whole numbers cannot hold sub-voxel displacements)");
  }
  const std::size_t count = static_cast<std::size_t>(fixed.voxel_count());
  const Eigen::Matrix3d ras_per_index = ras_from_index(fixed);
  std::vector<Eigen::Vector3d> ras(count);
  for (int k = 0; k < fixed.dims.z(); ++k)
    for (int j = 0; j < fixed.dims.y(); ++j)
      for (int i = 0; i < fixed.dims.x(); ++i) {
        const std::size_t v = voxel_index(fixed.dims, i, j, k);
        const Eigen::Vector3d stored(volume.values[v], volume.values[count + v],
                                     volume.values[2 * count + v]);
        if (!stored.allFinite()) {
          throw InputError(path.string() +
                           ": expected finite displacements, found NaN or infinity at voxel (" +
                           std::to_string(i) + ", " + std::to_string(j) + ", " + std::to_string(k) + ")");
        }
        switch (convention) {
        case FieldConvention::itk: ras[v] = ras_from_lps(stored); break;
        case FieldConvention::learn2reg: ras[v] = ras_per_index * stored; break;
        case FieldConvention::mrtrix_deformation:
          ras[v] = stored - fixed.world_from_index(Eigen::Vector3d(i, j, k));
          break;
        case FieldConvention::mrtrix_displacement: ras[v] = stored; break;
        }
      }
  return field_from_ras(fixed, ras);
}

} // namespace phantasm
