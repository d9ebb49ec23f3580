// The registry of organ shape sources: one member per source (anatomy/shape_sources/NAME.cpp),
// each the one place that knows its scene keys and their bounds, its help, its bounds in world
// space, how its organs' nesting is checked, what it reads from files, its plan line and its
// cost-model terms. Eigen and the standard library only, so the scene parses and the cost
// estimate reads the members without CGAL; how a member builds its organs lives beside it in
// anatomy/shape_builds/NAME.cpp (anatomy/shape_build.hpp). Adding a source:
// docs/architecture.md, "Adding a variant".
#pragma once

#include "anatomy/anatomy_settings.hpp"

#include <optional>
#include <string>
#include <vector>

namespace phantasm {

/// A scene key of a shape source (under anatomy.organs[i].shape, beside `type`).
struct ShapeParameter {
  enum class Kind {
    vector3, ///< three numbers into `vector` (with `scalar_allowed`, one number for all three)
    extent2, ///< two numbers into x and y of `vector`, z set to 0
    cells,   ///< `axes` integers in [1, 1000] into ShapeSettings::cells (the others set to 1)
    number,  ///< one number into `number`
    file,    ///< a file relative to the scene's folder into ShapeSettings::file; with
             ///< `atlas_allowed`, `atlas` (into ShapeSettings::atlas) instead of it
    labels   ///< one label or a list into ShapeSettings::label and ShapeSettings::labels
  };
  const char* key = "";
  Kind kind = Kind::number;
  Eigen::Vector3d ShapeSettings::*vector = nullptr; ///< Kind::vector3, Kind::extent2
  double ShapeSettings::*number = nullptr;          ///< Kind::number
  double min = 0.0, max = 0.0;                      ///< accepted values (vector3, extent2, number)
  bool min_exclusive = false, max_exclusive = false;
  const char* unit = "";
  bool required = false;
  bool scalar_allowed = false;              ///< Kind::vector3
  int axes = 3;                             ///< Kind::cells
  std::vector<std::string> extensions = {}; ///< Kind::file: the accepted extensions (empty: any)
  bool atlas_allowed = false;               ///< Kind::file
};

/// How the nesting of an organ of this source in its container is checked.
enum class NestingCheck {
  none,            ///< not checked (its bounds may be larger than its extent)
  by_bounds,       ///< by the scene's validation: its bounds are its extent
  when_built,      ///< once its surface is built (pipeline/anatomy_checks.hpp)
  by_construction, ///< nests by construction (label volumes: the target unites nested labels)
};

/// What an organ of this source reads from files before the anatomy stage builds it
/// (io/shape_files.hpp).
enum class ShapeInput { none, triangle_mesh, label_volume };

/// A structured mesh's counts, for the cost estimate (boxes and sheets).
struct StructuredCounts {
  double patches = 0.0;
  double tets = 0.0;        ///< 0: no tets (a surface organ, or a sheet)
  double tet_size_mm = 0.0; ///< the largest cell edge, mm (when tets > 0)
};

/// One shape source of the registry.
struct ShapeSource {
  ShapeKind kind;
  const char* name;        ///< the scene's `type`
  const char* description; ///< one line for help and the docs' table
  std::vector<ShapeParameter> parameters;
  /// False for a shape without interior (a sheet): its organ must be `solid: false`.
  bool has_interior = true;
  NestingCheck nesting = NestingCheck::none;
  ShapeInput input = ShapeInput::none;
  /// The world-space bounds of the shape as written; null: known only once its file is read.
  WorldBox (*bounds)(const ShapeSettings&) = nullptr;
  /// Area (mm^2) and enclosed volume (mm^3) of the shape as written, for the cost estimate; null:
  /// known only once read (the estimate guesses it from the grid).
  std::pair<double, double> (*area_volume)(const ShapeSettings&) = nullptr;
  /// A structured mesh instead of fitted patches (no fit to pay for); null: fitted.
  StructuredCounts (*structured)(const ShapeSettings&, bool solid) = nullptr;
  /// The plan states a solid organ's tet size, made from its base size and area_volume's area
  /// (which must then be within about 1 %); false: "its boundary of about the base size".
  bool plan_tet_size = false;
};

/// Every registered shape source, in the docs' order.
const std::vector<const ShapeSource*>& shape_sources();

/// The member of a kind (every kind has one).
const ShapeSource& shape_source(ShapeKind kind);

/// The member named `name`, or null.
const ShapeSource* find_shape_source(const std::string& name);

/// The registered names, in order.
std::vector<std::string> shape_source_names();

/// Surface area of an ellipsoid of semi-axes `radii_mm`, mm^2 (Thomsen's approximation, within
/// about 1 %).
double ellipsoid_area_mm2(const Eigen::Vector3d& radii_mm);

} // namespace phantasm
