// Cost of one local/global iteration (local step, global step, total) on the twisting bar
// (1421 vertices, 5040 tets) and on a ~10k-vertex / ~43k-tet solid, on 1 and 2 threads; of one
// Newton iteration on the bar, and of a Newton Hessian's factorization on cubes; of the global
// matrix's factorization, simplicial or supernodal, on both.

#include "sim/hessian_factor.hpp"
#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/sparse_cholesky.hpp"
#include "sim/twisting_bar.hpp"

#include <benchmark/benchmark.h>

#include <chrono>

#include <memory>
#include <vector>

namespace {

phantasm::TwistingBarSettings solid(int size) {
  phantasm::TwistingBarSettings settings;
  if (size == 1) { // 13 x 13 x 61 = 10309 vertices, 5 x 12 x 12 x 60 = 43200 tets
    settings.size_mm = {60, 60, 300};
    settings.cells = {12, 12, 60};
  }
  if (size == 2) { // a cube of 22^3 = 10648 vertices, 5 x 21^3 = 46305 tets: as compact as a head's body
    settings.size_mm = {100, 100, 100};
    settings.cells = {21, 21, 21};
  }
  return settings;
}

/// A solve of 20 iterations from the step's start (the inertial target, ends placed), as a
/// frame of the bar animation runs them: the first iterations move far, so the rotations'
/// warm start helps less than near convergence. range(0): 0 = bar, 1 = 10k solid; range(1):
/// threads; range(2): Anderson history (0 = plain local/global). Per iteration: local step
/// (projections and right-hand side, including Anderson's bookkeeping), global step (the
/// triangular solves) and their sum; the solver's factorization is made outside the timing.
void local_global_iteration(benchmark::State& state) {
  const phantasm::TwistingBarStep step = phantasm::twisting_bar_step(solid(static_cast<int>(state.range(0))));
  constexpr int iterations = 20;
  phantasm::StopCriteria fixed;
  fixed.max_iterations = iterations;
  fixed.relative_energy_decrease = -1.0; // never stop early
  fixed.position_change_m = -1.0;
  double local = 0.0, global = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    auto solver = std::make_unique<phantasm::LocalGlobalSolver>(
        step.model, step.inertia.weight, static_cast<int>(state.range(1)), static_cast<int>(state.range(2)));
    Eigen::MatrixX3d p = step.start_m;
    state.ResumeTiming();
    const phantasm::SolveReport report = solver->solve(p, step.inertia.target_m, fixed);
    local += report.local_seconds;
    global += report.global_seconds;
  }
  const auto n = static_cast<double>(state.iterations()) * iterations;
  state.counters["local_ms"] = 1e3 * local / n;
  state.counters["global_ms"] = 1e3 * global / n;
  state.counters["iteration_ms"] = 1e3 * (local + global) / n;
  state.counters["vertices"] = static_cast<double>(step.model.vertex_count());
  state.counters["tets"] = static_cast<double>(step.model.tets.size());
}
BENCHMARK(local_global_iteration)
    ->ArgsProduct({{0, 1}, {1, 2}, {0, 5}})
    ->ArgNames({"solid", "threads", "anderson"})
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

