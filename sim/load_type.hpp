// The registry of load types: one member per type (sim/load_types/NAME.cpp), each the one place
// that knows its scene keys and their bounds, its help, its provenance fields, its plan line and
// its name in warnings, the organs it acts on and its own consistency checks. Eigen and the
// standard library only, so the scene parses, checks and records loads (and the cost estimate
// may read the members) without the solver; how a member acts on the model lives beside it in
// sim/load_types/apply_NAME.cpp (sim/loads.hpp). Adding a load type: docs/architecture.md,
// "Adding a variant".
#pragma once

#include "sim/sim_settings.hpp"

#include <Eigen/Core>

#include <limits>
#include <string>
#include <vector>

namespace phantasm {

/// A scene key of a load type (under deformation.loads[i], beside `type`). A key of a nested
/// mapping is written as its path, "rotation.angle_deg", after the mapping's own parameter.
struct LoadParameter {
  enum class Kind {
    number,        ///< one number into `number`
    vector3,       ///< three numbers into `vector` (with `unit_vector`: not zero, then normalized)
    organ,         ///< the name of the organ it acts on into `text` (must exist, not be fixed)
    organs,        ///< a list of organ names into `names` (each must exist)
    name_or_names, ///< one name or a non-empty list of them into `names`
    choice,        ///< one of `choices` into `text`
    motion,        ///< constant, ramp or sine into LoadSettings::motion
    mapping,       ///< a mapping whose keys are the parameters "KEY.*" that follow it
  };
  const char* key = "";
  Kind kind = Kind::number;
  double LoadSettings::*number = nullptr;                  ///< Kind::number
  Eigen::Vector3d LoadSettings::*vector = nullptr;         ///< Kind::vector3
  std::string LoadSettings::*text = nullptr;               ///< Kind::organ, Kind::choice
  std::vector<std::string> LoadSettings::*names = nullptr; ///< Kind::organs, Kind::name_or_names
  double min = -std::numeric_limits<double>::infinity();   ///< accepted values (number, vector3)
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false, max_exclusive = false;
  const char* unit = "";
  bool required = false;
  /// Required only when the load does not have this key ("rotation": a turn alone needs no
  /// displacement); null: always as `required` says.
  const char* unless = nullptr;
  /// Keys that make it the other one of two alternatives: when the load has any of them this key
  /// is not read, and giving it too is refused ("expected organ or region, not both"); its own
  /// required alternative's keys are read only when one of them is given (`required_with`).
  std::vector<std::string> excluded_by = {};
  /// Keys of its alternative: required only when the load has one of them.
  std::vector<std::string> required_with = {};
  bool unit_vector = false;              ///< Kind::vector3
  std::vector<std::string> choices = {}; ///< Kind::choice
  const char* expected = "";             ///< Kind::mapping, Kind::name_or_names: a missing key's message
  /// Whether provenance records it for this load (an alternative not taken is not); null: always.
  bool (*recorded)(const LoadSettings&) = nullptr;
};

/// A problem of a load found by its member's check: the key it is about (under
/// deformation.loads[i]) and "expected ..., found ...".
struct LoadProblem {
  std::string key;
  std::string message;
};

/// An organ of the scene as a load's check sees it.
struct LoadOrgan {
  std::string name;
  bool solid = true;
};

/// One load type of the registry.
struct LoadType {
  LoadKind kind;
  const char* name;        ///< the scene's `type`
  const char* description; ///< one line for help and the docs' table
  std::vector<LoadParameter> parameters;
  /// It acts by a change of its tets' rest volume (sim/growth.hpp), not by a force: the solid
  /// organs holding its organ are simulated with it, and the growth machinery solves it.
  bool changes_rest_volume = false;
  /// Its acceleration_m_s2 acts on the bodies' masses (the stiffness check under gravity).
  bool accelerates_masses = false;
  /// It acts on the organ named `organ` (which is then simulated).
  bool (*acts_on)(const LoadSettings&, const std::string& organ) = nullptr;
  /// Its line of the deformation plan, before the motion of a dynamic scene.
  std::string (*plan)(const LoadSettings&) = nullptr;
  /// The load named in a warning ("gravity (9.81 m/s^2)").
  std::string (*summary)(const LoadSettings&) = nullptr;
  /// The problems of load `index` of `deformation` that are its own (beyond its keys' bounds and
  /// the organs it names); may be null.
  std::vector<LoadProblem> (*check)(const DeformationSettings& deformation, std::size_t index,
                                    const std::vector<LoadOrgan>& organs) = nullptr;
};

/// Every registered load type, in the docs' order.
const std::vector<const LoadType*>& load_types();

/// The member of a kind (every kind has one).
const LoadType& load_type(LoadKind kind);

/// The member named `name`, or null.
const LoadType* find_load_type(const std::string& name);

/// The registered names, in order.
std::vector<std::string> load_type_names();

} // namespace phantasm
