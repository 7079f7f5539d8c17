// Cloth through the whole substep (predict, stretch, bending, contacts, collisions, update):
// a sheet of n x n vertices pinned at two corners, as in Bender's PositionBasedDynamics cloth
// demo (a 10 m sheet, dt 5 ms as 5 substeps of 1 iteration, isometric bending, no colliders but
// the domain; our stretch is XPBD distance on the edges where the demo uses FEM triangles).
// Reports ms per substep and ns per constraint solve (stretch + bending constraints x
// iterations). Args: n, threads, self_collision (0/1).
#include <benchmark/benchmark.h>

#include <string>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include "seiche/scene_loader.hpp"
#include "seiche/simulation.hpp"

using namespace seiche;

namespace {

SceneDef sheet_scene(int n, bool self_collision) {
  const std::string text = fmt::format(R"({{
    "solver": {{ "frame_dt": 0.005, "substeps": 5, "iterations": 1 }},
    "domain": {{ "min": [-20, -20, -20], "max": [20, 20, 20] }},
    "cloths": [ {{ "sheet": {{ "origin": [0, 0, 0], "size": [10, 10], "resolution": [{0}, {0}] }},
                   "bending": "isometric", "stretch_compliance": 0, "bend_compliance": 1e4,
                   "thickness": {1}, "self_collision": {2}, "pins": [0, {3}] }} ] }})",
                                       n, 0.8 * 10.0 / (n - 1), self_collision ? "true" : "false", n - 1);
  return load_scene_text(text, "bench_cloth");
}

void BM_ClothSheetStep(benchmark::State& state) {
  const int n = int(state.range(0));
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(state.range(1)));
  const SceneDef scene = sheet_scene(n, state.range(2) != 0);
  Simulation sim(scene);
  for (int f = 0; f < 20; ++f) sim.step_frame();  // 0.1 s: the sheet is falling and bending
  const auto constraints = [&] {
    std::size_t edges = std::size_t(3 * (n - 1) * (n - 1) + 2 * (n - 1));
    std::size_t hinges = std::size_t(3 * (n - 1) * (n - 1) - 2 * (n - 1));  // interior edges
    return double(edges + hinges);
  }();
  for (auto _ : state) sim.step_frame();
  const double substeps = double(state.iterations()) * scene.solver.substeps;
  state.counters["ms_per_substep"] = benchmark::Counter(substeps * 1e-3, benchmark::Counter::kIsRate |
                                                                            benchmark::Counter::kInvert);
  state.counters["ns_per_constraint"] = benchmark::Counter(
      substeps * constraints * scene.solver.iterations * 1e-9, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["constraint_solves_per_s"] =
      benchmark::Counter(substeps * constraints * scene.solver.iterations, benchmark::Counter::kIsRate);
  state.counters["ns_per_particle_substep"] = benchmark::Counter(
      substeps * double(n) * n * 1e-9, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK(BM_ClothSheetStep)
    ->ArgNames({"n", "threads", "self"})
    ->ArgsProduct({{64, 100, 128, 256}, {1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
