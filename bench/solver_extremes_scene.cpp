// A scene's deformation against its tight Newton reference (#44), the extremes table's rows on
// real anatomy: builds the scene's anatomy as a run does, solves its deformation with the
// scene's own solver settings, then again with Newton to a relative residual of 1e-7 from rest,
// and prints per body the largest vertex distance between the two over the reference's largest
// displacement, with what the first solve reported (converged, relative residual, the Newton
// step at its result). Exit status 1 when a solve reported converged lies more than 1 % off.
// Usage: solver_extremes_scene SCENE.yaml
//        solver_extremes_scene SCENE.yaml volumes NU [ANATOMY_CACHE [SOLVE [TERM...]]]: every material
//        of Poisson ratio 0.45 or more set to NU (0: as the scene has them), solved (SOLVE: `newton`, the
//        default, to 1e-7; `scene`: the scene's own solver, to 1e-6; `defaults`: the scene's own solver and
//        stop test) with each bulk term TERM (default per_tet, tet_groups and tet_groups_and_tets); prints
//        each body's inverted tets and smallest det F and each organ's volume change (its patch surface's
//        base mesh, moved with the tets; and the sum of the tets of its material region), as
//        docs/deformation.md's volume table. An empty ANATOMY_CACHE builds the anatomy without a cache.

#include "geometry/tet_quality.hpp"
#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

namespace {

using namespace phantasm;

/// The volume a closed triangle mesh encloses (vertices as rows), mm^3.
double enclosed_volume_mm3(const Eigen::MatrixX3d& x, const Eigen::MatrixX3i& faces) {
  double v = 0.0;
  for (Eigen::Index t = 0; t < faces.rows(); ++t)
    v += signed_volume(Eigen::Vector3d::Zero(), x.row(faces(t, 0)).transpose(),
                       x.row(faces(t, 1)).transpose(), x.row(faces(t, 2)).transpose());
  return v;
}

/// Signed volume of tet t of `tets` over the vertices x (rows), mm^3.
double body_tet_volume_mm3(const Eigen::MatrixX3d& x, const Eigen::MatrixX4i& tets, Eigen::Index t) {
  return signed_volume(x.row(tets(t, 0)).transpose(), x.row(tets(t, 1)).transpose(),
                       x.row(tets(t, 2)).transpose(), x.row(tets(t, 3)).transpose());
}

/// How organ_volumes solves: Newton to 1e-7, the scene's solver to 1e-6, or the scene's solver as is.
enum class VolumeSolve { newton, scene, defaults };

/// Each organ's volume change at Poisson ratio nu with each bulk term of `terms`.
int organ_volumes(const Scene& scene, const Phantom& phantom, double nu, VolumeSolve how,
                  const std::vector<VolumeFormulation>& terms, Reporter& quiet) {
  std::printf("| bulk term | organ | volume change (surface) | volume change (its tets) | solve |\n"
              "|---|---|---|---|---|\n");
  for (VolumeFormulation v : terms) {
    DeformationSettings d = scene.deformation;
    d.volume = v;
    if (how == VolumeSolve::scene) {
      d.solver.relative_residual_tolerance = 1e-6;
    } else if (how == VolumeSolve::newton) {
      d.solver.method = SolverMethod::newton;
      d.solver.relative_residual_tolerance = 1e-7;
      d.solver.max_iterations = 200;
    }
    for (MaterialSettings& m : d.materials)
      if (m.poisson_ratio >= 0.45 && nu > 0.0) m.poisson_ratio = nu;
    StageReport report;
    const auto start = std::chrono::steady_clock::now();
    const PhantomDeformation result = deform_phantom(d, scene.organs, phantom, report, quiet);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::string solve;
    for (const SolveReport& r : result.solves) {
      char residual[64];
      std::snprintf(residual, sizeof residual, " (rel. residual %.2g)", r.relative_residual);
      solve +=
          std::to_string(r.iterations) + " it., " + (r.converged ? "converged" : "not converged") + residual;
    }
    char time[32];
    std::snprintf(time, sizeof time, ", %.0f s", seconds);
    for (const DeformedBody& body : result.bodies)
      std::printf("| %s | %s (body): %ld inverted tets, smallest det F %.3f | | | |\n", to_string(v),
                  body.organ.c_str(), body.inverted_tets, body.smallest_det_F);
    // The tets of each organ's material region, over every body.
    std::vector<double> rest(result.organs.size(), 0.0), moved(result.organs.size(), 0.0);
    for (const DeformedBody& body : result.bodies)
      for (Eigen::Index t = 0; t < body.tets.rows(); ++t) {
        const auto organ = static_cast<std::size_t>(body.tet_organ[static_cast<std::size_t>(t)]);
        rest[organ] += body_tet_volume_mm3(body.rest_mm, body.tets, t);
        moved[organ] += body_tet_volume_mm3(body.deformed_mm, body.tets, t);
      }
    for (std::size_t o = 0; o < result.organs.size(); ++o) {
      if (!phantom.organs[o].surface || result.organs[o].moved_by == "fixed") continue;
      const TriangleMesh& base = phantom.organs[o].surface->base_mesh();
      const double before = enclosed_volume_mm3(base.vertices, base.faces);
      const double after = enclosed_volume_mm3(result.organs[o].surface_mm, base.faces);
      char tets[32] = "";
      if (rest[o] > 0.0) std::snprintf(tets, sizeof tets, "%+.2f %%", 100.0 * (moved[o] / rest[o] - 1.0));
      std::printf("| %s | %s | %+.2f %% | %s | %s%s |\n", to_string(v), result.organs[o].organ.c_str(),
                  100.0 * (after / before - 1.0), tets, solve.c_str(), time);
    }
    std::fflush(stdout);
  }
  return 0;
}

} // namespace

