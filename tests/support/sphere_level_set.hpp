#pragma once

// The level set of a sphere for the voxelizer's tests: a level-4 icosphere (5120 triangles)
// scaled and moved, through the level set's mesh constructor.

#include "geometry/triangle_mesh.hpp"
#include "voxelize/level_set.hpp"

#include <Eigen/Core>

namespace phantasm::testing {

/// A sphere of `radius` mm around `centre` (RAS mm) in voxels of `voxel_mm`.
inline LevelSet sphere_level_set(double radius, const Eigen::Vector3d& centre, double voxel_mm) {
  TriangleMesh mesh = unit_icosphere(4);
  mesh.vertices = (mesh.vertices * radius).rowwise() + centre.transpose();
  return LevelSet(mesh, voxel_mm);
}

} // namespace phantasm::testing
