// The ElasticModel of the deformation stage: bodies from solid organs (materials by tet) and
// shells from surface organs, enclosed volumes, held boundaries, and collisions.
#include "sim/build_model.hpp"

#include "core/error.hpp"
#include "core/format.hpp"
#include "core/progress.hpp"
#include "geometry/tet_boundary.hpp"
#include "sim/growth.hpp"
#include "sim/vertex_star_volumes.hpp"

#include <algorithm>
#include <map>
#include <random>
#include <sstream>

namespace phantasm::sim_detail {
namespace {

/// The patch volume constraint of a closed shell (its base mesh's vertices from first_vertex),
/// with the weight of the material's bulk modulus E / (3 (1 - 2 nu)).
void add_enclosed_volume(ElasticModel& model, const PatchSurface& surface, int first_vertex,
                         const MaterialSettings& material, double tolerance) {
  const TriangleMesh& base = surface.base_mesh();
  std::vector<int> vertices(static_cast<std::size_t>(base.vertices.rows()));
  for (std::size_t v = 0; v < vertices.size(); ++v)
    vertices[v] = first_vertex + static_cast<int>(v);
  std::vector<std::array<int, 3>> triangles;
  std::vector<double> heights;
  for (Eigen::Index t = 0; t < base.face_count(); ++t) {
    triangles.push_back({base.faces(t, 0), base.faces(t, 1), base.faces(t, 2)});
    heights.push_back(k_mm * surface.mean_bump_height(t));
  }
  const double bulk_modulus = material.youngs_modulus_Pa / (3.0 * (1.0 - 2.0 * material.poisson_ratio));
  model.volumes.push_back(enclosed_volume_constraint(std::move(vertices), std::move(triangles),
                                                     std::move(heights), model.rest_positions_m, bulk_modulus,
                                                     SingularValueRange{1.0 - tolerance, 1.0 + tolerance}));
}

/// A surface organ b as a shell of its triangles (and its enclosed volume when asked).
Body add_shell_body(const DeformationSettings& deformation, const OrganTable& organs, const Organ& organ,
                    std::size_t b, ElasticModel& model, StageReport& report) {
  const TriangleMesh& sheet = *shell_mesh(organ);
  const MaterialSettings* material = deformation.find_material(deformation.organs[b].material);
  if (material == nullptr)
    throw InputError(organs[b].name + ": material '" + deformation.organs[b].material + "' is not defined");
  Body body;
  body.organ = static_cast<int>(b);
  body.shell = true;
  body.vertex_count = sheet.vertices.rows();
  body.first_vertex =
      add_sheet(model, k_mm * sheet.vertices, sheet.faces, material->youngs_modulus_Pa,
                material->poisson_ratio, material->density_kg_m3, k_mm * deformation.organs[b].thickness_mm);
  report.modelled.push_back(
      organs[b].name + ": solved as a shell of " + std::to_string(sheet.vertices.rows()) + " vertices and " +
      std::to_string(sheet.faces.rows()) + " triangles (" +
      format_number(deformation.organs[b].thickness_mm) +
      " mm thick: as-rigid-as-possible membrane per triangle, bending per interior edge "
      "toward its rest curvature)");
  if (deformation.organs[b].enclosed_volume_tolerance) {
    if (!organ.surface) {
      throw InputError(organs[b].name +
                       ": enclosed_volume_tolerance needs a closed surface, but this organ is an open sheet");
    }
    const double tolerance = *deformation.organs[b].enclosed_volume_tolerance;
    add_enclosed_volume(model, *organ.surface, body.first_vertex, *material, tolerance);
    report.modelled.push_back(
        organs[b].name + ": enclosed volume kept within " + format_number(100.0 * tolerance) +
        " % of rest (patch volume constraint, bulk modulus of " + deformation.organs[b].material + ")");
  }
  return body;
}

/// The seed of body b's tet mesh: the scene's seed and the organ's index.
std::uint32_t body_mesh_seed(std::uint64_t scene_seed, std::size_t b) {
  std::seed_seq sequence{static_cast<std::uint32_t>(scene_seed), static_cast<std::uint32_t>(scene_seed >> 32),
                         static_cast<std::uint32_t>(b), 0x7e7u};
  std::uint32_t seed = 0;
  sequence.generate(&seed, &seed + 1);
  return seed;
}

/// What shapes body b's mesh of nested organs besides the organs' shapes: the body, its regions
/// (organs by name, each with the region holding it), the criteria and the seed, one per line.
std::string nested_mesh_inputs(const OrganTable& organs, std::size_t b,
                               const std::vector<std::size_t>& regions, const std::vector<int>& parents,
                               const TetMeshCriteria& c, std::uint32_t seed) {
  std::ostringstream out;
  out.precision(17);
  out << "body " << b << " " << organs[b].name << "\nregions";
  for (std::size_t k = 0; k < regions.size(); ++k)
    out << " " << regions[k] << ":" << organs[regions[k]].name << "<" << parents[k];
  out << "\ncriteria " << c.facet_size_mm << " " << c.facet_distance_mm << " " << c.facet_angle_deg << " "
      << c.cell_size_mm << " " << c.cell_radius_edge_ratio << " " << c.sliver_bound_deg << "\nseed " << seed
      << "\n";
  return out.str();
}

/// The tet mesh body b is solved on, and for each of its tets the organ whose material it takes.
/// Alone, the organ's own mesh; with organs nested in it (closed shapes carried by b), one mesh of
/// all of them at anatomy.tet_size_mm whose tets each lie in one organ's own region (the innermost
/// holding it), interfaces meshed as faces [docs/deformation.md, What is simulated]. With
/// anatomy.tet_interfaces: materials, a nested organ of the same material as the meshed organ
/// holding it is no region of its own: its tets are its holder's.
std::shared_ptr<const TetMesh> body_mesh(const DeformationSettings& deformation, const OrganTable& organs,
                                         const Phantom& phantom, const std::vector<int>& body_of,
                                         std::size_t b, std::vector<std::size_t>& organ_of_tet,
                                         StageReport& report, const BodyMeshSource& source) {
  const Organ& organ = phantom.organs[b];
  // Nested organs ordered by depth, so that each one's container comes before it.
  std::vector<std::size_t> carried{b};
  for (std::size_t i = 0; i < organs.size(); ++i) {
    if (i != b && body_of[i] == static_cast<int>(b) && phantom.organs[i].target) carried.push_back(i);
  }
  std::stable_sort(carried.begin() + 1, carried.end(),
                   [&](std::size_t x, std::size_t y) { return organs[x].depth < organs[y].depth; });
  if (carried.size() == 1 || !(phantom.tet_size_mm > 0.0)) {
    // The organ's own mesh (not owned); without a tet size each tet takes the material of the
    // innermost carried organ holding its centroid, so layers thinner than a tet get no tets.
    const TetMesh& mesh = *organ.solid;
    organ_of_tet.assign(static_cast<std::size_t>(mesh.tets.rows()), b);
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k)
        centroid += 0.25 * mesh.vertices.row(mesh.tets(t, k)).transpose();
      for (std::size_t k = 1; k < carried.size(); ++k) { // by depth: the innermost holder wins
        if (phantom.organs[carried[k]].target->value(centroid) > 0.0)
          organ_of_tet[static_cast<std::size_t>(t)] = carried[k];
      }
    }
    return std::shared_ptr<const TetMesh>(std::shared_ptr<const TetMesh>(), &mesh);
  }
  const TetMeshCriteria criteria = criteria_for_tet_size(phantom.tet_size_mm, phantom.tet_facet_distance_mm);
  // The regions of the mesh: carried organs in depth order, each with the region holding it. With
  // interfaces by material an organ of its holder's material is left out (merged into it).
  std::vector<std::size_t> regions;
  std::vector<std::string> merged;
  NestedShapes nested;
  for (std::size_t k = 0; k < carried.size(); ++k) {
    int parent = -1;
    for (int j = organs[carried[k]].parent; k > 0 && parent < 0 && j >= 0;
         j = organs[static_cast<std::size_t>(j)].parent) {
      const auto found = std::find(regions.begin(), regions.end(), static_cast<std::size_t>(j));
      if (found != regions.end()) parent = static_cast<int>(found - regions.begin());
    }
    if (k > 0 && parent < 0) parent = 0;
    if (k > 0 && phantom.tet_interfaces == TetInterfaces::materials &&
        deformation.organs[carried[k]].material ==
            deformation.organs[regions[static_cast<std::size_t>(parent)]].material) {
      merged.push_back(organs[carried[k]].name);
      continue;
    }
    regions.push_back(carried[k]);
    nested.shapes.push_back(phantom.organs[carried[k]].target.get());
    nested.parent.push_back(parent);
  }
  progress_detail(organs[b].name + ": one tet mesh of it and the " + std::to_string(regions.size() - 1) +
                  " organs nested in it (CGAL Mesh_3, tet size " + format_number(phantom.tet_size_mm) +
                  " mm)");
  const std::uint32_t seed = body_mesh_seed(phantom.seed, b);
  const auto build = [&] {
    NestedBodyMesh built;
    built.mesh = mesh_nested_solid(nested, criteria, seed, &built.repairs);
    return built;
  };
  NestedBodyMesh made =
      source ? source(nested_mesh_inputs(organs, b, regions, nested.parent, criteria, seed), build) : build();
  const SliverRepairs repairs = made.repairs;
  auto mesh = std::make_shared<TetMesh>(std::move(made.mesh));
  organ_of_tet.clear();
  for (Eigen::Index t = 0; t < mesh->tets.rows(); ++t)
    organ_of_tet.push_back(regions[static_cast<std::size_t>(mesh->subdomains[t])]);
  std::ostringstream line;
  line << organs[b].name << ": one tet mesh of it and the " << regions.size() - 1
       << " organs nested in it (tet size " << format_number(phantom.tet_size_mm) << " mm, interfaces within "
       << format_number(criteria.facet_distance_mm) << " mm, mean edge "
       << format_number(mean_edge_length(*mesh)) << " mm, min dihedral "
       << format_number(min_dihedral_angle_deg(*mesh)) << " deg, " << tets_with_dihedral_below(*mesh, 10.0)
       << " tets under 10 deg after mending those under " << format_number(criteria.sliver_bound_deg)
       << " deg: " << repairs.vertex_moves << " vertex moves, " << repairs.peeled
       << " flat tets peeled off the boundary, " << repairs.relabelled
       << " lone tets given the region around them, " << repairs.flips << " flips, " << repairs.splits
       << " edges split, " << repairs.collapses << " short edges collapsed; tissue interfaces are faces";
  if (!merged.empty()) {
    line << "; meshed with the organ holding them, of the same material (anatomy.tet_interfaces: materials):";
    for (const std::string& name : merged)
      line << " " << name;
  }
  line << ")";
  report.modelled.push_back(line.str());
  return mesh;
}

