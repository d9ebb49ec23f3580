#include "anatomy/shape_source.hpp"

#include <cmath>
#include <stdexcept>

namespace phantasm {

// The members, one per file of anatomy/shape_sources/.
const ShapeSource& ellipsoid_shape_source();
const ShapeSource& superquadric_shape_source();
const ShapeSource& box_shape_source();
const ShapeSource& sheet_shape_source();
const ShapeSource& mesh_shape_source();
const ShapeSource& label_volume_shape_source();

const std::vector<const ShapeSource*>& shape_sources() {
  // The registrations: a new source adds its line here and its declaration above
  // (docs/architecture.md, Adding a variant).
  static const std::vector<const ShapeSource*> sources{
      &ellipsoid_shape_source(), &superquadric_shape_source(), &box_shape_source(),
      &sheet_shape_source(),     &mesh_shape_source(),         &label_volume_shape_source()};
  return sources;
}

const ShapeSource& shape_source(ShapeKind kind) {
  for (const ShapeSource* source : shape_sources())
    if (source->kind == kind) return *source;
  throw std::logic_error("a shape kind without a member of the shape source registry");
}

const ShapeSource* find_shape_source(const std::string& name) {
  for (const ShapeSource* source : shape_sources())
    if (name == source->name) return source;
  return nullptr;
}

std::vector<std::string> shape_source_names() {
  std::vector<std::string> names;
  for (const ShapeSource* source : shape_sources())
    names.emplace_back(source->name);
  return names;
}

double ellipsoid_area_mm2(const Eigen::Vector3d& r) {
  constexpr double p = 1.6075;
  return 4.0 * M_PI *
         std::pow((std::pow(r.x() * r.y(), p) + std::pow(r.x() * r.z(), p) + std::pow(r.y() * r.z(), p)) /
                      3.0,
                  1.0 / p);
}

const char* to_string(ShapeKind kind) {
  return shape_source(kind).name;
}

} // namespace phantasm
