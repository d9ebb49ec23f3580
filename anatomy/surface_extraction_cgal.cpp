// Surface meshes of implicit shapes with CGAL Mesh_3 (surface facets only): kept apart from the
// rest of the anatomy behind a plain Eigen interface, like tet_mesh_cgal.cpp.
//
// Determinism: meshing is sequential and seeded, no optimiser with a time limit runs, and the
// output is put in a canonical order (vertices by position, faces rotated and sorted).

#include "anatomy/surface_extraction.hpp"
#include "core/cancellation.hpp"
#include "core/error.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/make_mesh_3.h>

#include <algorithm>
#include <array>
#include <functional>
#include <map>
#include <numeric>
#include <vector>

namespace phantasm {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Domain = CGAL::Labeled_mesh_domain_3<Kernel>;
using Triangulation = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using Complex = CGAL::Mesh_complex_3_in_triangulation_3<Triangulation>;
using Criteria = CGAL::Mesh_criteria_3<Triangulation>;

/// Vertices sorted by position, each face rotated to start at its smallest index (orientation
/// kept), faces sorted: an order that does not follow CGAL's container order.
TriangleMesh canonical(const std::vector<Eigen::Vector3d>& points,
                       const std::vector<std::array<int, 3>>& faces) {
  std::vector<int> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const Eigen::Vector3d& p = points[static_cast<std::size_t>(a)];
    const Eigen::Vector3d& q = points[static_cast<std::size_t>(b)];
    for (int k = 0; k < 3; ++k) {
      if (p[k] != q[k]) return p[k] < q[k];
    }
    return a < b;
  });
  std::vector<int> new_index(points.size());
  TriangleMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (std::size_t i = 0; i < order.size(); ++i) {
    new_index[static_cast<std::size_t>(order[i])] = static_cast<int>(i);
    mesh.vertices.row(static_cast<Eigen::Index>(i)) = points[static_cast<std::size_t>(order[i])].transpose();
  }
  std::vector<std::array<int, 3>> sorted;
  for (const auto& f : faces) {
    std::array<int, 3> v;
    for (std::size_t k = 0; k < 3; ++k)
      v[k] = new_index[static_cast<std::size_t>(f[k])];
    std::rotate(v.begin(), std::min_element(v.begin(), v.end()), v.end());
    sorted.push_back(v);
  }
  std::sort(sorted.begin(), sorted.end());
  mesh.faces.resize(static_cast<Eigen::Index>(sorted.size()), 3);
  for (std::size_t f = 0; f < sorted.size(); ++f) {
    for (std::size_t k = 0; k < 3; ++k)
      mesh.faces(static_cast<Eigen::Index>(f), static_cast<Eigen::Index>(k)) = sorted[f][k];
  }
  return mesh;
}

} // namespace

TriangleMesh extract_surface(const ImplicitShape& shape, const SurfaceMeshCriteria& c, std::uint32_t seed) {
  namespace p = CGAL::parameters;
  // CGAL's implicit domains are negative inside; ours are positive inside.
  // Mesh_3 cannot be asked to stop, but it calls the domain all the time (refinement, ODT,
  // perturbation): a cancelled run throws from here and the mesher unwinds (its containers free
  // themselves), so SIGINT ends even minutes of meshing at once.
  std::function<double(const Point&)> inside_negative = [&shape](const Point& x) {
    throw_if_cancelled();
    return -shape.value(Eigen::Vector3d(x.x(), x.y(), x.z()));
  };
  const Eigen::Vector3d centre = shape.center();
  const double radius = 1.05 * shape.bounding_radius();
  CGAL::Random random(seed);
  const Domain domain = Domain::create_implicit_mesh_domain(
      inside_negative, Kernel::Sphere_3(Point(centre.x(), centre.y(), centre.z()), radius * radius),
      p::relative_error_bound = 1e-9, p::p_rng = &random);
  // Facet criteria only: the cells are whatever the surface's Delaunay triangulation gives.
  const Criteria criteria(p::facet_angle = c.facet_angle_deg, p::facet_size = c.facet_size_mm,
                          p::facet_distance = c.facet_distance_mm);
  CGAL::get_default_random() = CGAL::Random(seed);
  const Complex complex = CGAL::make_mesh_3<Complex>(
      domain, criteria, p::no_lloyd(), p::no_odt(), p::no_perturb(), p::no_exude(), p::manifold(),
      p::mesh_3_options(p::pointer_to_stop_atomic_boolean = &cancellation_flag()));
  throw_if_cancelled(); // a mesher asked to stop returns what it has: never a result

  std::map<Triangulation::Vertex_handle, int> index;
  std::vector<Eigen::Vector3d> points;
  auto index_of = [&](Triangulation::Vertex_handle v) {
    const auto found = index.find(v);
    if (found != index.end()) return found->second;
    const auto& q = v->point().point();
    points.emplace_back(q.x(), q.y(), q.z());
    const int i = static_cast<int>(points.size()) - 1;
    index.emplace(v, i);
    return i;
  };
  std::vector<std::array<int, 3>> faces;
  for (auto facet = complex.facets_in_complex_begin(); facet != complex.facets_in_complex_end(); ++facet) {
    // Orient away from the side whose cell is inside the shape (in the complex).
    auto cell = facet->first;
    int opposite = facet->second;
    if (!complex.is_in_complex(cell)) {
      const auto mirror = complex.triangulation().mirror_facet(*facet);
      cell = mirror.first;
      opposite = mirror.second;
    }
    std::array<int, 3> f{};
    for (int k = 0, j = 0; k < 4; ++k) {
      if (k != opposite) f[static_cast<std::size_t>(j++)] = index_of(cell->vertex(k));
    }
    const int inside = index_of(cell->vertex(opposite));
    const Eigen::Vector3d a = points[static_cast<std::size_t>(f[0])];
    const Eigen::Vector3d normal =
        (points[static_cast<std::size_t>(f[1])] - a).cross(points[static_cast<std::size_t>(f[2])] - a);
    if (normal.dot(points[static_cast<std::size_t>(inside)] - a) > 0.0) std::swap(f[1], f[2]);
    faces.push_back(f);
  }
  if (faces.empty()) {
    throw InputError(
        "surface mesh: expected a surface, found none (the shape is smaller than the facet size " +
        std::to_string(c.facet_size_mm) + " mm or outside its bounding ball)");
  }
  // Keep the vertices the facets use (in the order they are met), nothing else of the triangulation.
  std::vector<int> used(points.size(), -1);
  std::vector<Eigen::Vector3d> kept;
  for (auto& f : faces) {
    for (int& v : f) {
      if (used[static_cast<std::size_t>(v)] < 0) {
        used[static_cast<std::size_t>(v)] = static_cast<int>(kept.size());
        kept.push_back(points[static_cast<std::size_t>(v)]);
      }
      v = used[static_cast<std::size_t>(v)];
    }
  }
  return canonical(kept, faces);
}

} // namespace phantasm
