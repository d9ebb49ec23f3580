// Building the anatomy of a scene (build_phantom): seeded variation, target shapes from settings,
// meshes and label volumes, tet meshes and fitted patch surfaces. Entry point of the stage.
#pragma once

#include "anatomy/anatomy_settings.hpp"
#include "anatomy/implicit_shape.hpp"
#include "anatomy/organ.hpp"
#include "core/byte_codec.hpp"
#include "core/grid.hpp"
#include "core/progress.hpp"

#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace phantasm {

/// Builds every organ of the anatomy settings: seeded size variation (nesting is kept), target
/// shapes, CGAL tet meshes for solid organs, fitted patch surfaces. Deterministic for given
/// settings (anatomy.seed included).
/// @param anatomy the organs, their shapes and the base mesh sizes
/// @param files shape data of organs whose shape is a mesh or label volume, by organ name
/// @throws InputError for shapes that cannot be built (invalid meshes, empty labels)
Phantom build_phantom(const AnatomySettings& anatomy, const std::map<std::string, ShapeData>& files,
                      Reporter& reporter);

/// Bytes that do not hold the geometry of the organs they were read for.
using DamagedGeometry = DamagedBytes;

/// The geometry of a built phantom's organs (patch surfaces with their bumps, sheets, tet
/// meshes, fit reports) as bytes, everything but the target shapes, which phantom_from_geometry
/// makes again from the settings (a file's shape on its first use: most runs that read the cache
/// never ask it anything). For the anatomy cache.
/// @param phantom as build_phantom returned it (every surface at rest)
std::string encode_organ_geometry(const Phantom& phantom);

/// The phantom build_phantom(anatomy, files, ...) made, from its encode_organ_geometry bytes:
/// targets made again, geometry decoded, the same log lines; bit for bit the built phantom.
/// @throws DamagedGeometry when the bytes are damaged or were written for other organs
Phantom phantom_from_geometry(const AnatomySettings& anatomy, const std::map<std::string, ShapeData>& files,
                              std::string_view bytes, Reporter& reporter);

/// The implicit shape of an organ's settings (before variation); files supply mesh and label shapes.
std::unique_ptr<ImplicitShape> target_shape(const ShapeSettings& shape, const ShapeData* file,
                                            const std::string& organ);

/// An implicit shape from a closed triangle mesh: minus the signed distance (positive inside).
std::unique_ptr<ImplicitShape> make_mesh_shape(const TriangleMesh& mesh, const std::string& what);

/// An implicit shape from labels of a label volume: the trilinear interpolation of the
/// indicator of their union (Gaussian-smoothed when asked) minus 1/2 (positive inside). Only the
/// union's bounding box (wider by the interpolation's and the kernel's reach) is kept.
/// @param grid the volume's grid (world RAS mm)
/// @param labels grid.voxel_count() labels, i fastest
/// @param label_set the labels whose union is the shape
/// @param smoothing_mm standard deviation of the Gaussian applied to the indicator, mm (0: none)
/// @param what names the shape in messages
/// @throws InputError when no voxel holds one of the labels
std::unique_ptr<ImplicitShape> make_label_shape(const ImageGrid& grid,
                                                const std::vector<std::int32_t>& labels,
                                                const std::vector<std::int32_t>& label_set,
                                                double smoothing_mm, const std::string& what);

} // namespace phantasm
