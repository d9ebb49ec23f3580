#include "anatomy/anatomy_settings.hpp"

#include "anatomy/shape_source.hpp"

namespace phantasm {

OrganTable organ_table(const AnatomySettings& anatomy) {
  std::vector<OrganNesting> organs;
  organs.reserve(anatomy.organs.size());
  for (const OrganSettings& organ : anatomy.organs)
    organs.push_back({organ.name, organ.tissue, organ.inside});
  return OrganTable(organs);
}

bool WorldBox::intersects(const WorldBox& other) const {
  return (min_mm.array() <= other.max_mm.array()).all() && (other.min_mm.array() <= max_mm.array()).all();
}

std::optional<WorldBox> analytic_shape_bounds(const ShapeSettings& shape) {
  const ShapeSource& source = shape_source(shape.kind);
  if (source.bounds == nullptr) return std::nullopt;
  return source.bounds(shape);
}

const char* to_string(TetInterfaces interfaces) {
  return interfaces == TetInterfaces::materials ? "materials" : "organs";
}

} // namespace phantasm
