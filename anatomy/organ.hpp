// The anatomy's result: Organ (target shape, patch surface or sheet, tet mesh) and Phantom, the
// list of organs every later stage reads.
#pragma once

#include "anatomy/anatomy_settings.hpp"
#include "anatomy/implicit_shape.hpp"
#include "anatomy/patch_fit.hpp"
#include "anatomy/patch_surface.hpp"
#include "anatomy/tet_mesh.hpp"
#include "core/grid.hpp"
#include "geometry/shape_data.hpp"
#include "geometry/triangle_mesh.hpp"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

// The anatomy stage's result types, apart from the functions that build them
// (anatomy/phantom.hpp), so that later stages and the writers include only what they read.

namespace phantasm {

/// One organ of a phantom: its target shape, the patch surface that represents it (closed
/// organs) or an open triangle sheet, and for solid organs a tet mesh whose boundary vertices
/// are the patch base vertices.
struct Organ {
  std::string name;
  std::string tissue;
  std::string material;
  std::string inside;                          ///< containing organ, empty for an outermost organ
  std::shared_ptr<const ImplicitShape> target; ///< after seeded variation
  std::optional<PatchSurface> surface;         ///< closed organs
  std::optional<TriangleMesh> sheet;           ///< open sheets (zero thickness)
  std::optional<TetMesh> solid;                ///< solid organs
  /// For each patch base vertex, the tet-mesh vertex it is (solid organs).
  Eigen::VectorXi tet_vertex_of_surface_vertex;
  SourceFit fit; ///< how well the surface matches the source it was fitted to
};

/// The anatomy of a scene.
struct Phantom {
  std::vector<Organ> organs; ///< in scene order
  /// anatomy.tet_size_mm: the element size of the tet meshes of bodies that hold nested organs,
  /// made when the deformation stage knows its bodies (tet_mesh.hpp, mesh_nested_solid)
  double tet_size_mm = 0.0;
  double tet_facet_distance_mm = 0.0; ///< anatomy.tet_facet_distance_mm (0: a tenth of tet_size_mm)
  TetInterfaces tet_interfaces = TetInterfaces::organs; ///< anatomy.tet_interfaces
  std::uint64_t seed = 0;                               ///< the scene's seed, for those meshes

  const Organ* find(const std::string& name) const;
};

} // namespace phantasm
