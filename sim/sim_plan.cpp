#include "sim/sim_plan.hpp"

#include "core/format.hpp"
#include "sim/load_type.hpp"

#include <algorithm>
#include <sstream>

namespace phantasm {
namespace {

/// The nearest simulated organ containing organ i, or -1 when none does.
int simulated_container(const OrganTable& organs, const std::vector<OrganMotion>& motion, std::size_t i) {
  // The bound guards against a cycle, which the scene's validation rejects.
  std::size_t steps = 0;
  for (int j = organs[i].parent; j >= 0 && steps <= organs.size();
       j = organs[static_cast<std::size_t>(j)].parent, ++steps) {
    if (motion[static_cast<std::size_t>(j)] == OrganMotion::simulated) return j;
  }
  return -1;
}

/// Whether organ i has a tet mesh (organs without mechanics settings count as solid, the default).
bool solid(const DeformationSettings& d, int i) {
  return static_cast<std::size_t>(i) >= d.organs.size() || d.organs[static_cast<std::size_t>(i)].solid;
}

} // namespace

StageReport plan_sim(const DeformationSettings& d, const OrganTable& organs) {
  StageReport report;
  report.stage = "sim";
  if (d.mode == DeformationMode::none) {
    report.status = "skipped";
    report.skipped.push_back(
        "deformation (deformation.mode is none): the deformed state equals the reference");
    return report;
  }
  const auto motion = classify_organ_motion(d, organs);
  for (std::size_t i = 0; i < organs.size(); ++i) {
    if (motion[i] == OrganMotion::simulated) {
      const MaterialSettings* material =
          i < d.organs.size() ? d.find_material(d.organs[i].material) : nullptr;
      std::ostringstream line;
      line << organs[i].name << ": simulated";
      if (material != nullptr) {
        line << " (" << material->name << ", E = " << material->youngs_modulus_Pa
             << " Pa, nu = " << material->poisson_ratio << ")";
      }
      report.modelled.push_back(line.str());
    } else if (motion[i] == OrganMotion::fixed) {
      report.modelled.push_back(organs[i].name + ": held fixed (deformation.fixed)");
    } else if (const int carrier = simulated_container(organs, motion, i);
               carrier >= 0 && solid(d, carrier)) {
      report.modelled.push_back(organs[i].name + ": no load of its own; inside the simulated " +
                                organs[static_cast<std::size_t>(carrier)].name +
                                ", it follows it (embedded in its tets)");
    } else if (carrier >= 0) {
      report.skipped.push_back(organs[i].name + ": inside the shell " +
                               organs[static_cast<std::size_t>(carrier)].name +
                               ", which has no interior to carry it; it stays in place");
    } else {
      report.skipped.push_back(organs[i].name + ": no load acts on it, carried rigidly");
    }
  }
  for (const auto& load : d.loads) {
    std::ostringstream line;
    line << load_type(load.kind).plan(load);
    if (d.mode == DeformationMode::dynamic) line << ", " << to_string(load.motion) << " motion";
    report.modelled.push_back(line.str());
  }
  for (const ObstacleSettings& o : d.obstacles) {
    std::ostringstream line;
    if (o.shape == ObstacleShape::sphere) {
      line << "sphere obstacle centred at " << format_vector(o.point_mm) << " mm, radius " << o.radius_mm
           << " mm";
    } else {
      line << "half-space obstacle through " << format_vector(o.point_mm) << " mm, normal "
           << format_vector(o.normal);
    }
    line << ", moved by " << format_vector(o.displacement_mm) << " mm (frictionless contact)";
    report.modelled.push_back(line.str());
  }
  for (const CollisionSettings& c : d.collisions) {
    if (c.organs.size() == 2)
      report.modelled.push_back("collision of " + c.organs[0] + " and " + c.organs[1] +
                                " (frictionless contact of their surfaces)");
  }
  std::ostringstream solver;
  solver << to_string(d.solver.method) << " solver, " << to_string(d.mode) << ", at most "
         << d.solver.max_iterations << " iterations, converged at a residual of "
         << d.solver.relative_residual_tolerance
         << " of the loads' force per vertex and a Newton step within that fraction of the largest "
            "displacement";
  if (d.mode == DeformationMode::dynamic)
    solver << ", " << d.frames << " frames of " << d.time_step_s << " s";
  else if (d.load_steps > 1)
    solver << ", loads applied in " << d.load_steps << " steps";
  report.modelled.push_back(solver.str());
  if (!d.head_scale.identity()) {
    report.modelled.push_back("then the whole head grown by " + format_vector(d.head_scale.factors()) +
                              " (x, y, z) about " +
                              (d.head_scale.center_mm ? format_vector(*d.head_scale.center_mm) + " mm"
                                                      : std::string("its centre")) +
                              ", fixed organs included: volumes change by " +
                              format_number(d.head_scale.factors().prod()) + " (deformation.head_scale)");
  }
  return report;
}

} // namespace phantasm
