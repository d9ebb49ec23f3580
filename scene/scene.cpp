#include "scene/scene.hpp"

namespace phantasm {

ImageGrid GridSettings::grid() const {
  const auto direction = direction_from_axis_code(orientation);
  return make_centered_grid(field_of_view_mm, voxel_size_mm, center_mm,
                            direction ? *direction : Eigen::Matrix3d::Identity());
}

const MaterialSettings* Scene::find_material(const std::string& material_name) const {
  for (const auto& m : materials) {
    if (m.name == material_name) return &m;
  }
  return nullptr;
}

const OrganSettings* Scene::find_organ(const std::string& organ_name) const {
  for (const auto& o : anatomy.organs) {
    if (o.name == organ_name) return &o;
  }
  return nullptr;
}

SourceLocation Scene::location_of(const std::string& key_path) const {
  // Fall back to the nearest enclosing key that was seen.
  std::string path = key_path;
  while (!path.empty()) {
    const auto found = locations.find(path);
    if (found != locations.end()) return found->second;
    const auto cut = path.find_last_of(".[");
    if (cut == std::string::npos) break;
    path.resize(cut);
  }
  return SourceLocation{file.string(), 0, 0};
}

const char* to_string(ShapeKind kind) {
  switch (kind) {
  case ShapeKind::ellipsoid: return "ellipsoid";
  case ShapeKind::superquadric: return "superquadric";
  case ShapeKind::box: return "box";
  case ShapeKind::sheet: return "sheet";
  case ShapeKind::mesh: return "mesh";
  case ShapeKind::label_volume: return "label_volume";
  }
  return "?";
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

const char* to_string(SequenceKind kind) {
  switch (kind) {
  case SequenceKind::spin_echo: return "spin_echo";
  case SequenceKind::spoiled_gre: return "spoiled_gre";
  case SequenceKind::inversion_recovery: return "inversion_recovery";
  case SequenceKind::bssfp: return "bssfp";
  case SequenceKind::mprage: return "mprage";
  }
  return "?";
}

const char* to_string(Readout readout) {
  return readout == Readout::spin_echo ? "spin_echo" : "gradient_echo";
}

} // namespace phantasm
