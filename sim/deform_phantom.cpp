#include "sim/deform_phantom.hpp"

#include "anatomy/structured_mesh.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "sim/elastic_model.hpp"
#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/position_based.hpp"
#include "sim/sim_plan.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace phantasm {
namespace {

constexpr double k_mm = 1e-3; // metres per millimetre

/// A point given by barycentric coordinates in one tet of the model.
struct Embedding {
  std::array<int, 4> vertices{};
  Eigen::Vector4d coefficients = Eigen::Vector4d::Zero();
};

/// Locates points in a body's rest tets: the tet where the smallest barycentric coordinate is
/// largest (inside when it is >= 0; a point just outside the mesh extrapolates from the nearest
/// tet, which keeps the map smooth across the faceted boundary).
class TetLocator {
public:
  TetLocator(const Eigen::MatrixX3d& rest_mm, const Eigen::MatrixX4i& tets, int first_vertex)
      : m_tets(tets), m_first(first_vertex) {
    for (Eigen::Index t = 0; t < tets.rows(); ++t) {
      Eigen::Matrix3d D;
      for (int k = 0; k < 3; ++k)
        D.col(k) = (rest_mm.row(tets(t, k + 1)) - rest_mm.row(tets(t, 0))).transpose();
      m_origin.push_back(rest_mm.row(tets(t, 0)).transpose());
      m_inverse.push_back(D.inverse());
    }
  }

  Embedding locate(const Eigen::Vector3d& x) const {
    double best = -std::numeric_limits<double>::infinity();
    Embedding result;
    for (std::size_t t = 0; t < m_inverse.size(); ++t) {
      const Eigen::Vector3d b = m_inverse[t] * (x - m_origin[t]);
      const Eigen::Vector4d w(1.0 - b.sum(), b[0], b[1], b[2]);
      const double smallest = w.minCoeff();
      if (smallest > best) {
        best = smallest;
        for (int k = 0; k < 4; ++k)
          result.vertices[static_cast<std::size_t>(k)] = m_first + m_tets(static_cast<Eigen::Index>(t), k);
        result.coefficients = w;
        if (smallest >= 0.0) break;
      }
    }
    return result;
  }

private:
  const Eigen::MatrixX4i& m_tets;
  int m_first = 0;
  std::vector<Eigen::Vector3d> m_origin;
  std::vector<Eigen::Matrix3d> m_inverse;
};

Eigen::Vector3d interpolate(const Embedding& e, const Eigen::MatrixX3d& p) {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k)
    x += e.coefficients[k] * p.row(e.vertices[static_cast<std::size_t>(k)]).transpose();
  return x;
}

/// How far a displacement load has come at time t (dynamic mode).
double profile(MotionProfile motion, double period_s, double t) {
  switch (motion) {
  case MotionProfile::constant: return 1.0;
  case MotionProfile::ramp: return std::min(1.0, t / period_s);
  case MotionProfile::sine: return 0.5 * (1.0 - std::cos(2.0 * M_PI * t / period_s));
  }
  return 1.0;
}

struct Body {
  int organ = -1;
  int first_vertex = 0;
  Eigen::Index vertex_count = 0;
  std::unique_ptr<TetLocator> locator; ///< solids only
  bool shell = false;                  ///< a surface organ: its triangles carry the load
};

/// The triangles a surface organ is simulated with: its sheet, or its patch base mesh.
const TriangleMesh* shell_mesh(const Organ& organ) {
  if (organ.sheet) return &*organ.sheet;
  if (organ.surface) return &organ.surface->base_mesh();
  return nullptr;
}

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

