// How each organ shape source builds its organs (the build side of the shape source registry,
// anatomy/shape_source.hpp), keyed by the same kind: its target shape, and its geometry when it
// is not the default one (fitted patches over a CGAL tet mesh for a solid organ, fitted patches
// alone for a surface). One member per source, anatomy/shape_builds/NAME.cpp.
#pragma once

#include "anatomy/anatomy_settings.hpp"
#include "anatomy/implicit_shape.hpp"
#include "anatomy/organ.hpp"

#include <memory>
#include <string>
#include <vector>

namespace phantasm {

/// One shape source's build.
struct ShapeBuild {
  ShapeKind kind;
  /// The organ's implicit target shape; `file` holds what io/shape_files.hpp read for it (null
  /// for sources that read nothing); null result: a shape without a target (a sheet).
  /// @throws InputError when the file's data is missing or cannot make a shape
  std::unique_ptr<ImplicitShape> (*target)(const ShapeSettings& shape, const ShapeData* file,
                                           const std::string& organ) = nullptr;
  /// Builds the organ's geometry (surface, sheet, tets and fit) from its varied shape and its
  /// target (organ.target); null: the default fitted geometry.
  void (*geometry)(Organ& organ, const OrganSettings& settings, const ShapeSettings& shape) = nullptr;
  /// The semi-axes a fitted surface organ starts from, mm; null: unit (found from the target).
  Eigen::Vector3d (*fit_hint)(const ShapeSettings& shape) = nullptr;
};

/// Every registered build, in the order of shape_sources().
const std::vector<const ShapeBuild*>& shape_builds();

/// The build of a kind (every kind has one).
const ShapeBuild& shape_build(ShapeKind kind);

} // namespace phantasm
