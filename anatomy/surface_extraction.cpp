#include "anatomy/surface_extraction.hpp"

#include <algorithm>
#include <cmath>

namespace phantasm {
namespace {

/// Criteria for triangles of edge about `edge_mm`. Mesh_3's facets come out about 1.35 times
/// smaller than the bound (as in criteria_for_boundary_size), and the distance bound of a tenth
/// of an edge keeps the topology of parts thicker than about that.
SurfaceMeshCriteria criteria_for_edge(double edge_mm) {
  SurfaceMeshCriteria criteria;
  criteria.facet_size_mm = 1.35 * edge_mm / std::sqrt(3.0);
  criteria.facet_distance_mm = 0.1 * 1.35 * edge_mm;
  return criteria;
}

/// Edge of an equilateral triangle with area area_mm2 / triangles.
double edge_for(double area_mm2, int triangles) {
  return std::sqrt(area_mm2 / (0.25 * std::sqrt(3.0) * std::max(1, triangles)));
}

} // namespace

TriangleMesh extract_surface_of_size(const ImplicitShape& shape, int triangles, std::uint32_t seed) {
  // First pass: the area of a mesh fine enough to see the shape (edges a sixteenth of the
  // bounding radius, or finer when more triangles are asked for on a sphere of that radius).
  const double r = shape.bounding_radius();
  const double first_edge = std::min(r / 16.0, edge_for(4.0 * M_PI * r * r, triangles));
  const TriangleMesh probe = extract_surface(shape, criteria_for_edge(first_edge), seed);
  double edge = edge_for(surface_area(probe), triangles);
  TriangleMesh mesh = extract_surface(shape, criteria_for_edge(edge), seed);
  const double ratio = double(mesh.face_count()) / std::max(1, triangles);
  if (ratio > 1.2 || ratio < 1.0 / 1.2) {
    edge *= std::sqrt(ratio);
    mesh = extract_surface(shape, criteria_for_edge(edge), seed);
  }
  return mesh;
}

} // namespace phantasm
