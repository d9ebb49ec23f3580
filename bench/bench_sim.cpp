// Cost of one local/global iteration (local step, global step, total) on the twisting bar
// (1421 vertices, 5040 tets) and on a ~10k-vertex / ~43k-tet solid, on 1 and 2 threads, and
// of one Newton iteration on the bar.

#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/twisting_bar.hpp"

#include <benchmark/benchmark.h>

namespace {

phantasm::TwistingBarSettings solid(int size) {
  phantasm::TwistingBarSettings settings;
  if (size == 1) { // 13 x 13 x 61 = 10309 vertices, 5 x 12 x 12 x 60 = 43200 tets
    settings.size_mm = {60, 60, 300};
    settings.cells = {12, 12, 60};
  }
  return settings;
}

/// range(0): 0 = bar, 1 = 10k solid; range(1): threads.
void local_global_iteration(benchmark::State& state) {
  const phantasm::TwistingBarStep step = phantasm::twisting_bar_step(solid(static_cast<int>(state.range(0))));
  phantasm::LocalGlobalSolver solver(step.model, step.inertia.weight, static_cast<int>(state.range(1)));
  Eigen::MatrixX3d p = step.start_m;
  phantasm::StopCriteria one;
  one.max_iterations = 1;
  one.relative_energy_decrease = 0.0;
  one.position_change_m = 0.0;
  solver.solve(p, step.inertia.target_m, one); // warm the rotations
  double local = 0.0, global = 0.0;
  for (auto _ : state) {
    // Each solve() is one iteration plus the local step of its result: two local steps and one
    // global step; the counters split the time.
    const phantasm::SolveReport report = solver.solve(p, step.inertia.target_m, one);
    local += report.local_seconds;
    global += report.global_seconds;
  }
  const auto n = static_cast<double>(state.iterations());
  state.counters["local_ms"] = 1e3 * local / n / 2.0;
  state.counters["global_ms"] = 1e3 * global / n;
  state.counters["iteration_ms"] = 1e3 * (local / 2.0 + global) / n;
  state.counters["vertices"] = static_cast<double>(step.model.vertex_count());
  state.counters["tets"] = static_cast<double>(step.model.tets.size());
}
BENCHMARK(local_global_iteration)
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->ArgNames({"solid", "threads"})
    ->Unit(benchmark::kMillisecond);

void newton_iteration_bar(benchmark::State& state) {
  const phantasm::TwistingBarStep step = phantasm::twisting_bar_step({});
  phantasm::StopCriteria one;
  one.max_iterations = 1;
  for (auto _ : state) {
    Eigen::MatrixX3d p = step.start_m;
    benchmark::DoNotOptimize(phantasm::newton_solve(step.model, step.inertia, p, one));
  }
}
BENCHMARK(newton_iteration_bar)->Unit(benchmark::kMillisecond);

} // namespace

BENCHMARK_MAIN();
