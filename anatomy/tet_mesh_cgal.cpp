// The one translation unit that includes CGAL Mesh_3 (it is slow to compile).
//
// Determinism: meshing is sequential and seeded, every optimisation step runs without a time
// limit (Mesh_3 otherwise stops perturbation and exudation after as long as the refinement
// took, so the mesh depended on the machine's load), and the output is put in a canonical order
// (vertices by position), which removes differences of container order.

#include "anatomy/tet_mesh.hpp"
#include "core/cancellation.hpp"
#include "core/error.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
// With TBB support (anatomy/CMakeLists.txt) the sliver exuder names this header's types without
// including it.
#include <CGAL/Mesh_3/Worksharing_data_structures.h>
#include <CGAL/exude_mesh_3.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/refine_mesh_3.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <functional>
#include <map>
#include <numeric>

namespace phantasm {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Domain = CGAL::Labeled_mesh_domain_3<Kernel>;
using Triangulation = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using Complex = CGAL::Mesh_complex_3_in_triangulation_3<Triangulation>;
using Criteria = CGAL::Mesh_criteria_3<Triangulation>;

/// Puts a mesh in a canonical order that does not depend on the order of CGAL's internal
/// containers (which follows memory reuse): vertices sorted by position, each tet and face
/// rotated to start at its smallest index (orientation kept), rows sorted.
void canonicalize(TetMesh& mesh) {
  const Eigen::Index nv = mesh.vertices.rows();
  std::vector<int> order(static_cast<std::size_t>(nv));
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    for (int k = 0; k < 3; ++k) {
      if (mesh.vertices(a, k) != mesh.vertices(b, k)) return mesh.vertices(a, k) < mesh.vertices(b, k);
    }
    return a < b;
  });
  std::vector<int> new_index(static_cast<std::size_t>(nv));
  Eigen::MatrixX3d sorted(nv, 3);
  for (Eigen::Index i = 0; i < nv; ++i) {
    new_index[static_cast<std::size_t>(order[static_cast<std::size_t>(i)])] = static_cast<int>(i);
    sorted.row(i) = mesh.vertices.row(order[static_cast<std::size_t>(i)]);
  }
  mesh.vertices = sorted;
  // Each tet with its subdomain as a fifth entry (tets are distinct, so it never decides the order).
  const bool labeled = mesh.subdomains.size() == mesh.tets.rows();
  std::vector<std::array<int, 5>> tets;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    std::array<int, 4> v;
    for (int k = 0; k < 4; ++k)
      v[static_cast<std::size_t>(k)] = new_index[static_cast<std::size_t>(mesh.tets(t, k))];
    // Even permutations keep the orientation: bring the smallest index first with one.
    const auto smallest = static_cast<std::size_t>(std::min_element(v.begin(), v.end()) - v.begin());
    static const int even[4][4] = {{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}};
    std::array<int, 5> rotated;
    for (int k = 0; k < 4; ++k)
      rotated[static_cast<std::size_t>(k)] = v[static_cast<std::size_t>(even[smallest][k])];
    // Then order the last three cyclically so the second is the smallest of them.
    while (rotated[1] > rotated[2] || rotated[1] > rotated[3]) {
      std::rotate(rotated.begin() + 1, rotated.begin() + 2, rotated.begin() + 4);
    }
    rotated[4] = labeled ? mesh.subdomains[t] : 0;
    tets.push_back(rotated);
  }
  std::sort(tets.begin(), tets.end());
  for (std::size_t t = 0; t < tets.size(); ++t) {
    for (int k = 0; k < 4; ++k)
      mesh.tets(static_cast<Eigen::Index>(t), k) = tets[t][static_cast<std::size_t>(k)];
    if (labeled) mesh.subdomains[static_cast<Eigen::Index>(t)] = tets[t][4];
  }
  std::vector<std::array<int, 3>> faces;
  for (Eigen::Index f = 0; f < mesh.boundary_faces.rows(); ++f) {
    std::array<int, 3> v;
    for (int k = 0; k < 3; ++k)
      v[static_cast<std::size_t>(k)] = new_index[static_cast<std::size_t>(mesh.boundary_faces(f, k))];
    std::rotate(v.begin(), std::min_element(v.begin(), v.end()), v.end());
    faces.push_back(v);
  }
  std::sort(faces.begin(), faces.end());
  for (std::size_t f = 0; f < faces.size(); ++f) {
    for (int k = 0; k < 3; ++k)
      mesh.boundary_faces(static_cast<Eigen::Index>(f), k) = faces[f][static_cast<std::size_t>(k)];
  }
}

