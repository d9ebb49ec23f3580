// A scene's deformation against its tight Newton reference (#44), the extremes table's rows on
// real anatomy: builds the scene's anatomy as a run does, solves its deformation with the
// scene's own solver settings, then again with Newton to a relative residual of 1e-7 from rest,
// and prints per body the largest vertex distance between the two over the reference's largest
// displacement, with what the first solve reported (converged, relative residual, the Newton
// step at its result). Exit status 1 when a solve reported converged lies more than 1 % off.
// Usage: solver_extremes_scene SCENE.yaml

#include "pipeline/run_pipeline.hpp"
#include "scene/scene.hpp"
#include "sim/deform_phantom.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>

int main(int argc, char** argv) {
  using namespace phantasm;
  SceneLoadResult loaded;
  if (argc == 2) loaded = load_scene(argv[1]);
  if (argc != 2 || !loaded.scene) {
    std::cerr << (argc == 2 ? format_diagnostics(loaded.problems)
                            : "usage: solver_extremes_scene SCENE.yaml\n");
    return 2;
  }
  const Scene& scene = *loaded.scene;
  Reporter quiet = Reporter::silent();
  try {
    const Phantom phantom = simulate(scene, quiet, SimulationStage::anatomy).phantom;
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
