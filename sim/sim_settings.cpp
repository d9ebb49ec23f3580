#include "sim/sim_settings.hpp"

namespace phantasm {

const MaterialSettings* DeformationSettings::find_material(const std::string& material_name) const {
  for (const auto& m : materials) {
    if (m.name == material_name) return &m;
  }
  return nullptr;
}

const char* to_string(DeformationMode mode) {
  switch (mode) {
  case DeformationMode::none: return "none";
  case DeformationMode::quasi_static: return "quasi_static";
  case DeformationMode::dynamic: return "dynamic";
  }
  return "?";
}

const char* to_string(SolverMethod method) {
  switch (method) {
  case SolverMethod::local_global: return "local_global";
  case SolverMethod::newton: return "newton";
  case SolverMethod::gauss_seidel_pbd: return "gauss_seidel_pbd";
  case SolverMethod::jacobi_chebyshev: return "jacobi_chebyshev";
  case SolverMethod::xpbd: return "xpbd";
  }
  return "?";
}

const char* to_string(LoadKind kind) {
  return kind == LoadKind::gravity ? "gravity" : "displacement";
}

const char* to_string(ObstacleShape shape) {
  return shape == ObstacleShape::sphere ? "sphere" : "half_space";
}

const char* to_string(MotionProfile motion) {
  switch (motion) {
  case MotionProfile::constant: return "constant";
  case MotionProfile::ramp: return "ramp";
  case MotionProfile::sine: return "sine";
  }
  return "?";
}

} // namespace phantasm