/// The complex's cells as a TetMesh in canonical order: tets oriented positively, boundary
/// faces (between the domain and its outside) oriented outward, and with `labeled` each tet's
/// subdomain index minus one (the shape index of NestedShapes).
TetMesh to_tet_mesh(const Complex& complex, bool labeled, double cell_size_mm) {
  TetMesh mesh;
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
  std::vector<Eigen::Vector4i> tets;
  std::vector<int> subdomains;
  for (auto cell = complex.cells_in_complex_begin(); cell != complex.cells_in_complex_end(); ++cell) {
    Eigen::Vector4i t;
    for (int k = 0; k < 4; ++k)
      t[k] = index_of(cell->vertex(k));
    tets.push_back(t);
    subdomains.push_back(static_cast<int>(complex.subdomain_index(cell)) - 1);
  }
  if (tets.empty()) {
    throw InputError(
        "tetrahedral mesh: expected cells inside the shape, found none (the shape is smaller than the "
        "cell size " +
        std::to_string(cell_size_mm) + " mm)");
  }
  std::vector<Eigen::Vector3i> faces;
  std::vector<int> inside_vertex; // the fourth vertex of the tet each boundary face belongs to
  for (auto facet = complex.facets_in_complex_begin(); facet != complex.facets_in_complex_end(); ++facet) {
    // Of the two cells sharing the facet, one is in the complex: orient away from its fourth vertex.
    auto cell = facet->first;
    int opposite = facet->second;
    const auto mirror = complex.triangulation().mirror_facet(*facet);
    // A facet between two subdomains is an interface, not boundary.
    if (complex.is_in_complex(cell) && complex.is_in_complex(mirror.first)) continue;
    if (!complex.is_in_complex(cell)) {
      cell = mirror.first;
      opposite = mirror.second;
    }
    Eigen::Vector3i f;
    for (int k = 0, j = 0; k < 4; ++k) {
      if (k != opposite) f[j++] = index_of(cell->vertex(k));
    }
    faces.push_back(f);
    inside_vertex.push_back(index_of(cell->vertex(opposite)));
  }
  mesh.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i)
    mesh.vertices.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
  mesh.tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
  for (std::size_t i = 0; i < tets.size(); ++i) {
    mesh.tets.row(static_cast<Eigen::Index>(i)) = tets[i].transpose();
    if (tet_volume(mesh, static_cast<Eigen::Index>(i)) < 0.0) {
      std::swap(mesh.tets(static_cast<Eigen::Index>(i), 2), mesh.tets(static_cast<Eigen::Index>(i), 3));
    }
  }
  mesh.boundary_faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (std::size_t i = 0; i < faces.size(); ++i) {
    Eigen::Vector3i f = faces[i];
    const Eigen::Vector3d a = points[static_cast<std::size_t>(f[0])];
    const Eigen::Vector3d normal =
        (points[static_cast<std::size_t>(f[1])] - a).cross(points[static_cast<std::size_t>(f[2])] - a);
    if (normal.dot(points[static_cast<std::size_t>(inside_vertex[i])] - a) > 0.0) std::swap(f[1], f[2]);
    mesh.boundary_faces.row(static_cast<Eigen::Index>(i)) = f.transpose();
  }
  if (labeled) {
    mesh.subdomains =
        Eigen::Map<const Eigen::VectorXi>(subdomains.data(), static_cast<Eigen::Index>(subdomains.size()));
  }
  throw_if_cancelled(); // sorting a million tets takes a second
  canonicalize(mesh);
  return mesh;
}

