// The twisting bar, the solvers' benchmark problem: a clamped box turned at one end under
// gravity, as one dynamic step for the benchmarks and tests.
#pragma once

#include "sim/elastic_model.hpp"

namespace phantasm {

/// The twisting bar of docs/method.md section 6, the benchmark problem of the solvers: a box of
/// size_mm meshed with cells (5 tets per cell), one end (z min) clamped, the other end (z max)
/// turned by twist_deg about the bar's axis, gravity along -y. One dynamic step of h from rest.
struct TwistingBarSettings {
  Eigen::Vector3d size_mm{60, 60, 280};
  Eigen::Vector3i cells{6, 6, 28};
  double youngs_modulus_Pa = 1e5;
  double poisson_ratio = 0.45;
  double density_kg_m3 = 1000.0;
  double twist_deg = 30.0;
  double time_step_s = 1.0 / 30.0;
  double gravity_m_s2 = 9.81; ///< along -y
};

struct TwistingBarStep {
  ElasticModel model;
  StepInertia inertia;      ///< 1/h^2 and s = rest + h^2 g
  Eigen::MatrixX3d start_m; ///< s, with the clamped and turned ends at their prescribed places
};

TwistingBarStep twisting_bar_step(const TwistingBarSettings& settings);

} // namespace phantasm
