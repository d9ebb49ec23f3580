// Locking of the bulk term as nu -> 1/2 (#16, docs/deformation.md).
//
// volume_locking [N]: the cantilever 20 x 20 x 100 mm (E = 250 kPa, 1000 kg/m^3, gravity, z-min
//   face held; sim/cantilever.hpp) on N x N x 5N structured cells (default 4), bulk term per tet,
//   per vertex star and per hexahedral cell (its 5 tets); Newton to 1e-9 N at nu = 0.45, 0.49,
//   0.499, and local/global (scene defaults, 2000 iterations at most) at 0.45 and 0.499.
// volume_locking cgal SIZE [GROUP ...]: the same cantilever on a CGAL tet mesh of SIZE mm, per
//   tet, per vertex star and in groups of GROUP tets (default 5; group_tets); cgal-groups: the
//   groups only, Newton only (the refined reference).
// volume_locking head [SCENE] [newton]: the head's deformation (data-synthetic/head.yaml) with the
//   brain's Poisson ratio at 0.45, 0.49, 0.499 and each formulation (the scene's solver, or
//   Newton): the bodies' volume change, whole and RMS over tets and over groups of 8 tets.
// volume_locking head-gravity [local-global]: the same with gravity alone (no retractor), Newton
//   (or the scene's local/global).
// volume_locking local-global NU [cgal SIZE] [per-tet]: the cantilever with the bulk term on tet
//   groups (the 4 x 4 x 20 structured cells, or groups of 8 on a CGAL mesh of SIZE mm; per-tet:
//   per tet instead) at Poisson ratio NU:
//   Newton's tip (to 1e-9 N) and local/global's with the scene defaults (relative residual 1e-3,
//   2000 iterations at most, one thread): iterations, converged, tip, its difference from
//   Newton's, seconds. One row per process, so that the process's time is the solve's.
// Tables go to stdout (Markdown).

#include "anatomy/phantom.hpp"
#include "anatomy/tet_mesh.hpp"
#include "core/format.hpp"
#include "scene/scene.hpp"
#include "sim/cantilever.hpp"
#include "sim/deform_phantom.hpp"
#include "sim/load_type.hpp"
#include "sim/local_global.hpp"
#include "sim/newton.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unistd.h>
#include <vector>

using namespace phantasm;