/// The solve and the bulk terms of `volumes` (argv[5] and after); false on a name it does not know.
bool volume_arguments(int argc, char** argv, VolumeSolve& how, std::vector<VolumeFormulation>& terms) {
  const std::string solve = argc >= 6 ? argv[5] : "newton";
  if (solve != "newton" && solve != "scene" && solve != "defaults") return false;
  how = solve == "scene"      ? VolumeSolve::scene
        : solve == "defaults" ? VolumeSolve::defaults
                              : VolumeSolve::newton;
  const std::vector<VolumeFormulation> all = {VolumeFormulation::tet, VolumeFormulation::tet_group,
                                              VolumeFormulation::tet_group_and_tet};
  for (int a = 6; a < argc; ++a) {
    const auto named = std::find_if(
        all.begin(), all.end(), [&](VolumeFormulation v) { return std::string(to_string(v)) == argv[a]; });
    if (named == all.end()) return false;
    terms.push_back(*named);
  }
  if (terms.empty()) terms = all;
  return true;
}

int main(int argc, char** argv) {
  SceneLoadResult loaded;
  VolumeSolve how = VolumeSolve::newton;
  std::vector<VolumeFormulation> terms;
  const bool usage = argc == 2 || (argc >= 4 && std::string(argv[2]) == "volumes" &&
                                   volume_arguments(argc, argv, how, terms));
  if (usage) loaded = load_scene(argv[1]);
  if (!usage || !loaded.scene) {
    std::cerr << (usage ? format_diagnostics(loaded.problems)
                        : "usage: solver_extremes_scene SCENE.yaml [volumes NU [ANATOMY_CACHE "
                          "[newton|scene|defaults [BULK_TERM...]]]]\n");
    return 2;
  }
  const Scene& scene = *loaded.scene;
  Reporter quiet = Reporter::silent();
  try {
    const Phantom phantom =
        simulate(scene, quiet, SimulationStage::anatomy, argc >= 5 ? argv[4] : std::string()).phantom;
    if (argc >= 4) return organ_volumes(scene, phantom, std::atof(argv[3]), how, terms, quiet);
    auto solve = [&](const DeformationSettings& settings, StageReport& report) {
      const auto start = std::chrono::steady_clock::now();
      PhantomDeformation d = deform_phantom(settings, scene.organs, phantom, report, quiet);
      std::fprintf(stderr, "%s: %.1f s\n", to_string(settings.solver.method),
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      return d;
    };
    StageReport report, reference_report;
    const PhantomDeformation run = solve(scene.deformation, report);
    DeformationSettings tight = scene.deformation;
    tight.solver.method = SolverMethod::newton;
    tight.solver.relative_residual_tolerance = 1e-7;
    tight.solver.max_iterations = 200;
    const PhantomDeformation reference = solve(tight, reference_report);
    bool converged = true;
    int iterations = 0;
    double relative_residual = 0.0, relative_distance = 0.0;
    for (const SolveReport& s : run.solves) {
      converged = converged && s.converged;
      iterations += s.iterations;
      relative_residual = std::max(relative_residual, s.relative_residual);
      relative_distance = std::max(relative_distance, s.relative_distance());
    }
    double reference_residual = 0.0;
    for (const SolveReport& s : reference.solves)
      reference_residual = std::max(reference_residual, s.relative_residual);
    std::printf(
        "| body | solver | iterations | converged (rel. residual; Newton step / displacement) | "
        "reference rel. residual | largest displacement | field error |\n|---|---|---|---|---|---|---|\n");
    bool silent = false;
    for (std::size_t b = 0; b < run.bodies.size() && b < reference.bodies.size(); ++b) {
      const DeformedBody& x = run.bodies[b];
      const DeformedBody& r = reference.bodies[b];
      const double largest = (r.deformed_mm - r.rest_mm).rowwise().norm().maxCoeff();
      const double distance = (x.deformed_mm - r.deformed_mm).rowwise().norm().maxCoeff();
      const double error = largest > 0.0 ? distance / largest : distance;
      silent = silent || (converged && error > 0.01);
      std::printf("| %s | %s | %d | %s (%.3g; %.3g) | %.3g | %.3g mm | %.3g |\n", x.organ.c_str(),
                  to_string(scene.deformation.solver.method), iterations, converged ? "yes" : "no",
                  relative_residual, relative_distance, reference_residual, largest, error);
    }
    for (const std::string& w : report.warnings)
      std::printf("warning: %s\n", w.c_str());
    for (const std::string& m : report.modelled)
      if (m.find("unstable") != std::string::npos) std::printf("%s\n", m.c_str());
    return silent ? 1 : 0;
  } catch (const std::exception& error) {
    std::cerr << error.what() << '\n';
    return 1;
  }
}