/// The factorization of a matrix with the global matrix's pattern (one row per vertex, an entry
/// per tet edge: the tet graph's Laplacian plus the identity) and one three-column solve with
/// the factor. range(0): 0 = bar, 1 = 10k solid, 2 = 10k cube; range(1): 0 simplicial, 1 supernodal (then
/// converted to the simplicial LDL^T the solves read). The time is the factorization's; the
/// solve's is a counter.
void sparse_cholesky_factor(benchmark::State& state) {
  const phantasm::TwistingBarStep step = phantasm::twisting_bar_step(solid(static_cast<int>(state.range(0))));
  const auto n = static_cast<int>(step.model.vertex_count());
  std::vector<Eigen::Triplet<double>> entries;
  for (int v = 0; v < n; ++v)
    entries.emplace_back(v, v, 1.0);
  for (const phantasm::TetElement& tet : step.model.tets) {
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        const int i = tet.vertices[static_cast<std::size_t>(a)],
                  j = tet.vertices[static_cast<std::size_t>(b)];
        if (i >= j) entries.emplace_back(i, j, i == j ? 1.0 : -1.0 / 6.0);
      }
    }
  }
  Eigen::SparseMatrix<double> lower(n, n);
  lower.setFromTriplets(entries.begin(), entries.end());
  const auto kind = state.range(1) == 0 ? phantasm::SparseCholesky::Factorization::simplicial
                                        : phantasm::SparseCholesky::Factorization::supernodal;
  const Eigen::MatrixX3d b = Eigen::MatrixX3d::Ones(n, 3);
  Eigen::MatrixX3d x;
  double solve_seconds = 0.0;
  for (auto _ : state) {
    phantasm::SparseCholesky factor(lower, kind);
    state.PauseTiming();
    const auto start = std::chrono::steady_clock::now();
    factor.solve(b, x);
    solve_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.ResumeTiming();
  }
  state.counters["rows"] = n;
  state.counters["solve_ms"] = 1e3 * solve_seconds / static_cast<double>(state.iterations());
}
BENCHMARK(sparse_cholesky_factor)
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->ArgNames({"solid", "supernodal"})
    ->Unit(benchmark::kMillisecond);

/// The Newton check's factorization (sim/hessian_factor.hpp): the LL^T of a matrix with the
/// projected Hessian's pattern (a 3 x 3 block per pair of vertices that share a tet: the tet
/// graph's Laplacian plus the identity, times an SPD 3 x 3 block) on a cube of range(0)^3 cells
/// (5 tets each), simplicial (range(1) = 0) or supernodal (1). The symbolic analysis is made by
/// the first factorization and kept, as Newton keeps it while the pattern stays; the time is the
/// numeric factorization's. Where the two cross sets HessianFactor::k_supernodal_rows.
void newton_hessian_factor(benchmark::State& state) {
  phantasm::TwistingBarSettings settings;
  const auto cells = static_cast<int>(state.range(0));
  settings.size_mm = {100, 100, 100};
  settings.cells = {cells, cells, cells};
  const phantasm::TwistingBarStep step = phantasm::twisting_bar_step(settings);
  const auto n = static_cast<int>(step.model.vertex_count());
  Eigen::Matrix3d block;
  block << 1.0, 0.2, 0.1, 0.2, 1.0, 0.2, 0.1, 0.2, 1.0;
  std::vector<Eigen::Triplet<double>> entries;
  const auto add = [&](int i, int j, double weight) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        if (3 * i + r >= 3 * j + c) entries.emplace_back(3 * i + r, 3 * j + c, weight * block(r, c));
  };
  for (int v = 0; v < n; ++v)
    add(v, v, 1.0);
  for (const phantasm::TetElement& tet : step.model.tets)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const int i = tet.vertices[static_cast<std::size_t>(a)],
                  j = tet.vertices[static_cast<std::size_t>(b)];
        if (i >= j) add(i, j, i == j ? 1.0 : -1.0 / 6.0);
      }
  Eigen::SparseMatrix<double> lower(3 * n, 3 * n);
  lower.setFromTriplets(entries.begin(), entries.end());
  phantasm::HessianFactor factor(lower.rows(), state.range(1) == 0
                                                   ? phantasm::HessianFactor::Factorization::simplicial
                                                   : phantasm::HessianFactor::Factorization::supernodal);
  if (!factor.factorize(lower, 0.0)) state.SkipWithError("not positive definite"); // the analysis
  for (auto _ : state) {
    if (!factor.factorize(lower, 0.0)) state.SkipWithError("not positive definite");
  }
  state.counters["rows"] = 3 * n;
}
BENCHMARK(newton_hessian_factor)
    ->ArgsProduct({{8, 10, 12, 14, 16}, {0, 1}})
    ->ArgNames({"cells", "supernodal"})
    ->Unit(benchmark::kMillisecond);

} // namespace

BENCHMARK_MAIN();
