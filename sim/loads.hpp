// The scene's loads as terms of the model: gravity on the bodies' masses, displacement loads as
// stiff springs, the release of held boundary near them, and obstacles. Internal to sim.
#pragma once

#include "sim/build_model.hpp"

#include <Eigen/Core>

#include <functional>
#include <vector>

namespace phantasm::sim_detail {

/// A displacement load's springs: which model point constraints, and their rest targets (m).
struct PushedPoints {
  const LoadSettings* load = nullptr;
  std::vector<std::size_t> constraints;
  std::vector<Eigen::Vector3d> rest_m;
};

/// Where a displacement load takes a rest point (m) when the fraction `amount` of it applies:
/// turned by amount x rotation_deg about the load's axis, then moved by amount x displacement.
Eigen::Vector3d loaded_position_m(const LoadSettings& load, const Eigen::Vector3d& rest_m, double amount);

/// The loads of the scene on the model.
struct Loads {
  Eigen::MatrixX3d acceleration;    ///< per model vertex, m/s^2 (gravity)
  std::vector<PushedPoints> pushes; ///< one per displacement load that reaches a body
  double growth_moved_m = 0.0;      ///< the largest rest-surface motion of a growth load (sim/growth.hpp)
};

/// What a load type's second half reads and changes when its load acts on the model.
struct LoadTarget {
  const OrganTable& organs;
  const Phantom& phantom;
  const BodyAssignment& assignment;
  BodyModel& built;
  double nominal_stiffness;
  StageReport& report;
  Loads& loads;
};

/// How a load type acts on the model: the second half of its member of the load type registry
/// (sim/load_type.hpp), keyed by the same kind, in sim/load_types/apply_NAME.cpp.
struct LoadEntry {
  LoadKind kind;
  /// Adds `load`, deformation.loads[index], to the target's model and loads, saying what was
  /// modelled or skipped in its report.
  void (*add)(const LoadSettings& load, std::size_t index, LoadTarget& target) = nullptr;
};

/// Every load type's entry, in the registry's order.
const std::vector<const LoadEntry*>& load_entries();

/// The entry of a kind (every kind has one).
const LoadEntry& load_entry(LoadKind kind);

/// The index of the organ a load acts on (its `organ`).
/// @throws SettingError at deformation.loads[index].organ when the phantom has no such organ
std::size_t loaded_organ(const LoadSettings& load, std::size_t index, const OrganTable& organs);

/// Every load on the model by its type's entry: gravity on the bodies it acts on, every
/// displacement load as springs of 10^4 x `nominal_stiffness` from the organ's surface points in
/// its region (embedded in their body) to their displaced places, added to `built.model.points`
/// at full displacement. Loads that reach no body go into `report` as skipped. Growth loads act on
/// the bodies' tets (build_body_model); here only their scale of motion is kept.
Loads add_loads(const std::vector<LoadSettings>& load_settings, const OrganTable& organs,
                const Phantom& phantom, const BodyAssignment& assignment, BodyModel& built,
                double nominal_stiffness, StageReport& report);

/// Fixes the held boundary vertices (`built.held`) in the model, except those within 1.5 region
/// radii of a displacement load's centre.
void hold_boundaries(const std::vector<PushedPoints>& pushes, BodyModel& built, StageReport& report);

/// The scene's obstacles at rest in the model, with a contact penalty of 10^4 x
/// `nominal_stiffness` (none without bodies: then they go into `report` as skipped).
void add_obstacles(const std::vector<ObstacleSettings>& obstacles, const std::vector<Body>& bodies,
                   double nominal_stiffness, ElasticModel& model, StageReport& report);

/// Replaces the model's obstacles by the scene's, each moved by `amount_of` it times its
/// displacement.
void place_obstacles(const std::vector<ObstacleSettings>& obstacles,
                     const std::function<double(const ObstacleSettings&)>& amount_of, ElasticModel& model);

} // namespace phantasm::sim_detail
