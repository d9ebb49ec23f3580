// The scene's loads on the model, each by its load type's entry (sim/load_types/apply_*.cpp), the
// held boundary released near displacement loads, and obstacles placed at rest or moved.
#include "sim/loads.hpp"

#include "core/error.hpp"
#include "core/format.hpp"
#include "core/registry.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace phantasm::sim_detail {

Eigen::Vector3d loaded_position_m(const LoadSettings& load, const Eigen::Vector3d& rest_m, double amount) {
  const Eigen::Vector3d centre_m = k_mm * load.rotation_center_mm;
  const Eigen::AngleAxisd turn(amount * load.rotation_deg * M_PI / 180.0, load.rotation_axis);
  return centre_m + turn * (rest_m - centre_m) + amount * k_mm * load.displacement_mm;
}

// The second halves of the load types, one per file of sim/load_types/apply_*.cpp.
const LoadEntry& gravity_load_entry();
const LoadEntry& displacement_load_entry();
const LoadEntry& growth_load_entry();

namespace {

const Registry<LoadEntry, LoadKind>& load_entry_registry() {
  // The registrations: a new load type adds its line here and its declaration above, beside its
  // member in sim/load_types.cpp (docs/architecture.md, Adding a variant).
  static const Registry<LoadEntry, LoadKind> entries(
      "load entry", &LoadEntry::kind,
      {&gravity_load_entry(), &displacement_load_entry(), &growth_load_entry()});
  return entries;
}

} // namespace

const std::vector<const LoadEntry*>& load_entries() {
  return load_entry_registry().members();
}

const LoadEntry& load_entry(LoadKind kind) {
  return load_entry_registry().at(kind);
}

std::size_t loaded_organ(const LoadSettings& load, std::size_t index, const OrganTable& organs) {
  const int organ = organs.index_of(load.organ);
  if (organ < 0) {
    throw SettingError("deformation.loads[" + std::to_string(index) + "].organ",
                       "expected an organ of the phantom, found '" + load.organ + "'");
  }
  return static_cast<std::size_t>(organ);
}

Loads add_loads(const std::vector<LoadSettings>& load_settings, const OrganTable& organs,
                const Phantom& phantom, const BodyAssignment& assignment, BodyModel& built,
                double nominal_stiffness, StageReport& report) {
  Loads loads;
  loads.acceleration = Eigen::MatrixX3d::Zero(built.model.vertex_count(), 3);
  LoadTarget target{organs, phantom, assignment, built, nominal_stiffness, report, loads};
  for (std::size_t k = 0; k < load_settings.size(); ++k)
    load_entry(load_settings[k].kind).add(load_settings[k], k, target);
  return loads;
}

void hold_boundaries(const std::vector<PushedPoints>& pushes, BodyModel& built, StageReport& report) {
  ElasticModel& model = built.model;
  // The container holds a body's boundary, except where a load pushes (a retractor through an
  // opening of the skull, a paddle on the skin): boundary vertices within 1.5 region radii of a
  // displacement load's centre are released [choice], so the pushed surface is not pinned to a
  // held layer next to it.
  std::size_t released = 0;
  for (int v : built.held) {
    const Eigen::Vector3d x_mm = model.rest_positions_m.row(v).transpose() / k_mm;
    bool in_opening = false;
    for (const PushedPoints& push : pushes)
      in_opening |= (x_mm - push.load->region_center_mm).norm() <= 1.5 * push.load->region_radius_mm;
    if (in_opening) {
      ++released;
    } else {
      model.fixed[static_cast<std::size_t>(v)] = 1;
    }
  }
  if (released > 0) {
    report.modelled.push_back(
        std::to_string(released) +
        " held boundary vertices released within 1.5 region radii of a displacement load");
  }
}

void add_obstacles(const std::vector<ObstacleSettings>& obstacles, const std::vector<Body>& bodies,
                   double nominal_stiffness, ElasticModel& model, StageReport& report) {
  // Obstacles act on every free vertex of every body, by a penalty as stiff as the displacement
  // loads' springs.
  if (!obstacles.empty() && !bodies.empty()) {
    model.contact_stiffness_N_m = 1e4 * nominal_stiffness;
    place_obstacles(
        obstacles, [](const ObstacleSettings&) { return 0.0; }, model);
    for (const ObstacleSettings& o : obstacles) {
      report.modelled.push_back(
          std::string(to_string(o.shape)) + " obstacle " +
          (o.shape == ObstacleShape::sphere
               ? "centred at " + format_vector(o.point_mm) + " mm, radius " + format_number(o.radius_mm) +
                     " mm"
               : "through " + format_vector(o.point_mm) + " mm, normal " + format_vector(o.normal)) +
          ", moved by " + format_vector(o.displacement_mm) + " mm; contacts by a penalty of " +
          format_number(model.contact_stiffness_N_m) + " N/m (10^4 x the mean elastic stiffness)");
    }
  } else if (!obstacles.empty()) {
    report.skipped.push_back("obstacles: no organ is simulated, nothing can touch them");
  }
}

void place_obstacles(const std::vector<ObstacleSettings>& obstacles,
                     const std::function<double(const ObstacleSettings&)>& amount_of, ElasticModel& model) {
  model.obstacles.clear();
  for (const ObstacleSettings& obstacle : obstacles) {
    Obstacle o;
    o.shape = obstacle.shape == ObstacleShape::sphere ? Obstacle::Shape::sphere : Obstacle::Shape::half_space;
    o.point_m = k_mm * (obstacle.point_mm + amount_of(obstacle) * obstacle.displacement_mm);
    o.normal = obstacle.normal;
    o.radius_m = k_mm * obstacle.radius_mm;
    model.obstacles.push_back(o);
  }
}

} // namespace phantasm::sim_detail
