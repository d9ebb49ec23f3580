#include "sim/sim_plan.hpp"

#include "core/format.hpp"

#include <algorithm>
#include <sstream>

namespace phantasm {
namespace {

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

} // namespace

std::vector<OrganMotion> classify_organ_motion(const Scene& scene) {
  const auto& organs = scene.anatomy.organs;
  const DeformationSettings& d = scene.deformation;
  std::vector<OrganMotion> motion(organs.size(), OrganMotion::rigid);
  if (d.mode == DeformationMode::none) return motion;
  for (std::size_t i = 0; i < organs.size(); ++i) {
    const std::string& name = organs[i].name;
    if (contains(d.fixed, name)) {
      motion[i] = OrganMotion::fixed;
      continue;
    }
    for (const auto& load : d.loads) {
      const bool acts = load.kind == LoadKind::displacement
                            ? load.organ == name
                            : load.organs.empty() || contains(load.organs, name);
      if (acts) motion[i] = OrganMotion::simulated;
    }
  }
  return motion;
}

namespace {

/// The nearest simulated organ containing organ i, or null when none does.
const OrganSettings* simulated_container(const Scene& scene, const std::vector<OrganMotion>& motion,
                                         std::size_t i) {
  const auto& organs = scene.anatomy.organs;
  for (std::string inside = organs[i].inside; !inside.empty();) {
    std::size_t j = 0;
    while (j < organs.size() && organs[j].name != inside)
      ++j;
    if (j == organs.size()) return nullptr;
    if (motion[j] == OrganMotion::simulated) return &organs[j];
    inside = organs[j].inside;
  }
  return nullptr;
}

} // namespace

StageReport plan_sim(const Scene& scene) {
  StageReport report;
  report.stage = "sim";
  const DeformationSettings& d = scene.deformation;
  if (d.mode == DeformationMode::none) {
    report.status = "skipped";
    report.skipped.push_back(
        "deformation (deformation.mode is none): the deformed state equals the reference");
    return report;
  }
  const auto motion = classify_organ_motion(scene);
  const auto& organs = scene.anatomy.organs;
  for (std::size_t i = 0; i < organs.size(); ++i) {
    if (motion[i] == OrganMotion::simulated) {
      const MaterialSettings* material = scene.find_material(organs[i].material);
      std::ostringstream line;
      line << organs[i].name << ": simulated";
      if (material != nullptr) {
        line << " (" << material->name << ", E = " << material->youngs_modulus_Pa
             << " Pa, nu = " << material->poisson_ratio << ")";
      }
      report.modelled.push_back(line.str());
    } else if (motion[i] == OrganMotion::fixed) {
      report.modelled.push_back(organs[i].name + ": held fixed (deformation.fixed)");
    } else if (const OrganSettings* carrier = simulated_container(scene, motion, i);
               carrier && carrier->solid) {
      report.modelled.push_back(organs[i].name + ": no load of its own; inside the simulated " +
                                carrier->name + ", it follows it (embedded in its tets)");
    } else if (carrier) {
      report.skipped.push_back(organs[i].name + ": inside the shell " + carrier->name +
                               ", which has no interior to carry it; it stays in place");
    } else {
      report.skipped.push_back(organs[i].name + ": no load acts on it, carried rigidly");
    }
  }
  for (const auto& load : d.loads) {
    std::ostringstream line;
    if (load.kind == LoadKind::gravity) {
      line << "gravity " << format_vector(load.acceleration_m_s2) << " m/s^2";
    } else {
      line << "displacement " << format_vector(load.displacement_mm) << " mm";
      if (load.rotation_deg != 0.0)
        line << " and turn of " << load.rotation_deg << " degrees about " << format_vector(load.rotation_axis)
             << " through " << format_vector(load.rotation_center_mm) << " mm";
      line << " of " << load.organ << " within " << load.region_radius_mm << " mm of "
           << format_vector(load.region_center_mm);
    }
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
         << d.solver.max_iterations << " iterations, stop at relative energy decrease "
         << d.solver.relative_energy_tolerance << " or position change " << d.solver.position_tolerance_mm
         << " mm";
  if (d.mode == DeformationMode::dynamic)
    solver << ", " << d.frames << " frames of " << d.time_step_s << " s";
  else if (d.load_steps > 1)
    solver << ", loads applied in " << d.load_steps << " steps";
  report.modelled.push_back(solver.str());
  return report;
}

} // namespace phantasm
