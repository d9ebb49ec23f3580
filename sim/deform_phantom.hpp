// The deformation stage (deform_phantom): bodies from the simulated organs, loads and obstacles,
// quasi-static or dynamic solves, giving the PhantomDeformation the voxelizer reads.
#pragma once

#include "anatomy/phantom.hpp"
#include "anatomy/sliver_repairs.hpp"
#include "core/organ_table.hpp"
#include "core/progress.hpp"
#include "core/stage_report.hpp"
#include "sim/phantom_deformation.hpp"
#include "sim/sim_settings.hpp"

#include <functional>
#include <string>

namespace phantasm {

/// A body's one tet mesh of the organs nested in it, and what its sliver repairs did (the log says).
struct NestedBodyMesh {
  TetMesh mesh;
  SliverRepairs repairs;
};

/// Where the deformation stage gets a body's tet mesh of nested organs (CGAL Mesh_3 and the
/// sliver repairs: seconds to minutes on real anatomy). `inputs` names everything that shapes the
/// mesh besides the phantom's organ shapes (the body, its regions and their nesting, the
/// criteria, the seed); `build` makes it. A source that keeps meshes across runs
/// (pipeline/body_mesh_cache.hpp) returns the kept mesh for the same phantom and `inputs`, bit
/// for bit what `build` gives; an empty source builds every time.
using BodyMeshSource =
    std::function<NestedBodyMesh(const std::string& inputs, const std::function<NestedBodyMesh()>& build)>;

/// Deforms the phantom as the settings say (docs/method.md sections 2-3) [choices documented in
/// docs/deformation.md]: each simulated organ whose container does not move becomes a body
/// (its tet mesh; each tet takes the material of the innermost organ holding its centroid);
/// organs nested in a body are embedded in its tets; a body inside a fixed or unmoving organ
/// has its boundary held there. Gravity acts on the bodies' masses; a displacement load pulls
/// the organ's surface points in its region to their displaced places by stiff springs.
/// Quasi-static mode solves for equilibrium (in `load_steps` increments); dynamic mode steps
/// `frames` times and keeps the last frame. What was modelled goes into `report`.
/// @param deformation mode, solver, loads, obstacles, collisions, materials, organs' mechanics
/// @param organs the organ table, in the phantom's organ order
/// @param body_meshes where bodies' tet meshes of nested organs come from (empty: built here)
/// @throws SettingError naming the setting (a collision of organs that are not bodies of their
/// own with a closed surface, a displacement load on an organ that is not simulated, a
/// position-based solver in quasi-static mode)
/// @throws InputError when a body is held by nothing in quasi-static mode, a material is not
/// defined, an enclosed volume is asked of an open sheet, or a solve goes non-finite
PhantomDeformation deform_phantom(const DeformationSettings& deformation, const OrganTable& organs,
                                  const Phantom& phantom, StageReport& report, Reporter& reporter,
                                  const BodyMeshSource& body_meshes = {});

/// The phantom with every organ moved to its deformed place (patches follow their base).
Phantom deformed_phantom(const Phantom& phantom, const PhantomDeformation& deformation);

} // namespace phantasm
