// Locking of the bulk term as nu -> 1/2 (#16, docs/deformation.md): the cantilever 20 x 20 x
// 100 mm (E = 250 kPa, 1000 kg/m^3, gravity, z-min face held) on n x n x 5n cells of 5 tets,
// Newton to 1e-9 N, with the bulk term per tet, per vertex star and per hexahedral cell (its 5
// tets); prints the mean downward deflection of the free face at nu = 0.45, 0.49, 0.499.
// Usage: volume_locking [n] (default 4)

#include "anatomy/structured_mesh.hpp"
#include "sim/elastic_model.hpp"
#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/vertex_star_volumes.hpp"

#include <cstdio>
#include <cstdlib>
#include <unistd.h>
#include <vector>

using namespace phantasm;

namespace {

/// Local/global at nu = 0.45 with the scene defaults (relative residual 1e-3 of a vertex's
/// weight, at most 2000 iterations): iterations, converged, tip (mm).
struct LocalGlobalRun {
  int iterations = 0;
  bool converged = false;
  double tip_mm = 0.0;
};

double tip_mm(int n, double nu, VolumeFormulation formulation, LocalGlobalRun* local_global = nullptr) {
  const Eigen::Vector3d size(20, 20, 100);
  const TetMesh mesh = structured_box(size, {n, n, 5 * n}, Eigen::Matrix3d::Identity(), 0.5 * size);
  ElasticModel model;
  add_body(model, 1e-3 * mesh.vertices, mesh.tets, lame_parameters(2.5e5, nu), 1000.0);
  if (formulation == VolumeFormulation::vertex_star) move_bulk_to_vertex_stars(model);
  if (formulation == VolumeFormulation::tet_group) { // structured_box: 5 consecutive tets per cell
    std::vector<std::vector<int>> cells(model.tets.size() / 5);
    for (std::size_t t = 0; t < model.tets.size(); ++t)
      cells[t / 5].push_back(static_cast<int>(t));
    move_bulk_to_tet_groups(model, cells);
  }
  model.external_forces_N = Eigen::MatrixX3d::Zero(model.vertex_count(), 3);
  model.external_forces_N.col(1) = -9.81 * model.masses_kg;
  for (Eigen::Index v = 0; v < model.vertex_count(); ++v)
    model.fixed[static_cast<std::size_t>(v)] = model.rest_positions_m(v, 2) < 1e-9 ? 1 : 0;
  if (local_global) {
    Eigen::MatrixX3d q = model.rest_positions_m;
    StopCriteria defaults;
    defaults.max_iterations = 2000;
    defaults.force_scale_N = 9.81 * model.masses_kg.maxCoeff();
    LocalGlobalSolver solver(model, 0.0, 1);
    const SolveReport report = solver.solve(q, q, defaults);
    local_global->iterations = report.iterations;
    local_global->converged = report.converged;
    double sum = 0.0;
    int count = 0;
    for (Eigen::Index v = 0; v < q.rows(); ++v) {
      if (model.rest_positions_m(v, 2) > 0.1 - 1e-9) {
        sum += model.rest_positions_m(v, 1) - q(v, 1);
        ++count;
      }
    }
    local_global->tip_mm = 1e3 * sum / count;
  }
  Eigen::MatrixX3d p = model.rest_positions_m;
  StopCriteria stop;
  stop.max_iterations = 200;
  stop.gradient_norm_N = 1e-9;
  newton_solve(model, StepInertia{}, p, stop);
  double sum = 0.0;
  int count = 0;
  for (Eigen::Index v = 0; v < p.rows(); ++v) {
    if (model.rest_positions_m(v, 2) > 0.1 - 1e-9) {
      sum += model.rest_positions_m(v, 1) - p(v, 1);
      ++count;
    }
  }
  return 1e3 * sum / count;
}

} // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 4;
  // The table goes to stdout; CHOLMOD's warnings (a singular Hessian, which Newton shifts) to stderr.
  std::FILE* table = fdopen(dup(1), "w");
  dup2(2, 1);
  std::fprintf(table,
               "| bulk term, %d x %d x %d cells | nu 0.45 | nu 0.49 | nu 0.499 | 0.499 vs 0.45 | "
               "local/global at 0.45 |\n",
               n, n, 5 * n);
  std::fprintf(table, "|---|---|---|---|---|---|\n");
  const std::pair<VolumeFormulation, const char*> formulations[] = {
      {VolumeFormulation::tet, "per tet"},
      {VolumeFormulation::vertex_star, "vertex stars"},
      {VolumeFormulation::tet_group, "hexahedral cells"}};
  for (const auto& [formulation, name] : formulations) {
    double tip[3];
    const double nus[3] = {0.45, 0.49, 0.499};
    LocalGlobalRun run;
    for (int k = 0; k < 3; ++k)
      tip[k] = tip_mm(n, nus[k], formulation, k == 0 ? &run : nullptr);
    std::fprintf(table, "| %s | %.2f mm | %.2f mm | %.2f mm | %+.1f %% | %d iterations, %s, %.2f mm |\n",
                 name, tip[0], tip[1], tip[2], 100.0 * (tip[2] / tip[0] - 1.0), run.iterations,
                 run.converged ? "converged" : "not converged", run.tip_mm);
    std::fflush(table);
  }
}