/// A solid organ b as a body of its tets (body_mesh), each with the material of its organ; its
/// boundary is held when it lies inside another organ.
Body add_solid_body(const DeformationSettings& deformation, const OrganTable& organs, const Phantom& phantom,
                    const BodyAssignment& assignment, std::size_t b, BodyModel& built, StageReport& report,
                    const BodyMeshSource& body_meshes) {
  const std::size_t n = organs.size();
  const std::vector<int>& body_of = assignment.body_of;
  ElasticModel& model = built.model;
  std::vector<std::size_t> organ_of_tet;
  std::shared_ptr<const TetMesh> shared =
      body_mesh(deformation, organs, phantom, body_of, b, organ_of_tet, report, body_meshes);
  const TetMesh& mesh = *shared;
  std::vector<TetMaterial> materials;
  std::map<std::string, int> tets_per_organ;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    const std::size_t holder = organ_of_tet[static_cast<std::size_t>(t)];
    const MaterialSettings* material = deformation.find_material(deformation.organs[holder].material);
    if (material == nullptr) {
      throw InputError(organs[holder].name + ": material '" + deformation.organs[holder].material +
                       "' is not defined");
    }
    materials.push_back(
        {lame_parameters(material->youngs_modulus_Pa, material->poisson_ratio), material->density_kg_m3});
    ++tets_per_organ[organs[holder].name];
  }
  Body body;
  body.organ = static_cast<int>(b);
  const std::size_t first_tet = model.tets.size();
  body.first_vertex = add_body(model, k_mm * mesh.vertices, mesh.tets, materials);
  std::vector<int> organ_labels(organ_of_tet.begin(), organ_of_tet.end());
  apply_growth(deformation, organs, organ_of_tet, mesh, first_tet, built);
  const int bulk_terms = apply_volume_formulation(model, deformation.volume, mesh, first_tet, organ_labels);
  body.tet_organ = std::move(organ_labels);
  body.vertex_count = mesh.vertices.rows();
  body.locator = std::make_unique<TetLocator>(mesh.vertices, mesh.tets, body.first_vertex);
  body.mesh = shared;
  std::ostringstream line;
  line << organs[b].name << ": solved as one body of " << mesh.vertices.rows() << " vertices and "
       << mesh.tets.rows() << " tets (materials by tet:";
  for (const auto& [name, count] : tets_per_organ)
    line << ' ' << name << ' ' << count;
  line << ")";
  if (deformation.volume == VolumeFormulation::tet_group)
    line << "; bulk term on " << bulk_terms << " groups of tets (volume-averaged F)";
  if (deformation.volume == VolumeFormulation::vertex_star)
    line << "; bulk term on " << bulk_terms << " vertex stars";
  report.modelled.push_back(line.str());
  if (organs[b].parent >= 0) {
    for (Eigen::Index f = 0; f < mesh.boundary_faces.rows(); ++f)
      for (int k = 0; k < 3; ++k)
        built.held.push_back(body.first_vertex + mesh.boundary_faces(f, k));
    report.modelled.push_back(organs[b].name + ": boundary held by " +
                              organs[static_cast<std::size_t>(organs[b].parent)].name +
                              " (it does not move; no slip)");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (body_of[i] == static_cast<int>(b) && i != b)
      report.modelled.push_back(organs[i].name + ": embedded in " + organs[b].name + ", follows its tets");
  }
  return body;
}

} // namespace

