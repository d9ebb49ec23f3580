// Bodies of the deformation stage: the assignment of organs to bodies, the embedding of nested
// organs in a body's tets, and the organs' deformed vertices interpolated from the solve.
#include "sim/body_embedding.hpp"

namespace phantasm::sim_detail {

Embedding TetLocator::locate(const Eigen::Vector3d& x) const {
  Embedding result;
  const TetLocation location = m_locator.nearest(x);
  if (location.tet < 0) return result;
  for (int k = 0; k < 4; ++k)
    result.vertices[static_cast<std::size_t>(k)] = m_first + m_tets(location.tet, k);
  result.coefficients = location.weights;
  return result;
}

Eigen::Vector3d interpolate(const Embedding& e, const Eigen::MatrixX3d& p) {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k)
    x += e.coefficients[k] * p.row(e.vertices[static_cast<std::size_t>(k)]).transpose();
  return x;
}

const TriangleMesh* shell_mesh(const Organ& organ) {
  if (organ.sheet) return &*organ.sheet;
  if (organ.surface) return &organ.surface->base_mesh();
  return nullptr;
}

BodyAssignment assign_bodies(const DeformationSettings& deformation, const OrganTable& organs,
                             const Phantom& phantom, StageReport& report) {
  const std::size_t n = organs.size();
  std::vector<OrganMotion> motion = classify_organ_motion(deformation, organs);
  // The body of each organ: its topmost simulated ancestor-or-self (-1: none).
  std::vector<int> body_of(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    for (int j = static_cast<int>(i); j >= 0; j = organs[static_cast<std::size_t>(j)].parent) {
      if (motion[static_cast<std::size_t>(j)] == OrganMotion::simulated) body_of[i] = j;
    }
  }
  // A surface organ (no tet mesh) is simulated as a shell of its triangles; organs nested in it
  // have nothing to follow (no interior) and stay in place.
  for (std::size_t b = 0; b < n; ++b) {
    if (body_of[b] != static_cast<int>(b) || phantom.organs[b].solid) continue;
    if (shell_mesh(phantom.organs[b]) == nullptr) {
      report.skipped.push_back(organs[b].name + ": a load acts on it but it has neither tets nor triangles");
      for (std::size_t i = 0; i < n; ++i)
        if (body_of[i] == static_cast<int>(b)) body_of[i] = -1;
      continue;
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (i == b || body_of[i] != static_cast<int>(b)) continue;
      body_of[i] = -1;
      report.skipped.push_back(organs[i].name + ": inside the shell " + organs[b].name +
                               ", which has no interior to carry it; it stays in place");
    }
  }
  return {std::move(motion), std::move(body_of)};
}

int body_index(const std::vector<Body>& bodies, int organ) {
  for (std::size_t k = 0; k < bodies.size(); ++k)
    if (bodies[k].organ == organ) return static_cast<int>(k);
  return -1;
}

Embedding embed(const Phantom& phantom, const BodyAssignment& assignment, const std::vector<Body>& bodies,
                std::size_t i, Eigen::Index surface_vertex, const Eigen::Vector3d& x_mm) {
  const Body& body = bodies[static_cast<std::size_t>(body_index(bodies, assignment.body_of[i]))];
  Embedding e;
  if (body.shell) { // the shell's own vertices (nothing else is embedded in a shell)
    e.vertices = {body.first_vertex + static_cast<int>(surface_vertex), 0, 0, 0};
    e.coefficients = Eigen::Vector4d(1, 0, 0, 0);
    return e;
  }
  if (static_cast<int>(i) == body.organ && phantom.organs[i].solid &&
      body.mesh.get() == &*phantom.organs[i].solid &&
      phantom.organs[i].tet_vertex_of_surface_vertex.size() > surface_vertex) {
    e.vertices = {body.first_vertex + phantom.organs[i].tet_vertex_of_surface_vertex[surface_vertex], 0, 0,
                  0};
    e.coefficients = Eigen::Vector4d(1, 0, 0, 0);
    return e;
  }
  return body.locator->locate(x_mm);
}

void collect_deformations(const OrganTable& organs, const Phantom& phantom, const BodyAssignment& assignment,
                          const std::vector<Body>& bodies, const Eigen::MatrixX3d& deformed_mm,
                          PhantomDeformation& result) {
  const std::size_t n = organs.size();
  for (const Body& body : bodies) {
    if (body.shell) continue; // the displacement fields come from solids' tets
    const TetMesh& mesh = *body.mesh;
    DeformedBody deformed;
    deformed.organ = organs[static_cast<std::size_t>(body.organ)].name;
    deformed.rest_mm = mesh.vertices;
    deformed.deformed_mm = deformed_mm.middleRows(body.first_vertex, mesh.vertices.rows());
    deformed.tets = mesh.tets;
    deformed.tet_organ = body.tet_organ;
    result.bodies.push_back(std::move(deformed));
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Organ& organ = phantom.organs[i];
    OrganDeformation d;
    d.organ = organs[i].name;
    const Eigen::MatrixX3d surface = organ.surface ? organ.surface->rest_positions()
                                     : organ.sheet ? organ.sheet->vertices
                                                   : Eigen::MatrixX3d();
    d.surface_mm = surface;
    if (organ.solid) d.solid_mm = organ.solid->vertices;
    if (assignment.body_of[i] < 0) {
      d.moved_by = assignment.motion[i] == OrganMotion::fixed ? "fixed" : "rigid";
    } else {
      const Body& body = bodies[static_cast<std::size_t>(body_index(bodies, assignment.body_of[i]))];
      const bool is_body = body.organ == static_cast<int>(i);
      d.moved_by = is_body ? "solver" : "embedded in " + organs[static_cast<std::size_t>(body.organ)].name;
      for (Eigen::Index v = 0; v < surface.rows(); ++v)
        d.surface_mm.row(v) =
            interpolate(embed(phantom, assignment, bodies, i, v, surface.row(v).transpose()), deformed_mm)
                .transpose();
      if (organ.solid) {
        if (is_body && body.mesh.get() == &*organ.solid) {
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
}

} // namespace phantasm::sim_detail
