#include "io/shape_files.hpp"

#include "core/error.hpp"
#include "io/mesh_file.hpp"
#include "io/nifti_file.hpp"

#include <algorithm>
#include <memory>

namespace phantasm {

std::map<std::string, ShapeData> read_shape_files(const AnatomySettings& anatomy) {
  std::map<std::string, ShapeData> files;
  std::map<std::filesystem::path, std::shared_ptr<const ShapeData>> volumes;
  for (std::size_t i = 0; i < anatomy.organs.size(); ++i) {
    const OrganSettings& organ = anatomy.organs[i];
    const ShapeSettings& shape = organ.shape;
    if (shape.kind != ShapeKind::mesh && shape.kind != ShapeKind::label_volume) continue;
    const std::string key = "anatomy.organs[" + std::to_string(i) + "].shape.file";
    try {
      if (shape.kind == ShapeKind::mesh) {
        files[organ.name].mesh = read_triangle_mesh(shape.file);
        continue;
      }
      auto& volume = volumes[shape.file];
      if (!volume) {
        auto data = std::make_shared<ShapeData>();
        data->label_grid.emplace();
        data->labels = read_nifti_labels(shape.file, &*data->label_grid);
        volume = data;
      }
      if (std::find(volume->labels.begin(), volume->labels.end(), shape.label) == volume->labels.end()) {
        throw InputError(shape.file.string() + ": expected voxels of label " + std::to_string(shape.label) +
                         " (organ " + organ.name + "), found none");
      }
      files[organ.name] = *volume;
    } catch (const InputError& error) {
      throw SettingError(key, error.what());
    }
  }
  return files;
}

} // namespace phantasm
