#include "sim/deform_phantom.hpp"

#include "sim/body_embedding.hpp"
#include "sim/build_model.hpp"
#include "sim/load_schedule.hpp"
#include "sim/loads.hpp"

namespace phantasm {

PhantomDeformation deform_phantom(const DeformationSettings& deformation, const OrganTable& organs,
                                  const Phantom& phantom, StageReport& report, Reporter& reporter) {
  using namespace sim_detail;
  const BodyAssignment assignment = assign_bodies(deformation, organs, phantom, report);
  BodyModel built = build_body_model(deformation, organs, phantom, assignment, report);
  ElasticModel& model = built.model;
  PhantomDeformation result;
  if (built.bodies.empty()) {
    report.skipped.push_back("the solve: no organ is moved by a load");
  }
  const double stiffness = nominal_stiffness(model);
  Loads loads = add_loads(deformation.loads, organs, phantom, assignment, built, stiffness, report);
  hold_boundaries(loads.pushes, built, report);
  add_obstacles(deformation.obstacles, built.bodies, stiffness, model, report);
  add_collisions(deformation.collisions, organs, phantom, built.bodies, stiffness, model, report);

  Eigen::MatrixX3d p = model.rest_positions_m;
  if (!built.bodies.empty()) solve_frames(deformation, model, loads, p, result, report, reporter);
  collect_deformations(organs, phantom, assignment, built.bodies, p / k_mm, result);
  return result;
}

Phantom deformed_phantom(const Phantom& phantom, const PhantomDeformation& deformation) {
  Phantom moved = phantom;
  for (std::size_t i = 0; i < moved.organs.size(); ++i) {
    Organ& organ = moved.organs[i];
    const OrganDeformation& d = deformation.organs[i];
    if (organ.surface) organ.surface->set_positions(d.surface_mm);
    if (organ.sheet) organ.sheet->vertices = d.surface_mm;
    if (organ.solid) organ.solid->vertices = d.solid_mm;
  }
  return moved;
}

} // namespace phantasm
