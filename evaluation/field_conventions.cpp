#include "evaluation/field_conventions.hpp"

#include "core/error.hpp"
#include "core/registry.hpp"
#include "geometry/ras_lps.hpp"
#include "io/nifti_file.hpp"

#include <Eigen/LU>

#include <cmath>

namespace phantasm {
namespace {

std::string dims_text(const Eigen::Vector3i& d) {
  return std::to_string(d.x()) + " x " + std::to_string(d.y()) + " x " + std::to_string(d.z());
}

bool is_integer_datatype(int datatype) {
  return datatype != 16 && datatype != 64; // NIfTI float32 and float64
}

} // namespace

// The members, one per file of evaluation/field_conventions/.
const FieldConventionType& itk_field_convention();
const FieldConventionType& learn2reg_field_convention();
const FieldConventionType& mrtrix_deformation_field_convention();
const FieldConventionType& mrtrix_displacement_field_convention();

namespace {

const Registry<FieldConventionType, FieldConvention>& field_convention_registry() {
  // The registrations: a new convention adds its line here and its declaration above
  // (docs/architecture.md, Adding a variant).
  static const Registry<FieldConventionType, FieldConvention> types(
      "field convention", &FieldConventionType::convention,
      {&itk_field_convention(), &learn2reg_field_convention(), &mrtrix_deformation_field_convention(),
       &mrtrix_displacement_field_convention()});
  return types;
}

} // namespace

const std::vector<const FieldConventionType*>& field_convention_types() {
  return field_convention_registry().members();
}

const FieldConventionType& field_convention_type(FieldConvention convention) {
  return field_convention_registry().at(convention);
}

FieldFrame::FieldFrame(const ImageGrid& g)
    : grid(g), ras_from_index(g.world_from_voxel.topLeftCorner<3, 3>()),
      index_from_ras(ras_from_index.inverse()) {}

std::string field_convention_help(FieldConvention default_convention) {
  std::string help = std::string("Convention of the result fields: ") +
                     field_convention_type(default_convention).name + " (default)";
  for (const FieldConventionType* type : field_convention_types())
    if (type->convention != default_convention) help += std::string(", ") + type->name;
  return help;
}

std::string to_string(FieldConvention convention) {
  return field_convention_type(convention).name;
}

FieldConvention field_convention_from_string(const std::string& name, const std::string& option) {
  if (const FieldConventionType* type = field_convention_registry().find(name)) return type->convention;
  throw InputError(option + ": expected one of " + field_convention_registry().all_names_text(", ") +
                   ", found '" + name + "'");
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
  const FieldConventionType& type = field_convention_type(convention);
  const FieldFrame frame(grid);
  std::vector<float> values(3 * count);
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) {
        const std::size_t v = voxel_index(grid.dims, i, j, k);
        const Eigen::Vector3d stored =
            type.stored(frame, Eigen::Vector3d(i, j, k), ras_from_lps(field.lps_mm[v]));
        for (int c = 0; c < 3; ++c)
          values[c * count + v] = static_cast<float>(stored[c]);
      }
  NiftiWriteOptions options;
  options.components = 3;
  options.intent = NiftiIntent::displacement;
  options.components_in_fourth_dimension = type.components_in_fourth_dimension;
  options.description = "displacement, " + std::string(type.name) + " convention";
  write_nifti(path, grid, values, options);
}

DisplacementField read_field(const std::filesystem::path& path, FieldConvention convention,
                             const ImageGrid& fixed) {
  const FieldConventionType& type = field_convention_type(convention);
  const NiftiVolume volume =
      type.components_in_fourth_dimension ? read_nifti_vectors_4d(path, 3) : read_nifti_vectors(path, 3);
  if (volume.grid.dims != fixed.dims) {
    throw InputError(path.string() + ": expected a field on the fixed grid (" + dims_text(fixed.dims) +
                     " voxels, 3 components), found " + dims_text(volume.grid.dims) + " voxels");
  }
  // The world-coordinate conventions (ITK, MRtrix3) read their vectors in the file's space: one on
  // another grid of the same size is another field. A Learn2Reg file's vectors are voxels of the
  // fixed grid whatever its header says (the challenge's files carry an identity or none).
  if (type.world_frame &&
      (volume.grid.world_from_voxel - fixed.world_from_voxel).cwiseAbs().maxCoeff() > 1e-3) {
    throw InputError(path.string() + ": expected a field on the fixed grid's voxel-to-world matrix (" +
                     type.name + " vectors are in world mm), found another one");
  }
  if (is_integer_datatype(volume.datatype)) {
    throw InputError(path.string() + ": expected float32 or float64 displacements, found NIfTI datatype " +
                     std::to_string(volume.datatype) +
                     " (whole numbers cannot hold sub-voxel displacements)");
  }
  const std::size_t count = static_cast<std::size_t>(fixed.voxel_count());
  const FieldFrame frame(fixed);
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
        ras[v] = type.displacement(frame, Eigen::Vector3d(i, j, k), stored);
      }
  return field_from_ras(fixed, ras);
}

} // namespace phantasm