namespace {

std::FILE* table = stdout;

const char* name_of(VolumeFormulation v, bool structured) {
  switch (v) {
  case VolumeFormulation::tet: return "per tet";
  case VolumeFormulation::vertex_star: return "vertex stars";
  case VolumeFormulation::tet_group: return structured ? "hexahedral cells" : "groups";
  case VolumeFormulation::tet_group_and_tet:
    return structured ? "hexahedral cells and tets" : "groups and tets";
  }
  return "?";
}

double newton_tip_mm(const ElasticModel& model) {
  Eigen::MatrixX3d p = model.rest_positions_m;
  StopCriteria stop;
  stop.max_iterations = 200;
  stop.gradient_norm_N = 1e-9;
  newton_solve(model, StepInertia{}, p, stop);
  return cantilever_tip_deflection_mm(model, p);
}

/// A quasi-static local/global solve of the model on one thread with the scene defaults (relative
/// residual 1e-3 of a vertex's weight, at most 2000 iterations): its report, the positions
/// reached (`q`) and the solve's seconds.
SolveReport solve_local_global(const ElasticModel& model, Eigen::MatrixX3d& q, double& seconds) {
  q = model.rest_positions_m;
  StopCriteria defaults;
  defaults.max_iterations = 2000;
  defaults.force_scale_N = 9.81 * model.masses_kg.maxCoeff();
  LocalGlobalSolver solver(model, 0.0, 1);
  const auto start = std::chrono::steady_clock::now();
  const SolveReport report = solver.solve(q, q, defaults);
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

/// Local/global with the scene defaults: "iterations, converged or not, tip".
std::string local_global_run(const ElasticModel& model) {
  Eigen::MatrixX3d q;
  double seconds = 0.0;
  const SolveReport report = solve_local_global(model, q, seconds);
  char text[160];
  std::snprintf(text, sizeof text, "%d it., %s, %.2f mm, %.1f s", report.iterations,
                report.converged ? "converged" : "not converged", cantilever_tip_deflection_mm(model, q),
                seconds);
  return text;
}

void cantilever_row(CantileverSettings s, const char* name, bool with_local_global) {
  const double nus[3] = {0.45, 0.49, 0.499};
  double tip[3];
  std::string runs[2];
  long tets = 0, constraints = 0;
  for (int k = 0; k < 3; ++k) {
    s.poisson_ratio = nus[k];
    const ElasticModel model = cantilever_model(s);
    tets = static_cast<long>(model.tets.size());
    constraints = s.volume == VolumeFormulation::tet_group     ? static_cast<long>(model.tet_groups.size())
                  : s.volume == VolumeFormulation::vertex_star ? static_cast<long>(model.volumes.size())
                                                               : tets;
    tip[k] = newton_tip_mm(model);
    if (with_local_global && k != 1) runs[k / 2] = local_global_run(model);
  }
  std::fprintf(table, "| %s | %ld / %ld | %.2f mm | %.2f mm | %.2f mm | %+.1f %% | %s | %s |\n", name,
               constraints, tets, tip[0], tip[1], tip[2], 100.0 * (tip[2] / tip[0] - 1.0), runs[0].c_str(),
               runs[1].c_str());
  std::fflush(table);
}

void header(const char* mesh) {
  std::fprintf(table,
               "| bulk term, %s | constraints / tets | nu 0.45 | nu 0.49 | nu 0.499 | 0.499 vs 0.45 | "
               "local/global at 0.45 | local/global at 0.499 |\n",
               mesh);
  std::fprintf(table, "|---|---|---|---|---|---|---|---|\n");
}

void beam_theory(const CantileverSettings& s) {
  CantileverSettings t = s;
  std::fprintf(table, "\nEuler-Bernoulli %.2f mm; Timoshenko", cantilever_beam_theory_mm(s, false));
  for (double nu : {0.45, 0.49, 0.499}) {
    t.poisson_ratio = nu;
    std::fprintf(table, " %.2f", cantilever_beam_theory_mm(t, true));
  }
  std::fprintf(table, " mm (nu 0.45, 0.49, 0.499)\n");
}

int structured(int n) {
  CantileverSettings s;
  s.cells = {n, n, 5 * n};
  char mesh[64];
  std::snprintf(mesh, sizeof mesh, "%d x %d x %d cells", n, n, 5 * n);
  header(mesh);
  for (VolumeFormulation v :
       {VolumeFormulation::tet, VolumeFormulation::vertex_star, VolumeFormulation::tet_group}) {
    s.volume = v;
    cantilever_row(s, name_of(v, true), true);
  }
  beam_theory(s);
  return 0;
}

int unstructured(double size, std::vector<int> group_sizes, bool groups_only) {
  if (group_sizes.empty()) group_sizes = {5};
  CantileverSettings s;
  s.tet_size_mm = size;
  char mesh[64];
  std::snprintf(mesh, sizeof mesh, "CGAL tets of %g mm", size);
  header(mesh);
  if (!groups_only) {
    s.volume = VolumeFormulation::tet;
    cantilever_row(s, "per tet", false);
    s.volume = VolumeFormulation::vertex_star;
    cantilever_row(s, "vertex stars", false);
  }
  for (int g : group_sizes) {
    s.volume = VolumeFormulation::tet_group;
    s.group_size = g;
    char name[64];
    std::snprintf(name, sizeof name, "groups of %d tets", g);
    cantilever_row(s, name, !groups_only);
  }
  beam_theory(s);
  return 0;
}

int local_global_row(double nu, double tet_size_mm, bool per_tet) {
  CantileverSettings s;
  s.poisson_ratio = nu;
  s.volume = per_tet ? VolumeFormulation::tet : VolumeFormulation::tet_group;
  s.tet_size_mm = tet_size_mm;
  if (tet_size_mm > 0.0) s.group_size = 8;
  const ElasticModel model = cantilever_model(s);
  const double newton = newton_tip_mm(model);
  Eigen::MatrixX3d q;
  double seconds = 0.0;
  const SolveReport report = solve_local_global(model, q, seconds);
  const double tip = cantilever_tip_deflection_mm(model, q);
  std::fprintf(table, "| %s | %g | %.2f mm | %d | %s (%.2g) | %.3f mm | %+.3f %% | %.2f s |\n",
               per_tet ? (tet_size_mm > 0.0 ? "CGAL, per tet" : "4 x 4 x 20 cells, per tet")
                       : (tet_size_mm > 0.0 ? "CGAL, groups of 8" : "4 x 4 x 20 cells"),
               nu, newton, report.iterations, report.converged ? "yes" : "no", report.relative_residual, tip,
               100.0 * (tip / newton - 1.0), seconds);
  return 0;
}

int head(const std::string& path, bool newton, bool gravity_only) {
  SceneLoadResult loaded = load_scene(path);
  if (!loaded.scene) {
    std::fprintf(stderr, "%s", format_diagnostics(loaded.problems).c_str());
    return 2;
  }
  Scene scene = *loaded.scene;
  Reporter quiet = Reporter::silent();
  const Phantom phantom = build_phantom(scene.anatomy, {}, quiet);
  std::fprintf(table, "| bulk term | brain nu | volume change | RMS per tet | RMS per 8 tets | iterations | "
                      "converged |\n");
  std::fprintf(table, "|---|---|---|---|---|---|---|\n");
  for (VolumeFormulation v :
       {VolumeFormulation::tet, VolumeFormulation::vertex_star, VolumeFormulation::tet_group}) {
    for (double nu : {0.45, 0.49, 0.499}) {
      DeformationSettings d = scene.deformation;
      d.volume = v;
      if (newton) d.solver.method = SolverMethod::newton;
      if (gravity_only)
        d.loads.erase(
            std::remove_if(d.loads.begin(), d.loads.end(),
                           [](const LoadSettings& l) { return !load_type(l.kind).accelerates_masses; }),
            d.loads.end());
      for (MaterialSettings& m : d.materials)
        if (m.name == "brain") m.poisson_ratio = nu;
      StageReport report;
      const PhantomDeformation result = deform_phantom(d, scene.organs, phantom, report, quiet);
      // Volume changes: the whole body's, and the RMS (volume-weighted) over single tets and over
      // groups of 8 tets (group_tets: the same partition for every formulation).
      double rest = 0.0, deformed = 0.0, tet_sum = 0.0, group_sum = 0.0;
      for (const DeformedBody& body : result.bodies) {
        std::vector<double> rest_volume(static_cast<std::size_t>(body.tets.rows()));
        std::vector<double> deformed_volume(rest_volume.size());
        for (Eigen::Index t = 0; t < body.tets.rows(); ++t) {
          Eigen::Matrix3d R, D;
          for (int k = 0; k < 3; ++k) {
            R.col(k) =
                (body.rest_mm.row(body.tets(t, k + 1)) - body.rest_mm.row(body.tets(t, 0))).transpose();
            D.col(k) = (body.deformed_mm.row(body.tets(t, k + 1)) - body.deformed_mm.row(body.tets(t, 0)))
                           .transpose();
          }
          rest_volume[static_cast<std::size_t>(t)] = R.determinant() / 6.0;
          deformed_volume[static_cast<std::size_t>(t)] = D.determinant() / 6.0;
          rest += R.determinant() / 6.0;
          deformed += D.determinant() / 6.0;
          tet_sum += std::pow(D.determinant() / R.determinant() - 1.0, 2) * R.determinant() / 6.0;
        }
        TetMesh mesh;
        mesh.vertices = body.rest_mm;
        mesh.tets = body.tets;
        for (const std::vector<int>& group : group_tets(mesh, 8)) {
          double v0 = 0.0, v1 = 0.0;
          for (int t : group) {
            v0 += rest_volume[static_cast<std::size_t>(t)];
            v1 += deformed_volume[static_cast<std::size_t>(t)];
          }
          group_sum += std::pow(v1 / v0 - 1.0, 2) * v0;
        }
      }
      int iterations = 0;
      bool converged = true;
      for (const SolveReport& r : result.solves) {
        iterations += r.iterations;
        converged = converged && r.converged;
      }
      std::fprintf(table, "| %s | %g | %+.3f %% | %.2f %% | %.2f %% | %d | %s |\n", name_of(v, false), nu,
                   100.0 * (deformed / rest - 1.0), 100.0 * std::sqrt(tet_sum / rest),
                   100.0 * std::sqrt(group_sum / rest), iterations, converged ? "yes" : "no");
      std::fflush(table);
    }
  }
  return 0;
}

} // namespace

int main(int argc, char** argv) {
  // The tables go to stdout; CHOLMOD's warnings (a singular Hessian, which Newton shifts) to stderr.
  table = fdopen(dup(1), "w");
  dup2(2, 1);
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "cgal" || mode == "cgal-groups") {
    std::vector<int> groups;
    for (int a = 3; a < argc; ++a)
      groups.push_back(std::atoi(argv[a]));
    return unstructured(argc > 2 ? std::atof(argv[2]) : 5.0, groups, mode == "cgal-groups");
  }
  if (mode == "local-global") {
    if (argc < 3) {
      std::fprintf(stderr, "usage: volume_locking local-global NU [cgal SIZE]\n");
      return 2;
    }
    return local_global_row(std::atof(argv[2]),
                            argc > 4 && std::string(argv[3]) == "cgal" ? std::atof(argv[4]) : 0.0,
                            std::string(argv[argc - 1]) == "per-tet");
  }
  if (mode == "head")
    return head(argc > 2 && std::string(argv[2]) != "newton"
                    ? argv[2]
                    : std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/head.yaml",
                std::string(argv[argc - 1]) == "newton", false);
  if (mode == "head-gravity")
    return head(std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/head.yaml",
                std::string(argv[argc - 1]) != "local-global", true);
  return structured(argc > 1 ? std::atoi(argv[1]) : 4);
}