/// Mesh_3's sliver exudation as make_mesh_3 runs it last (no time limit), with a visitor that
/// stops a cancelled run: exudation never calls the domain, so the oracle's poll cannot.
void exude(Complex& complex, double sliver_bound_deg) {
  struct CancellingVisitor {
    void after_cell_pumped(std::size_t) { throw_if_cancelled(); }
  };
  using Criterion = CGAL::Mesh_3::Min_dihedral_angle_criterion<Triangulation>;
  const Criterion criterion(sliver_bound_deg, complex.triangulation());
  CGAL::Mesh_3::Slivers_exuder<Complex, Criterion, CancellingVisitor> exuder(complex, criterion);
  exuder.set_time_limit(0);
  exuder(CancellingVisitor());
  throw_if_cancelled();
}

} // namespace

TetMesh mesh_implicit_solid(const ImplicitShape& shape, const TetMeshCriteria& c, std::uint32_t seed) {
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
      p::relative_error_bound = 1e-6, p::p_rng = &random);
  const Criteria criteria(p::facet_angle = c.facet_angle_deg, p::facet_size = c.facet_size_mm,
                          p::facet_distance = c.facet_distance_mm,
                          p::cell_radius_edge_ratio = c.cell_radius_edge_ratio,
                          p::cell_size = c.cell_size_mm);
  // Mesh_3 draws from CGAL's default generator too: reseed it for repeatable meshes.
  CGAL::get_default_random() = CGAL::Random(seed);
  Complex complex = CGAL::make_mesh_3<Complex>(
      domain, criteria, p::no_lloyd(), p::odt(p::max_iteration_number = 20, p::time_limit = 0),
      p::perturb(p::sliver_bound = c.sliver_bound_deg, p::time_limit = 0), p::no_exude(),
      // The refinement polls the flag too (the domain is not called while it drains stale cells).
      p::mesh_3_options(p::pointer_to_stop_atomic_boolean = &cancellation_flag()));
  exude(complex, c.sliver_bound_deg);
  return to_tet_mesh(complex, false, c.cell_size_mm);
}