/// The contact surfaces of the scene's collisions (each organ's closed surface: a solid body's
/// boundary faces, a closed shell's triangles) and their pairs.
/// @throws InputError naming the scene field when an organ of a pair is not simulated as a body
/// of its own or has no closed surface
void add_collisions(const Scene& scene, const Phantom& phantom, const std::vector<Body>& bodies,
                    double nominal_stiffness, ElasticModel& model, StageReport& report) {
  std::map<int, int> surface_of_body;
  for (std::size_t i = 0; i < scene.deformation.collisions.size(); ++i) {
    const std::vector<std::string>& names = scene.deformation.collisions[i].organs;
    const std::string key = "deformation.collisions[" + std::to_string(i) + "].organs";
    std::array<int, 2> pair{};
    for (std::size_t k = 0; k < 2 && k < names.size(); ++k) {
      const auto body = std::find_if(bodies.begin(), bodies.end(), [&](const Body& b) {
        return scene.anatomy.organs[static_cast<std::size_t>(b.organ)].name == names[k];
      });
      if (body == bodies.end()) {
        throw InputError(
            Diagnostic{scene.location_of(key), key,
                       "expected organs simulated as bodies of their own (loaded, not fixed, not "
                       "inside another simulated organ), found '" +
                           names[k] + "'"}
                .format());
      }
      const auto b = static_cast<int>(body - bodies.begin());
      if (!surface_of_body.count(b)) {
        const Organ& organ = phantom.organs[static_cast<std::size_t>(body->organ)];
        Eigen::MatrixX3i faces;
        if (organ.solid)
          faces = boundary_faces_of(organ.solid->vertices, organ.solid->tets);
        else if (organ.surface)
          faces = organ.surface->base_mesh().faces;
        else
          throw InputError(
              Diagnostic{scene.location_of(key), key,
                         "expected organs with a closed surface, found the open sheet '" + names[k] + "'"}
                  .format());
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
  for (const CollisionSettings& c : scene.deformation.collisions) {
    report.modelled.push_back("collision of " + c.organs[0] + " and " + c.organs[1] +
                              ": a vertex of either inside the other's surface is pushed out to the closest "
                              "point there, the triangle it lies on pushed back (penalty " +
                              format_number(model.contact_stiffness_N_m) + " N/m)");
  }
}

/// A displacement load's springs: which model point constraints, and their rest targets (m).
struct PushedPoints {
  const LoadSettings* load = nullptr;
  std::vector<std::size_t> constraints;
  std::vector<Eigen::Vector3d> rest_m;
};

} // namespace

PhantomDeformation deform_phantom(const Scene& scene, const Phantom& phantom, StageReport& report,
                                  Reporter& reporter) {
  const auto& settings = scene.anatomy.organs;
  const std::size_t n = settings.size();
  const std::vector<OrganMotion> motion = classify_organ_motion(scene);
  std::map<std::string, int> index;
  for (std::size_t i = 0; i < n; ++i)
    index[settings[i].name] = static_cast<int>(i);
  std::vector<int> parent(n, -1), depth(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!settings[i].inside.empty()) parent[i] = index.at(settings[i].inside);
  }
  // The body of each organ: its topmost simulated ancestor-or-self (-1: none).
  std::vector<int> body_of(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    for (int j = static_cast<int>(i); j >= 0; j = parent[static_cast<std::size_t>(j)]) {
      if (motion[static_cast<std::size_t>(j)] == OrganMotion::simulated) body_of[i] = j;
      if (j != static_cast<int>(i)) ++depth[i];
    }
  }
  // A surface organ (no tet mesh) is simulated as a shell of its triangles; organs nested in it
  // have nothing to follow (no interior) and stay in place.
  for (std::size_t b = 0; b < n; ++b) {
    if (body_of[b] != static_cast<int>(b) || phantom.organs[b].solid) continue;
    if (shell_mesh(phantom.organs[b]) == nullptr) {
      report.skipped.push_back(settings[b].name +
                               ": a load acts on it but it has neither tets nor triangles");
      for (std::size_t i = 0; i < n; ++i)
        if (body_of[i] == static_cast<int>(b)) body_of[i] = -1;
      continue;
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (i == b || body_of[i] != static_cast<int>(b)) continue;
      body_of[i] = -1;
      report.skipped.push_back(settings[i].name + ": inside the shell " + settings[b].name +
                               ", which has no interior to carry it; it stays in place");
    }
  }

  ElasticModel model;
  std::vector<Body> bodies;
  std::vector<int> held; // boundary vertices of bodies inside an organ that does not move
  for (std::size_t b = 0; b < n; ++b) {
    if (body_of[b] != static_cast<int>(b)) continue;
    const Organ& organ = phantom.organs[b];
    if (!organ.solid) {
      const TriangleMesh& sheet = *shell_mesh(organ);
      const MaterialSettings* material = scene.find_material(settings[b].material);
      if (material == nullptr)
        throw InputError(settings[b].name + ": material '" + settings[b].material + "' is not defined");
      Body body;
      body.organ = static_cast<int>(b);
      body.shell = true;
      body.vertex_count = sheet.vertices.rows();
      body.first_vertex =
          add_sheet(model, k_mm * sheet.vertices, sheet.faces, material->youngs_modulus_Pa,
                    material->poisson_ratio, material->density_kg_m3, k_mm * settings[b].thickness_mm);
      report.modelled.push_back(
          settings[b].name + ": solved as a shell of " + std::to_string(sheet.vertices.rows()) +
          " vertices and " + std::to_string(sheet.faces.rows()) + " triangles (" +
          format_number(settings[b].thickness_mm) +
          " mm thick: as-rigid-as-possible membrane per triangle, bending per interior edge "
          "toward its rest curvature)");
      if (settings[b].enclosed_volume_tolerance) {
        if (!organ.surface) {
          throw InputError(
              settings[b].name +
              ": enclosed_volume_tolerance needs a closed surface, but this organ is an open sheet");
        }
        const double tolerance = *settings[b].enclosed_volume_tolerance;
        add_enclosed_volume(model, *organ.surface, body.first_vertex, *material, tolerance);
        report.modelled.push_back(
            settings[b].name + ": enclosed volume kept within " + format_number(100.0 * tolerance) +
            " % of rest (patch volume constraint, bulk modulus of " + settings[b].material + ")");
      }
      bodies.push_back(std::move(body));
      continue;
    }
    const TetMesh& mesh = *organ.solid;
    // Each tet takes the material of the innermost organ of this body holding its centroid.
    std::vector<TetMaterial> materials;
    std::map<std::string, int> tets_per_organ;
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k)
        centroid += 0.25 * mesh.vertices.row(mesh.tets(t, k)).transpose();
      std::size_t holder = b;
      for (std::size_t i = 0; i < n; ++i) {
        if (body_of[i] == static_cast<int>(b) && depth[i] > depth[holder] &&
            phantom.organs[i].target->value(centroid) > 0.0) {
          holder = i;
        }
      }
      const MaterialSettings* material = scene.find_material(settings[holder].material);
      if (material == nullptr) {
        throw InputError(settings[holder].name + ": material '" + settings[holder].material +
                         "' is not defined");
      }
      materials.push_back(
          {lame_parameters(material->youngs_modulus_Pa, material->poisson_ratio), material->density_kg_m3});
      ++tets_per_organ[settings[holder].name];
    }
    Body body;
    body.organ = static_cast<int>(b);
    body.first_vertex = add_body(model, k_mm * mesh.vertices, mesh.tets, materials);
    body.vertex_count = mesh.vertices.rows();
    body.locator = std::make_unique<TetLocator>(mesh.vertices, mesh.tets, body.first_vertex);
    std::ostringstream line;
    line << settings[b].name << ": solved as one body of " << mesh.vertices.rows() << " vertices and "
         << mesh.tets.rows() << " tets (materials by tet:";
    for (const auto& [name, count] : tets_per_organ)
      line << ' ' << name << ' ' << count;
    line << ")";
    report.modelled.push_back(line.str());
    if (parent[b] >= 0) {
      for (Eigen::Index f = 0; f < mesh.boundary_faces.rows(); ++f)
        for (int k = 0; k < 3; ++k)
          held.push_back(body.first_vertex + mesh.boundary_faces(f, k));
      report.modelled.push_back(settings[b].name + ": boundary held by " +
                                settings[static_cast<std::size_t>(parent[b])].name +
                                " (it does not move; no slip)");
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (body_of[i] == static_cast<int>(b) && i != b)
        report.modelled.push_back(settings[i].name + ": embedded in " + settings[b].name +
                                  ", follows its tets");
    }
    bodies.push_back(std::move(body));
  }
  PhantomDeformation result;
  if (bodies.empty()) {
    report.skipped.push_back("the solve: no organ is moved by a load");
  }

  auto body_index = [&](int organ) {
    for (std::size_t k = 0; k < bodies.size(); ++k)
      if (bodies[k].organ == organ) return static_cast<int>(k);
    return -1;
  };
  // A point of organ i's rest surface (mm) as an embedding in its body.
  auto embed = [&](std::size_t i, Eigen::Index surface_vertex, const Eigen::Vector3d& x_mm) {
    const Body& body = bodies[static_cast<std::size_t>(body_index(body_of[i]))];
    Embedding e;
    if (body.shell) { // the shell's own vertices (nothing else is embedded in a shell)
      e.vertices = {body.first_vertex + static_cast<int>(surface_vertex), 0, 0, 0};
      e.coefficients = Eigen::Vector4d(1, 0, 0, 0);
      return e;
    }
    if (static_cast<int>(i) == body.organ &&
        phantom.organs[i].tet_vertex_of_surface_vertex.size() > surface_vertex) {
      e.vertices = {body.first_vertex + phantom.organs[i].tet_vertex_of_surface_vertex[surface_vertex], 0, 0,
                    0};
      e.coefficients = Eigen::Vector4d(1, 0, 0, 0);
      return e;
    }
    return body.locator->locate(x_mm);
  };

  // Loads.
  Eigen::MatrixX3d acceleration = Eigen::MatrixX3d::Zero(model.vertex_count(), 3);
  std::vector<PushedPoints> pushes;
  const double nominal_stiffness = [&] {
    double diagonal = 0.0;
    for (const TetElement& e : model.tets)
      diagonal += (e.strain_weight + e.volume_weight) * e.Q.squaredNorm();
    for (const SurfaceElement& e : model.surfaces)
      diagonal += e.weight * e.Q.squaredNorm();
    return model.vertex_count() > 0 ? diagonal / static_cast<double>(model.vertex_count()) : 0.0;
  }();
  for (const LoadSettings& load : scene.deformation.loads) {
    if (load.kind == LoadKind::gravity) {
      for (const Body& body : bodies) {
        bool acts = load.organs.empty();
        for (std::size_t i = 0; i < n; ++i)
          if (body_of[i] == body.organ &&
              std::find(load.organs.begin(), load.organs.end(), settings[i].name) != load.organs.end())
            acts = true;
        if (!acts) continue;
        acceleration.middleRows(body.first_vertex, body.vertex_count).rowwise() =
            load.acceleration_m_s2.transpose();
      }
      report.modelled.push_back("gravity " + format_vector(load.acceleration_m_s2) +
                                " m/s^2 on the bodies' lumped masses");
      continue;
    }
    const std::size_t i = static_cast<std::size_t>(index.at(load.organ));
    if (body_of[i] < 0 || (!phantom.organs[i].surface && !phantom.organs[i].sheet)) {
      report.skipped.push_back("displacement of " + load.organ +
                               ": the organ is not part of a simulated body");
      continue;
    }
    PushedPoints push;
    push.load = &load;
    const Eigen::MatrixX3d& rest = phantom.organs[i].surface ? phantom.organs[i].surface->rest_positions()
                                                             : phantom.organs[i].sheet->vertices;
    const double stiffness = 1e4 * nominal_stiffness;
    for (Eigen::Index v = 0; v < rest.rows(); ++v) {
      const Eigen::Vector3d x = rest.row(v).transpose();
      if ((x - load.region_center_mm).norm() > load.region_radius_mm) continue;
      const Embedding e = embed(i, v, x);
      PointConstraint c;
      c.vertices = e.vertices;
      c.coefficients = e.coefficients;
      c.count = e.coefficients.tail<3>().isZero() ? 1 : 4;
      c.stiffness_N_m = stiffness;
      push.rest_m.push_back(interpolate(e, model.rest_positions_m));
      c.target_m = push.rest_m.back() + k_mm * load.displacement_mm;
      push.constraints.push_back(model.points.size());
      model.points.push_back(c);
    }
    if (push.constraints.empty()) {
      report.skipped.push_back("displacement of " + load.organ + ": no surface point lies within " +
                               format_number(load.region_radius_mm) + " mm of " +
                               format_vector(load.region_center_mm));
      continue;
    }
    report.modelled.push_back("displacement " + format_vector(load.displacement_mm) + " mm of " +
                              std::to_string(push.constraints.size()) + " surface points of " + load.organ +
                              ", by springs of " + format_number(stiffness) +
                              " N/m (10^4 x the mean elastic stiffness)");
    pushes.push_back(std::move(push));
  }

  // The container holds a body's boundary, except where a load pushes (a retractor through an
  // opening of the skull, a paddle on the skin): boundary vertices within 1.5 region radii of a
  // displacement load's centre are released [choice], so the pushed surface is not pinned to a
  // held layer next to it.
  std::size_t released = 0;
  for (int v : held) {
    const Eigen::Vector3d x_mm = model.rest_positions_m.row(v).transpose() / k_mm;
    bool in_opening = false;
    for (const PushedPoints& push : pushes)
      in_opening |= (x_mm - push.load->region_center_mm).norm() <= 1.5 * push.load->region_radius_mm;
    if (in_opening) {
      ++released;
    } else {
      model.fixed[static_cast<std::size_t>(v)] = 1;
    }
  }
  if (released > 0) {
    report.modelled.push_back(
        std::to_string(released) +
        " held boundary vertices released within 1.5 region radii of a displacement load");
  }

  // Obstacles act on every free vertex of every body, by a penalty as stiff as the displacement
  // loads' springs.
  const auto place_obstacles = [&](auto&& amount_of) {
    model.obstacles.clear();
    for (const ObstacleSettings& obstacle : scene.deformation.obstacles) {
      Obstacle o;
      o.shape =
          obstacle.shape == ObstacleShape::sphere ? Obstacle::Shape::sphere : Obstacle::Shape::half_space;
      o.point_m = k_mm * (obstacle.point_mm + amount_of(obstacle) * obstacle.displacement_mm);
      o.normal = obstacle.normal;
      o.radius_m = k_mm * obstacle.radius_mm;
      model.obstacles.push_back(o);
    }
  };
  if (!scene.deformation.obstacles.empty() && !bodies.empty()) {
    model.contact_stiffness_N_m = 1e4 * nominal_stiffness;
    place_obstacles([](const ObstacleSettings&) { return 0.0; });
    for (const ObstacleSettings& o : scene.deformation.obstacles) {
      report.modelled.push_back(
          std::string(to_string(o.shape)) + " obstacle " +
          (o.shape == ObstacleShape::sphere
               ? "centred at " + format_vector(o.point_mm) + " mm, radius " + format_number(o.radius_mm) +
                     " mm"
               : "through " + format_vector(o.point_mm) + " mm, normal " + format_vector(o.normal)) +
          ", moved by " + format_vector(o.displacement_mm) + " mm; contacts by a penalty of " +
          format_number(model.contact_stiffness_N_m) + " N/m (10^4 x the mean elastic stiffness)");
    }
  } else if (!scene.deformation.obstacles.empty()) {
    report.skipped.push_back("obstacles: no organ is simulated, nothing can touch them");
  }

  add_collisions(scene, phantom, bodies, nominal_stiffness, model, report);

  Eigen::MatrixX3d p = model.rest_positions_m;
  if (!bodies.empty()) {
    const SolverSettings& solver = scene.deformation.solver;
    const bool jacobi = solver.method == SolverMethod::jacobi_chebyshev;
    const bool position_based =
        solver.method == SolverMethod::xpbd || solver.method == SolverMethod::gauss_seidel_pbd;
    const bool dynamic = scene.deformation.mode == DeformationMode::dynamic;
    if (position_based && !dynamic) {
      const std::string key = "deformation.solver.method";
      throw InputError(Diagnostic{
          scene.location_of(key), key,
          "expected local_global, jacobi_chebyshev or newton for a quasi_static scene (" +
              std::string(to_string(solver.method)) + " steps in time: it needs mode dynamic), found " +
              std::string(to_string(solver.method))}
                           .format());
    }
    StopCriteria stop;
    stop.max_iterations = solver.max_iterations;
    stop.relative_energy_decrease = solver.relative_energy_tolerance;
    stop.position_change_m = k_mm * solver.position_tolerance_mm;
    const double h = scene.deformation.time_step_s;
    // Quasi-static solves apply the loads in load_steps equal increments, each starting from the
    // last; dynamic mode makes one solve per frame.
    const int frames = dynamic ? scene.deformation.frames : scene.deformation.load_steps;
    std::unique_ptr<LocalGlobalSolver> local_global;
    try {
      if (solver.method == SolverMethod::local_global || jacobi)
        local_global =
            std::make_unique<LocalGlobalSolver>(model, dynamic ? 1.0 / (h * h) : 0.0, solver.threads);
    } catch (const std::runtime_error& error) {
      throw InputError(std::string("deformation: ") + error.what() +
                       "; in quasi-static mode put each loaded organ inside a fixed organ or list it in "
                       "deformation.fixed");
    }
    if (!dynamic) model.external_forces_N = model.masses_kg.asDiagonal() * acceleration;
    Eigen::MatrixX3d velocity = Eigen::MatrixX3d::Zero(p.rows(), 3);
    ProgressBar progress(reporter, "deform", static_cast<std::size_t>(frames));
    for (int frame = 0; frame < frames; ++frame) {
      const double t = (frame + 1) * h;
      const double increment = static_cast<double>(frame + 1) / frames;
      for (PushedPoints& push : pushes) {
        const double amount = dynamic ? profile(push.load->motion, push.load->period_s, t) : increment;
        for (std::size_t k = 0; k < push.constraints.size(); ++k)
          model.points[push.constraints[k]].target_m =
              push.rest_m[k] + amount * k_mm * push.load->displacement_mm;
      }
      if (!model.obstacles.empty()) {
        place_obstacles([&](const ObstacleSettings& o) {
          return dynamic ? profile(o.motion, o.period_s, t) : increment;
        });
      }
      StepInertia inertia;
      if (dynamic) {
        inertia.weight = 1.0 / (h * h);
        inertia.target_m = p + h * velocity + h * h * acceleration;
      }
      const Eigen::MatrixX3d previous = p;
      if (position_based) { // they start from the prediction s (Macklin et al.)
        for (Eigen::Index v = 0; v < p.rows(); ++v)
          if (!model.fixed[static_cast<std::size_t>(v)]) p.row(v) = inertia.target_m.row(v);
      }
      SolveReport solve = jacobi         ? local_global->solve_jacobi_chebyshev(p, inertia.target_m, stop)
                          : local_global ? local_global->solve(p, inertia.target_m, stop)
                          : position_based
                              ? position_based_solve(solver.method == SolverMethod::xpbd
                                                         ? PositionBasedVariant::xpbd
                                                         : PositionBasedVariant::gauss_seidel_pbd,
                                                     model, inertia, p, stop)
                              : newton_solve(model, inertia, p, stop);
      if (!p.allFinite()) throw InputError("deformation: the solver produced non-finite positions");
      if (dynamic) velocity = (p - previous) / h;
      result.solves.push_back(std::move(solve));
      progress.advance();
    }
    const SolveReport& last = result.solves.back();
    report.modelled.push_back(
        std::string(last.solver) + " " +
        (dynamic      ? "dynamic, " + std::to_string(frames) + " frames of " + format_number(h) + " s"
         : frames > 1 ? "quasi-static in " + std::to_string(frames) + " load steps"
                      : "quasi-static") +
        ": last solve " + std::to_string(last.iterations) + " iterations, stopped by " + last.stopped_by +
        ", residual " + format_number(last.residual_N) + " N");
    report.accuracy["solver residual N"] = last.residual_N;
    report.accuracy["solver iterations"] = last.iterations;
    for (const PointConstraint& c : model.points) {
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (int k = 0; k < c.count; ++k)
        x += c.coefficients[k] * p.row(c.vertices[static_cast<std::size_t>(k)]).transpose();
      result.attachment_error_mm = std::max(result.attachment_error_mm, (x - c.target_m).norm() / k_mm);
    }
    report.accuracy["displacement load error mm"] = result.attachment_error_mm;
    if (!model.obstacles.empty()) {
      double deepest = 0.0;
      for (Eigen::Index v = 0; v < p.rows(); ++v) {
        if (model.fixed[static_cast<std::size_t>(v)]) continue;
        for (const Obstacle& o : model.obstacles)
          deepest = std::max(deepest, -o.signed_distance(p.row(v).transpose()));
      }
      result.obstacle_penetration_mm = deepest / k_mm;
      report.accuracy["obstacle penetration mm"] = result.obstacle_penetration_mm;
      report.accuracy["vertices in contact"] = last.contacts;
      report.modelled.push_back(
          std::to_string(last.contacts) + " vertices in contact with obstacles at the end (" +
          std::to_string(last.rank_updates) + " rank-one updates of the factor as contacts came and went)");
    }
    report.status = "done";
  }

  // Every organ's vertices.
  const Eigen::MatrixX3d deformed_mm = p / k_mm;
  for (const Body& body : bodies) {
    if (body.shell) continue; // the displacement fields come from solids' tets
    const TetMesh& mesh = *phantom.organs[static_cast<std::size_t>(body.organ)].solid;
    result.bodies.push_back({settings[static_cast<std::size_t>(body.organ)].name, mesh.vertices,
                             deformed_mm.middleRows(body.first_vertex, mesh.vertices.rows()), mesh.tets});
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Organ& organ = phantom.organs[i];
    OrganDeformation d;
    d.organ = settings[i].name;
    const Eigen::MatrixX3d surface = organ.surface ? organ.surface->rest_positions()
                                     : organ.sheet ? organ.sheet->vertices
                                                   : Eigen::MatrixX3d();
    d.surface_mm = surface;
    if (organ.solid) d.solid_mm = organ.solid->vertices;
    if (body_of[i] < 0) {
      d.moved_by = motion[i] == OrganMotion::fixed ? "fixed" : "rigid";
    } else {
      const Body& body = bodies[static_cast<std::size_t>(body_index(body_of[i]))];
      const bool is_body = body.organ == static_cast<int>(i);
      d.moved_by = is_body ? "solver" : "embedded in " + settings[static_cast<std::size_t>(body.organ)].name;
      for (Eigen::Index v = 0; v < surface.rows(); ++v)
        d.surface_mm.row(v) = interpolate(embed(i, v, surface.row(v).transpose()), deformed_mm).transpose();
      if (organ.solid) {
        if (is_body) {
          d.solid_mm = deformed_mm.middleRows(body.first_vertex, organ.solid->vertices.rows());
        } else {
          for (Eigen::Index v = 0; v < d.solid_mm.rows(); ++v)
            d.solid_mm.row(v) =
                interpolate(body.locator->locate(organ.solid->vertices.row(v).transpose()), deformed_mm)
                    .transpose();
        }
      }
    }
    result.organs.push_back(std::move(d));
  }
  return result;
}

Phantom deformed_phantom(const Phantom& phantom, const PhantomDeformation& deformation) {
  Phantom moved = phantom;
  for (std::size_t i = 0; i < moved.organs.size(); ++i) {
    Organ& organ = moved.organs[i];
    const OrganDeformation& d = deformation.organs[i];
    if (organ.surface) organ.surface->set_positions(d.surface_mm);
    if (organ.sheet) organ.sheet->vertices = d.surface_mm;
    if (organ.solid) organ.solid->vertices = d.solid_mm;
  }
  return moved;
}

} // namespace phantasm
