// Building the ElasticModel of the deformation stage from the scene's bodies: materials, shells,
// enclosed volumes, held boundaries, and collisions between organs' surfaces. Internal to sim.
#pragma once

#include "sim/body_embedding.hpp"
#include "sim/elastic_model.hpp"

#include <vector>

namespace phantasm::sim_detail {

/// The model of the bodies, before loads.
struct BodyModel {
  ElasticModel model;
  std::vector<Body> bodies;              ///< in scene order of their organs
  std::vector<int> held;                 ///< boundary vertices of bodies inside an organ that does not move
  std::vector<std::size_t> grown_tets;   ///< per load of the scene, the tets a growth load grew
  double region_growth_moved_m = 0.0;    ///< the largest rest-surface motion of a grown atlas region
  std::vector<int> growth_load_of_tet;   ///< per tet of the model, the growth load growing it (-1: none)
  std::vector<double> growth_rest_ratio; ///< per load, the rest-volume ratio applied to its tets (1: none)
};

/// The model of every body of `assignment` [choices documented in docs/deformation.md]: a solid
/// organ's tet mesh, or with organs nested in it one tet mesh of all of them (at the phantom's
/// tet size), each tet with the material of its subdomain's organ; a surface organ as a shell of its
/// triangles (with its enclosed volume kept when the settings ask). What was modelled goes into `report`.
/// @param body_meshes where tet meshes of nested organs come from (empty: built here)
/// @throws InputError for an undefined material, or an enclosed volume asked of an open sheet
BodyModel build_body_model(const DeformationSettings& deformation, const OrganTable& organs,
                           const Phantom& phantom, const BodyAssignment& assignment, StageReport& report,
                           const BodyMeshSource& body_meshes = {});

/// The mean diagonal of the model's elastic matrix per vertex (N/m): the scale of the stiff
/// penalties (displacement springs, contacts), 10^4 times this.
double nominal_stiffness(const ElasticModel& model);

/// The contact surfaces of the scene's collisions (each organ's closed surface: a solid body's
/// boundary faces, a closed shell's triangles) and their pairs.
/// @throws SettingError naming the pair's key path when an organ of a pair is not simulated as a
/// body of its own or has no closed surface
void add_collisions(const std::vector<CollisionSettings>& collisions, const OrganTable& organs,
                    const Phantom& phantom, const std::vector<Body>& bodies, double nominal_stiffness,
                    ElasticModel& model, StageReport& report);

} // namespace phantasm::sim_detail
