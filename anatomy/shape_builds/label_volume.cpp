// A label volume's organs: the interpolated indicator of its target labels (its own and those
// nested in it, as io/shape_files.hpp gathered them), smoothed when asked.
#include "anatomy/phantom.hpp"
#include "anatomy/shape_build.hpp"
#include "core/error.hpp"

namespace phantasm {

const ShapeBuild& label_volume_shape_build() {
  static const ShapeBuild build{
      ShapeKind::label_volume,
      [](const ShapeSettings& shape, const ShapeData* file, const std::string& organ) {
        if (file == nullptr || !file->label_grid || !file->labels)
          throw InputError("organ " + organ + ": its label volume was not loaded");
        return make_label_shape(
            *file->label_grid, *file->labels,
            file->target_labels.empty() ? std::vector<std::int32_t>{shape.label} : file->target_labels,
            shape.smoothing_mm,
            "organ " + organ + " (" + (file->source.empty() ? shape.file.string() : file->source) + ")");
      }};
  return build;
}

} // namespace phantasm
