// The surface of labels of a label volume, read from a NIfTI file or derived from an atlas: its
// target unites its labels with those of the organs nested in it from the same volume, so its
// organs nest by construction.
#include "anatomy/shape_source.hpp"

namespace phantasm {

const ShapeSource& label_volume_shape_source() {
  static const ShapeSource source = [] {
    ShapeParameter file{"file", ShapeParameter::Kind::file};
    file.required = true;
    file.atlas_allowed = true;
    ShapeParameter labels{"label", ShapeParameter::Kind::labels};
    labels.required = true;
    ShapeParameter smoothing{
        "smoothing_mm", ShapeParameter::Kind::number, nullptr, &ShapeSettings::smoothing_mm, 0.0, 10.0};
    smoothing.unit = "mm";
    ShapeSource s{ShapeKind::label_volume,
                  "label_volume",
                  "labels of a label volume: file (NIfTI) or atlas (colin27), label, smoothing_mm",
                  {file, labels, smoothing}};
    s.nesting = NestingCheck::by_construction;
    s.input = ShapeInput::label_volume;
    return s;
  }();
  return source;
}

} // namespace phantasm
