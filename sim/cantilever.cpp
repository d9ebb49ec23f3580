#include "sim/cantilever.hpp"

#include "anatomy/implicit_shape.hpp"
#include "anatomy/structured_mesh.hpp"
#include "anatomy/tet_mesh.hpp"
#include "sim/vertex_star_volumes.hpp"

#include <cmath>

namespace phantasm {

namespace {
constexpr double k_face_tolerance_m = 1e-6; ///< vertices of the end faces: within 1e-3 mm
} // namespace

ElasticModel cantilever_model(const CantileverSettings& s) {
  const Eigen::Vector3d center = 0.5 * s.size_mm;
  const bool structured = !(s.tet_size_mm > 0.0);
  const TetMesh mesh = structured
                           ? structured_box(s.size_mm, s.cells, Eigen::Matrix3d::Identity(), center)
                           : mesh_implicit_solid(*make_box(center, s.size_mm, Eigen::Matrix3d::Identity()),
                                                 criteria_for_tet_size(s.tet_size_mm), 1);
  ElasticModel model;
  add_body(model, 1e-3 * mesh.vertices, mesh.tets, lame_parameters(s.youngs_modulus_Pa, s.poisson_ratio),
           s.density_kg_m3);
  if (s.volume == VolumeFormulation::tet_group)
    move_bulk_to_tet_groups(model, structured
                                       ? structured_box_cells(s.cells)
                                       : group_tets(mesh, s.group_size > 0 ? s.group_size : tets_per_group));
  if (s.volume == VolumeFormulation::vertex_star) move_bulk_to_vertex_stars(model);
  model.external_forces_N = Eigen::MatrixX3d::Zero(model.vertex_count(), 3);
  model.external_forces_N.col(1) = -s.gravity_m_s2 * model.masses_kg;
  const double low = model.rest_positions_m.col(2).minCoeff();
  for (Eigen::Index v = 0; v < model.vertex_count(); ++v)
    model.fixed[static_cast<std::size_t>(v)] =
        model.rest_positions_m(v, 2) < low + k_face_tolerance_m ? 1 : 0;
  return model;
}

double cantilever_tip_deflection_mm(const ElasticModel& model, const Eigen::MatrixX3d& p) {
  const double length = model.rest_positions_m.col(2).maxCoeff();
  double sum = 0.0;
  int count = 0;
  for (Eigen::Index v = 0; v < p.rows(); ++v) {
    if (model.rest_positions_m(v, 2) > length - k_face_tolerance_m) {
      sum += model.rest_positions_m(v, 1) - p(v, 1);
      ++count;
    }
  }
  return count > 0 ? 1e3 * sum / count : 0.0;
}

double cantilever_beam_theory_mm(const CantileverSettings& s, bool timoshenko) {
  const double width = 1e-3 * s.size_mm.x(), height = 1e-3 * s.size_mm.y(), length = 1e-3 * s.size_mm.z();
  const double area = width * height, inertia = width * std::pow(height, 3) / 12.0;
  const double q = s.density_kg_m3 * s.gravity_m_s2 * area;
  double deflection = q * std::pow(length, 4) / (8.0 * s.youngs_modulus_Pa * inertia);
  if (timoshenko) {
    const double nu = s.poisson_ratio;
    const double kappa = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu);
    const double shear = s.youngs_modulus_Pa / (2.0 * (1.0 + nu));
    deflection += q * length * length / (2.0 * kappa * shear * area);
  }
  return 1e3 * deflection;
}

} // namespace phantasm