BodyModel build_body_model(const DeformationSettings& deformation, const OrganTable& organs,
                           const Phantom& phantom, const BodyAssignment& assignment, StageReport& report,
                           const BodyMeshSource& body_meshes) {
  BodyModel built;
  for (std::size_t b = 0; b < assignment.body_of.size(); ++b) {
    if (assignment.body_of[b] != static_cast<int>(b)) continue;
    const Organ& organ = phantom.organs[b];
    if (!organ.solid) {
      built.bodies.push_back(add_shell_body(deformation, organs, organ, b, built.model, report));
    } else {
      built.bodies.push_back(
          add_solid_body(deformation, organs, phantom, assignment, b, built, report, body_meshes));
    }
  }
  report_growth(deformation, built.grown_tets, report);
  return built;
}

double nominal_stiffness(const ElasticModel& model) {
  double diagonal = 0.0;
  for (const TetElement& e : model.tets)
    diagonal += (e.strain_weight + e.volume_weight) * e.Q.squaredNorm();
  for (const SurfaceElement& e : model.surfaces)
    diagonal += e.weight * e.Q.squaredNorm();
  // A group's bulk term as its tets' was (their share of its weight by volume), so that the
  // penalties scaled by this do not depend on where the bulk term lives.
  for (const TetGroup& g : model.tet_groups)
    for (int t : g.tets) {
      const TetElement& e = model.tets[static_cast<std::size_t>(t)];
      diagonal += g.weight * e.rest_volume_m3 / g.rest_volume_m3 * e.Q.squaredNorm();
    }
  return model.vertex_count() > 0 ? diagonal / static_cast<double>(model.vertex_count()) : 0.0;
}

