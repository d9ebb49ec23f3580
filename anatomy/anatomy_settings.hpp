// The settings the anatomy stage reads (docs/scene-format.md, section anatomy), filled by the
// scene parser; Eigen and the standard library only, so the scene fills them without CGAL.
#pragma once

#include "core/organ_table.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace phantasm {

/// The organ shape sources; each has its member of the registry (anatomy/shape_source.hpp).
enum class ShapeKind { ellipsoid, superquadric, box, sheet, mesh, label_volume };

/// Which surfaces of the organs nested in a simulated body its conforming tet mesh follows with
/// faces (anatomy.tet_interfaces): every nested organ's, or only those where the material changes
/// (an organ of its container's material is meshed with the container; its surface moves with the
/// tets around it, as every surface does).
enum class TetInterfaces { organs, materials };

/// The target shape of an organ's surface.
struct ShapeSettings {
  ShapeKind kind = ShapeKind::ellipsoid;
  Eigen::Vector3d center_mm{0, 0, 0};    ///< ellipsoid / superquadric centre, RAS mm
  Eigen::Vector3d radii_mm{1, 1, 1};     ///< semi-axes before rotation, mm
  Eigen::Vector3d rotation_deg{0, 0, 0}; ///< rotations about x, then y, then z, degrees
  double exponent_1 = 1.0;               ///< superquadric north-south exponent (1 = ellipsoid)
  double exponent_2 = 1.0;               ///< superquadric east-west exponent (1 = ellipsoid)
  Eigen::Vector3d size_mm{10, 10, 10};   ///< box edge lengths; sheet: x and y extent (z unused)
  Eigen::Vector3i cells{1, 1, 1};        ///< box: hexahedral cells per axis (5 tets each); sheet: x, y
  std::filesystem::path file;            ///< mesh or label volume, resolved against the scene's folder
  /// label volume derived at run time from installed data instead of a file ("colin27",
  /// docs/anatomy-colin27.md); empty for a file
  std::string atlas;
  int label = 0; ///< the first label value given by number (0 when every label is named)
  /// every label of the organ: numbers, or names of the atlas's label table, as written
  std::vector<std::string> labels;
  double smoothing_mm = 0.0; ///< label volume: Gaussian smoothing of the labels' indicator, mm (0: none)
};

/// One organ of the phantom.
struct OrganSettings {
  std::string name;
  std::string tissue;
  std::string material;        ///< a name from the scene's materials
  std::string inside;          ///< the organ that contains this one; empty for the outermost
  bool solid = true;           ///< true: tetrahedralized interior; false: surface (shell, sheet) only
  int base_mesh_triangles = 0; ///< this organ's patch base size; 0 = anatomy.base_mesh_triangles
  ShapeSettings shape;
  double thickness_mm = 1.0; ///< surface organs (solid: false) simulated as shells: wall thickness
  /// closed surface organs simulated as shells: their enclosed volume is kept within this
  /// fraction of rest (a fluid-filled organ); unset: free
  std::optional<double> enclosed_volume_tolerance;
};

struct AnatomySettings {
  double variation = 0.0;        ///< seeded relative variation of organ sizes, 0 = exact
  int base_mesh_triangles = 320; ///< patch base mesh size per organ (the anatomy accuracy knob)
  /// element size (tet circumradius bound, mm) of one conforming tet mesh of a simulated body and
  /// the organs nested in it (the deformation's speed/accuracy knob); 0 (unset): the body is
  /// solved on its own organ's mesh, each tet with the material of the organ holding its centroid
  double tet_size_mm = 0.0;
  /// upper bound of the distance between those meshes' interface triangles and the organs'
  /// surfaces, mm; 0 (unset): a tenth of tet_size_mm
  double tet_facet_distance_mm = 0.0;
  TetInterfaces tet_interfaces = TetInterfaces::organs;
  std::vector<OrganSettings> organs;
  std::uint64_t seed = 0; ///< the scene's seed (size variation, tet meshing), set by the scene
};

/// The organ table of these organs: names, tissues and nesting in scene order.
OrganTable organ_table(const AnatomySettings& anatomy);

/// An axis-aligned box in world space (RAS mm).
struct WorldBox {
  Eigen::Vector3d min_mm;
  Eigen::Vector3d max_mm;

  bool intersects(const WorldBox& other) const;
};

/// The world-space bounding box of a shape as written (its source's `bounds`), or nothing for
/// shapes whose extent is known only once their file is read (meshes, label volumes).
std::optional<WorldBox> analytic_shape_bounds(const ShapeSettings& shape);

/// The shape source's name (its member of the registry, anatomy/shape_sources/).
const char* to_string(ShapeKind kind);
const char* to_string(TetInterfaces interfaces);

} // namespace phantasm
