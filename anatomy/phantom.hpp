#pragma once

#include "anatomy/implicit_shape.hpp"
#include "anatomy/patch_fit.hpp"
#include "anatomy/patch_surface.hpp"
#include "anatomy/tet_mesh.hpp"
#include "core/grid.hpp"
#include "core/progress.hpp"
#include "scene/scene.hpp"

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

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
  PatchFitReport fit; ///< how well the surface matches the target
};

/// A dense triangle mesh or a label volume read from a file, for organs whose shape is a file.
struct ShapeData {
  std::optional<TriangleMesh> mesh;
  std::optional<ImageGrid> label_grid;
  std::vector<std::int32_t> labels; ///< label_grid.voxel_count() values, i fastest
};

/// The anatomy of a scene.
struct Phantom {
  std::vector<Organ> organs; ///< in scene order

  const Organ* find(const std::string& name) const;
};

/// Builds every organ of the scene: seeded size variation (nesting is kept), target shapes,
/// CGAL tet meshes for solid organs, fitted patch surfaces. Deterministic for a given scene.
/// @param files shape data of organs whose shape is a mesh or label volume, by organ name
/// @throws InputError for shapes that cannot be built (invalid meshes, empty labels)
Phantom build_phantom(const Scene& scene, const std::map<std::string, ShapeData>& files, Reporter& reporter);

/// The implicit shape of an organ's settings (before variation); files supply mesh and label shapes.
std::unique_ptr<ImplicitShape> target_shape(const ShapeSettings& shape, const ShapeData* file,
                                            const std::string& organ);

/// An implicit shape from a closed triangle mesh: minus the signed distance (positive inside).
std::unique_ptr<ImplicitShape> make_mesh_shape(const TriangleMesh& mesh, const std::string& what);

/// An implicit shape from one label of a label volume: the trilinear interpolation of the
/// label's indicator minus 1/2 (positive inside).
std::unique_ptr<ImplicitShape> make_label_shape(const ImageGrid& grid,
                                                const std::vector<std::int32_t>& labels, int label,
                                                const std::string& what);

} // namespace phantasm