void add_collisions(const std::vector<CollisionSettings>& collisions, const OrganTable& organs,
                    const Phantom& phantom, const std::vector<Body>& bodies, double nominal_stiffness,
                    ElasticModel& model, StageReport& report) {
  std::map<int, int> surface_of_body;
  for (std::size_t i = 0; i < collisions.size(); ++i) {
    const std::vector<std::string>& names = collisions[i].organs;
    const std::string key = "deformation.collisions[" + std::to_string(i) + "].organs";
    std::array<int, 2> pair{};
    for (std::size_t k = 0; k < 2 && k < names.size(); ++k) {
      const auto body = std::find_if(bodies.begin(), bodies.end(), [&](const Body& b) {
        return organs[static_cast<std::size_t>(b.organ)].name == names[k];
      });
      if (body == bodies.end()) {
        throw SettingError(key, "expected organs simulated as bodies of their own (loaded, not fixed, not "
                                "inside another simulated organ), found '" +
                                    names[k] + "'");
      }
      const auto b = static_cast<int>(body - bodies.begin());
      if (!surface_of_body.count(b)) {
        const Organ& organ = phantom.organs[static_cast<std::size_t>(body->organ)];
        Eigen::MatrixX3i faces;
        if (body->mesh)
          faces = tet_boundary_faces(body->mesh->vertices, body->mesh->tets);
        else if (organ.surface)
          faces = organ.surface->base_mesh().faces;
        else
          throw SettingError(key, "expected organs with a closed surface, found the open sheet '" + names[k] +
                                      "'");
        ContactSurface surface;
        for (Eigen::Index f = 0; f < faces.rows(); ++f) {
          surface.triangles.push_back({body->first_vertex + faces(f, 0), body->first_vertex + faces(f, 1),
                                       body->first_vertex + faces(f, 2)});
          for (int c = 0; c < 3; ++c)
            surface.vertices.push_back(body->first_vertex + faces(f, c));
        }
        std::sort(surface.vertices.begin(), surface.vertices.end());
        surface.vertices.erase(std::unique(surface.vertices.begin(), surface.vertices.end()),
                               surface.vertices.end());
        surface_of_body[b] = static_cast<int>(model.contact_surfaces.size());
        model.contact_surfaces.push_back(std::move(surface));
      }
      pair[k] = surface_of_body[b];
    }
    model.contact_pairs.push_back(pair);
  }
  if (model.contact_pairs.empty()) return;
  if (model.contact_stiffness_N_m == 0.0) model.contact_stiffness_N_m = 1e4 * nominal_stiffness;
  for (const CollisionSettings& c : collisions) {
    report.modelled.push_back("collision of " + c.organs[0] + " and " + c.organs[1] +
                              ": a vertex of either inside the other's surface is pushed out to the closest "
                              "point there, the triangle it lies on pushed back (penalty " +
                              format_number(model.contact_stiffness_N_m) + " N/m)");
  }
}

} // namespace phantasm::sim_detail
