#include "pipeline/finite_outputs.hpp"

#include "core/error.hpp"
#include "core/format.hpp"

#include <cmath>
#include <string>
#include <tuple>

namespace phantasm {
namespace {

std::string shown(double value) {
  return std::isnan(value) ? std::string("NaN") : format_number(value);
}

/// Names a voxel of the grid by its indices and the tissue of its label in `volumes`.
std::string voxel_text(const VoxelizedPhantom& v, const TissueVolumes* volumes, std::size_t voxel) {
  const Eigen::Vector3i& d = v.grid.dims;
  const auto nx = static_cast<std::size_t>(d.x()), ny = static_cast<std::size_t>(d.y());
  std::string text = "voxel (" + std::to_string(voxel % nx) + ", " + std::to_string((voxel / nx) % ny) +
                     ", " + std::to_string(voxel / (nx * ny)) + ")";
  if (volumes != nullptr && voxel < volumes->labels.size() && volumes->labels[voxel] >= 0 &&
      static_cast<std::size_t>(volumes->labels[voxel]) < volumes->label_tissues.size()) {
    // The tissues with a share of the voxel: a partial voxel of the background label may hold one.
    std::string tissues;
    for (int t = 0; t < volumes->tissue_count && static_cast<std::size_t>(t) < v.tissues.size(); ++t)
      if (volumes->fraction(t, voxel) > 0.0f) tissues += (tissues.empty() ? "" : ", ") + v.tissues[t];
    text += tissues.empty() ? std::string(", tissue background") : ", tissue " + tissues;
  }
  return text;
}

/// Refuses the first value of `values` that is not finite; a voxel volume of `components`
/// components, component-major, on the grid of `v`.
void require_finite(const std::vector<float>& values, const std::string& what, const VoxelizedPhantom& v,
                    const TissueVolumes* volumes, int components = 1) {
  const std::size_t count = values.size() / static_cast<std::size_t>(components);
  for (std::size_t at = 0; at < values.size(); ++at) {
    if (std::isfinite(values[at])) continue;
    throw InputError(what + ": expected finite values before anything is written, found " +
                     shown(values[at]) + " at " + voxel_text(v, volumes, count > 0 ? at % count : at) +
                     (components > 1 ? ", component " + std::to_string(at / count) : std::string()) + "");
  }
}

void require_finite_maps(const ParameterMaps& maps, const std::string& state, const VoxelizedPhantom& v,
                         const TissueVolumes* volumes) {
  const std::pair<const char*, const std::vector<float>*> arrays[] = {
      {"PD", &maps.PD}, {"T1", &maps.T1_ms}, {"T2", &maps.T2_ms}, {"T2*", &maps.T2star_ms}};
  for (const auto& [name, values] : arrays)
    require_finite(*values, std::string(name) + " map of the " + state + " state", v, volumes);
}

/// The check itself, without the scene's name.
void require_finite_arrays(const Simulation& simulation) {
  const VoxelizedPhantom& v = simulation.volumes;
  const TissueVolumes* reference = &v.reference;
  const TissueVolumes* deformed = v.deformed ? &*v.deformed : reference;
  const MrImages& images = simulation.images;
  for (const auto& [state, list, volumes] : {std::tuple{"reference", &images.reference, reference},
                                             std::tuple{"deformed", &images.deformed, deformed}}) {
    for (const MrImage& image : *list) {
      const std::string sequence = image.sequence != nullptr ? image.sequence->name : std::string("?");
      require_finite(image.magnitude, "sequence " + sequence + ", " + state + " image", v, volumes);
    }
  }
  if (images.reference_maps) require_finite_maps(*images.reference_maps, "reference", v, reference);
  if (images.deformed_maps) require_finite_maps(*images.deformed_maps, "deformed", v, deformed);
  if (v.motion) {
    // ref_to_def lives on the reference grid (the dataset's from-def_to-ref), def_to_ref on the
    // deformed one (from-ref_to-def).
    require_finite(v.motion->ref_to_def, "displacement field from-def_to-ref", v, reference, 3);
    require_finite(v.motion->def_to_ref, "displacement field from-ref_to-def", v, deformed, 3);
    require_finite(v.motion->jacobian, "Jacobian of from-def_to-ref", v, reference);
    require_finite(v.motion->def_to_ref_jacobian, "Jacobian of from-ref_to-def", v, deformed);
  }
  for (const Landmark& landmark : v.landmarks) {
    if (!landmark.reference_mm.allFinite() || !landmark.deformed_mm.allFinite())
      throw InputError("landmark " + landmark.name + " of organ " + landmark.organ +
                       ": expected finite coordinates before anything is written, found NaN or infinity");
  }
  if (simulation.deformation) {
    for (const DeformedBody& body : simulation.deformation->bodies) {
      if (!body.deformed_mm.allFinite() || !body.rest_mm.allFinite())
        throw InputError("simulated body " + body.organ +
                         ": expected finite vertex positions before anything is written, found NaN or "
                         "infinity");
    }
  }
}

} // namespace

void require_finite_outputs(const Simulation& simulation, const std::filesystem::path& scene_file) {
  try {
    require_finite_arrays(simulation);
  } catch (const InputError& error) {
    if (scene_file.empty()) throw;
    throw InputError(scene_file.string() + ": " + error.what());
  }
}

} // namespace phantasm
