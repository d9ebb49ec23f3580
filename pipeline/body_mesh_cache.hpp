// The body mesh cache: the deformation stage's tet meshes of nested organs (CGAL Mesh_3 and the
// sliver repairs, sim/deform_phantom.hpp's BodyMeshSource) kept beside the anatomy they are cut
// from, so that the subjects of one anatomy (a population sweep) mesh their bodies once.
#pragma once

#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "sim/deform_phantom.hpp"

#include <filesystem>
#include <string>

namespace phantasm {

/// The content hash (SHA-256, hex) that names a body mesh: the anatomy's cache key (which names
/// the organ shapes the mesh is cut from, and the build) and the mesh's inputs as the deformation
/// stage names them (the body, its regions and their nesting, the criteria, the seed). Empty
/// when anatomy_key is (no cache).
std::string body_mesh_cache_key(const std::string& anatomy_key, const std::string& inputs);

/// The bytes of an entry after its header, and back; decoding throws DamagedBytes for bytes that
/// do not hold a mesh.
std::string encode_nested_body_mesh(const NestedBodyMesh& mesh);
NestedBodyMesh decode_nested_body_mesh(std::string_view bytes);

/// A BodyMeshSource over the cache folder: a mesh stored under its key is read (bit for bit what
/// building gives), else built and stored (atomically); processes that need the same key at once
/// build it once (the key's lock file). A damaged entry is built again, with a warning. What was
/// reused or stored is written to `report` and the reporter, which must outlive the source.
/// @return an empty source (build every time) when folder or anatomy_key is empty
BodyMeshSource body_mesh_cache(const std::string& anatomy_key, const std::filesystem::path& folder,
                               StageReport& report, Reporter& reporter);

} // namespace phantasm
