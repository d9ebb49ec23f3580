#include "sim/twisting_bar.hpp"

#include "anatomy/structured_mesh.hpp"

#include <Eigen/Geometry>

namespace phantasm {

TwistingBarStep twisting_bar_step(const TwistingBarSettings& s) {
  const TetMesh mesh =
      structured_box(s.size_mm, s.cells, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  TwistingBarStep step;
  add_body(step.model, 1e-3 * mesh.vertices, mesh.tets, lame_parameters(s.youngs_modulus_Pa, s.poisson_ratio),
           s.density_kg_m3);
  const Eigen::MatrixX3d& rest = step.model.rest_positions_m;
  const double h = s.time_step_s;
  step.inertia.weight = 1.0 / (h * h);
  step.inertia.target_m = rest;
  step.inertia.target_m.col(1).array() -= h * h * s.gravity_m_s2;
  step.start_m = step.inertia.target_m;
  const double half = 0.5e-3 * s.size_mm.z();
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(s.twist_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (Eigen::Index v = 0; v < rest.rows(); ++v) {
    const double z = rest(v, 2);
    if (z < -half + 1e-9) {
      step.model.fixed[static_cast<std::size_t>(v)] = 1;
      step.start_m.row(v) = rest.row(v);
    } else if (z > half - 1e-9) {
      step.model.fixed[static_cast<std::size_t>(v)] = 1;
      step.start_m.row(v) = (turn * rest.row(v).transpose()).transpose();
    }
  }
  return step;
}

} // namespace phantasm