TetMesh mesh_nested_solid(const NestedShapes& nested, const TetMeshCriteria& c, std::uint32_t seed,
                          SliverRepairs* repairs) {
  namespace p = CGAL::parameters;
  // Label 0 is outside; shape k is subdomain k + 1.
  std::function<int(const Point&)> label = [&nested](const Point& x) {
    throw_if_cancelled(); // as in mesh_implicit_solid: the mesher unwinds
    return nested.innermost(Eigen::Vector3d(x.x(), x.y(), x.z())) + 1;
  };
  const ImplicitShape& outer = *nested.shapes.at(0);
  const Eigen::Vector3d centre = outer.center();
  const double radius = 1.05 * outer.bounding_radius();
  CGAL::Random random(seed);
  const Domain domain(label, Kernel::Sphere_3(Point(centre.x(), centre.y(), centre.z()), radius * radius),
                      1e-6, CGAL::Null_subdomain_index(), &random);
  // No facet may join two surfaces (across a thin layer): each facet's vertices lie on the one
  // surface it approximates. Labels that touch (smoothed indicators, NestedShapes::innermost)
  // meet three at a time along curves, where no facet can keep that rule without the curves
  // meshed first as features (which Mesh_3 cannot find on an implicit domain): refinement there
  // would not end. Such shapes only ask that a facet's vertices lie on a surface.
  const bool touching = std::all_of(nested.shapes.begin(), nested.shapes.end(),
                                    [](const ImplicitShape* shape) { return shape->smoothed_indicator(); });
  const Criteria criteria(p::facet_angle = c.facet_angle_deg, p::facet_size = c.facet_size_mm,
                          p::facet_distance = c.facet_distance_mm,
                          p::cell_radius_edge_ratio = c.cell_radius_edge_ratio, p::cell_size = c.cell_size_mm,
                          p::facet_topology = touching ? CGAL::FACET_VERTICES_ON_SURFACE
                                                       : CGAL::FACET_VERTICES_ON_SAME_SURFACE_PATCH);
  CGAL::get_default_random() = CGAL::Random(seed);
  // Mesh_3's own initial points lie on whichever surface random rays from the centre cross first,
  // so a small inner shape could be missed: start instead from points on every shape's surface,
  // where rays from its centre (42 directions) first leave it.
  Complex complex;
  Triangulation& triangulation = complex.triangulation();
  const auto weighted = triangulation.geom_traits().construct_weighted_point_3_object();
  const auto crosses = domain.do_intersect_surface_object();
  const auto intersection = domain.construct_intersection_object();
  const TriangleMesh directions = unit_icosphere(1);
  const double step_across = 0.01 * c.facet_distance_mm;
  for (const ImplicitShape* shape : nested.shapes) {
    const Eigen::Vector3d from = shape->center();
    if (shape->value(from) <= 0.0) continue;
    const double reach = 1.05 * shape->bounding_radius();
    for (Eigen::Index d = 0; d < directions.vertex_count(); ++d) {
      const Eigen::Vector3d direction = directions.vertex(d);
      // The first sign change along the ray (64 steps), then bisection.
      constexpr int steps = 64;
      double inside = 0.0, outside = -1.0;
      for (int i = 1; i <= steps; ++i) {
        const double t = reach * i / steps;
        if (shape->value(from + t * direction) <= 0.0) {
          outside = t;
          break;
        }
        inside = t;
      }
      if (outside < 0.0) continue;
      for (int i = 0; i < 60; ++i) {
        const double t = 0.5 * (inside + outside);
        (shape->value(from + t * direction) > 0.0 ? inside : outside) = t;
      }
      const Eigen::Vector3d a = from + (inside - step_across) * direction;
      const Eigen::Vector3d b = from + (outside + step_across) * direction;
      const Kernel::Segment_3 segment(Point(a.x(), a.y(), a.z()), Point(b.x(), b.y(), b.z()));
      if (!crosses(segment)) continue;
      const auto crossing = intersection(segment);
      const auto vertex = triangulation.insert(weighted(std::get<0>(crossing)));
      if (vertex == Triangulation::Vertex_handle()) continue; // hidden
      complex.set_dimension(vertex, 2);
      complex.set_index(vertex, std::get<1>(crossing));
    }
  }
  CGAL::refine_mesh_3(
      complex, domain, criteria, p::no_lloyd(), p::odt(p::max_iteration_number = 20, p::time_limit = 0),
      p::perturb(p::sliver_bound = c.sliver_bound_deg, p::time_limit = 0), p::no_exude(),
      // The refinement polls the flag too (the domain is not called while it drains stale cells).
      p::mesh_3_options(p::pointer_to_stop_atomic_boolean = &cancellation_flag()));
  exude(complex, c.sliver_bound_deg);
  TetMesh mesh = to_tet_mesh(complex, true, c.cell_size_mm);
  // Slivers Mesh_3 leaves where its surface vertices are pinned (thin layers, interfaces): moved
  // along their interfaces by our own pass.
  const auto region_at = [&nested](const Eigen::Vector3d& x) { return nested.innermost(x); };
  SliverRepairs done;
  done.vertex_moves = improve_slivers(mesh, region_at, c.sliver_bound_deg);
  // What moving vertices cannot mend: flat tets on the boundary of a layer thinner than the tets
  // (peeled off), lone tets wedged between other regions (given the region around them) and flat
  // tets inside one region (flipped away); the pass then runs again on the changed mesh.
  // Each change can open a way for another: up to four rounds.
  for (int round = 0; round < 4; ++round) {
    const int peeled = peel_boundary_slivers(mesh, c.sliver_bound_deg);
    const int relabelled = relabel_stranded_slivers(mesh, c.sliver_bound_deg);
    const int flips = flip_slivers(mesh, c.sliver_bound_deg);
    const int splits = split_slivers(mesh, region_at);
    const int collapses = collapse_short_sliver_edges(mesh);
    if (peeled + relabelled + flips + splits + collapses == 0) break;
    done.collapses += collapses;
    done.peeled += peeled;
    done.relabelled += relabelled;
    done.flips += flips;
    done.splits += splits;
    done.vertex_moves += improve_slivers(mesh, region_at, c.sliver_bound_deg);
  }
  if (repairs) *repairs = done;
  return mesh;
}

} // namespace phantasm
