#include "anatomy/shape_source.hpp"

#include "core/registry.hpp"

#include <cmath>

namespace phantasm {

// The members, one per file of anatomy/shape_sources/.
const ShapeSource& ellipsoid_shape_source();
const ShapeSource& superquadric_shape_source();
const ShapeSource& box_shape_source();
const ShapeSource& sheet_shape_source();
const ShapeSource& mesh_shape_source();
const ShapeSource& label_volume_shape_source();

namespace {

const Registry<ShapeSource, ShapeKind>& shape_source_registry() {
  // The registrations: a new source adds its line here and its declaration above
  // (docs/architecture.md, Adding a variant).
  static const Registry<ShapeSource, ShapeKind> sources(
      "shape source", &ShapeSource::kind,
      {&ellipsoid_shape_source(), &superquadric_shape_source(), &box_shape_source(), &sheet_shape_source(),
       &mesh_shape_source(), &label_volume_shape_source()});
  return sources;
}

} // namespace

const std::vector<const ShapeSource*>& shape_sources() {
  return shape_source_registry().members();
}

const ShapeSource& shape_source(ShapeKind kind) {
  return shape_source_registry().at(kind);
}

const ShapeSource* find_shape_source(const std::string& name) {
  return shape_source_registry().find(name);
}

std::vector<std::string> shape_source_names() {
  return shape_source_registry().names();
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
