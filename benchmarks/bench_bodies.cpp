// Many bodies through the whole substep (the issue's "ms per substep for 100 bodies"), at the
// solver's defaults (1/60 s frames of 8 substeps x 2 iterations), dropped on the floor (the
// domain's lower wall, friction 0.5). One benchmark iteration is the whole drop, 60 frames (1 s)
// from the start, the simulation's construction not timed: the bodies fall for 0.1-0.25 s and
// land, the rigid boxes on a corner or an edge (they tumble and are all at rest, flat, by 0.5 s),
// the shape boxes on a face:
// - BM_RigidBodiesOnTheFloor/n/threads: n rigid boxes (0.1 m, 500 kg/m^3, each turned by its own
//   angle about its own axis) on a 10-wide grid 0.2 m apart, from 0.15-0.35 m up, under the
//   contacts with the static world (world_contacts.hpp: 8 corner points per box against the
//   domain's 6 walls; serial, body by body). Without fluid a body is its rigid state only (it
//   is sampled into boundary particles where it meets fluid: the pool's case).
// - BM_ShapeClustersOnTheFloor/n/threads: n rigid shape-matched boxes of 10 x 10 x 10 particles
//   (0.1 m at 0.01 m spacing: 1000 particles, one cluster each; n x 1000 particles) on a 10-wide
//   grid 0.15 m apart, from 0.05-0.3 m up: predict, shape matching and collisions every
//   iteration (TBB-parallel over the clusters and the particles), update.
// - BM_RigidBodiesInAPool/n/threads: the n rigid boxes of the first case (0.1 m, 500 kg/m^3, on a
//   10-wide grid 0.15 m apart, unturned) dropped from 2 cm above a pool 0.1 m deep of fluid at
//   0.01 m spacing, over the first kPoolFrames frames (the impact): each box is sampled into its
//   fluid boundary particles (the lattice points inside it within a kernel radius of its surface,
//   about 800 a box at this spacing: fluid_body/body_boundary.hpp), and bodies and fluid push
//   each other both ways (the density's boundary terms, the impulses on the bodies, the
//   separation out of the solids) on top of the fluid's own passes.
// Timed: step_frame without the frame's metrics (FrameMeasure::Skip), in a task arena of exactly
// `threads` threads (thread_count.hpp). Reported: ms per drop (the benchmark's time, real),
// ms_per_substep (its mean over the drop), bodies and particles (the store's: the pool's fluid) (the same counters in every
// benchmark, as the CSV output wants).
#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <cstddef>
#include <optional>
#include <string>

#include "seiche/scene_loader.hpp"
#include "seiche/simulation.hpp"
#include "seiche/thread_count.hpp"

using namespace seiche;

namespace {

constexpr int kGridWidth = 10;  // bodies per row
constexpr int kDropFrames = 60;  // one drop, from the start
constexpr int kPoolFrames = 6;   // the pool's case: its impact only (its substeps cost 100x more)

// A deterministic spread in [0, 1) for body k (no random source: the same scene every run).
double spread(int k, int salt) { return double((k * 7919 + salt * 104729) % 1000) / 1000.0; }

SceneDef rigid_boxes_scene(int bodies) {
  const int rows = (bodies + kGridWidth - 1) / kGridWidth;
  std::string list;
  for (int k = 0; k < bodies; ++k)
    list += fmt::format(
        R"({}{{"name": "box{}", "size": [0.1, 0.1, 0.1], "density": 500, "position": [{}, {}, {}],
           "axis": [{}, 1, {}], "angle": {}}})",
        k == 0 ? "" : ",", k, 0.2 * (k % kGridWidth) + 0.2, 0.15 + 0.2 * spread(k, 1), 0.2 * (k / kGridWidth) + 0.2,
        spread(k, 2) - 0.5, spread(k, 3) - 0.5, 10.0 + 50.0 * spread(k, 4));
  const std::string text = fmt::format(R"({{
    "domain": {{"min": [0, 0, 0], "max": [{}, 1, {}], "friction": 0.5}},
    "rigid_bodies": [{}]
  }})",
                                       0.2 * kGridWidth + 0.2, 0.2 * rows + 0.2, list);
  return load_scene_text(text, "bench_bodies");
}

SceneDef boxes_in_a_pool_scene(int bodies) {
  const int rows = (bodies + kGridWidth - 1) / kGridWidth;
  std::string list;
  for (int k = 0; k < bodies; ++k)
    list += fmt::format(R"({}{{"name": "box{}", "size": [0.1, 0.1, 0.1], "density": 500, "position": [{}, 0.17, {}]}})",
                        k == 0 ? "" : ",", k, 0.15 * (k % kGridWidth) + 0.1, 0.15 * (k / kGridWidth) + 0.1);
  const double x = 0.15 * kGridWidth + 0.05, z = 0.15 * rows + 0.05;
  const std::string text = fmt::format(R"({{
    "domain": {{"min": [0, 0, 0], "max": [{0}, 0.5, {1}]}},
    "fluids": [{{"box": {{"min": [0, 0, 0], "max": [{0}, 0.1, {1}]}}, "spacing": 0.01}}],
    "rigid_bodies": [{2}]
  }})",
                                       x, z, list);
  return load_scene_text(text, "bench_bodies_in_a_pool");
}

SceneDef shape_boxes_scene(int bodies) {
  const int rows = (bodies + kGridWidth - 1) / kGridWidth;
  std::string list;
  for (int k = 0; k < bodies; ++k) {
    const double x = 0.15 * (k % kGridWidth) + 0.05, z = 0.15 * (k / kGridWidth) + 0.05;
    const double y = 0.05 + 0.25 * spread(k, 1);
    list += fmt::format(R"({}{{"box": {{"min": [{}, {}, {}], "max": [{}, {}, {}]}}, "spacing": 0.01, "density": 500}})",
                        k == 0 ? "" : ",", x, y, z, x + 0.1, y + 0.1, z + 0.1);
  }
  const std::string text = fmt::format(R"({{
    "domain": {{"min": [0, 0, 0], "max": [{}, 1, {}], "friction": 0.5}},
    "shapes": [{}]
  }})",
                                       0.15 * kGridWidth + 0.05, 0.15 * rows + 0.05, list);
  return load_scene_text(text, "bench_shapes");
}

// Per benchmark iteration, builds `scene` (untimed) and steps it kDropFrames, all on `threads`.
// Returns the particle count, which it reports with the bodies and the ms per substep.
std::size_t drop(benchmark::State& state, const SceneDef& scene, int threads, int frames = kDropFrames) {
  std::size_t particles = 0;
  run_with_threads(threads, [&] {
    std::optional<Simulation> sim;
    for (auto _ : state) {
      state.PauseTiming();
      sim.reset();  // the last drop's destruction, untimed too
      sim.emplace(scene);
      particles = sim->particles().size();
      state.ResumeTiming();
      for (int f = 0; f < frames; ++f) sim->step_frame(FrameMeasure::Skip);
    }
  });
  const double substeps = double(state.iterations()) * frames * scene.solver.substeps;
  state.counters["ms_per_substep"] =
      benchmark::Counter(substeps * 1e-3, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["bodies"] = double(scene.rigid_bodies.size() + scene.shapes.size());
  state.counters["particles"] = double(particles);
  return particles;
}

void BM_RigidBodiesOnTheFloor(benchmark::State& state) {
  drop(state, rigid_boxes_scene(int(state.range(0))), int(state.range(1)));
}

void BM_RigidBodiesInAPool(benchmark::State& state) {
  drop(state, boxes_in_a_pool_scene(int(state.range(0))), int(state.range(1)), kPoolFrames);
}

void BM_ShapeClustersOnTheFloor(benchmark::State& state) {
  const SceneDef scene = shape_boxes_scene(int(state.range(0)));
  if (drop(state, scene, int(state.range(1))) != 1000 * scene.shapes.size())
    state.SkipWithError("not 1000 particles a body");
}

}  // namespace

BENCHMARK(BM_RigidBodiesOnTheFloor)
    ->ArgNames({"bodies", "threads"})
    ->Args({100, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_RigidBodiesInAPool)
    ->ArgNames({"bodies", "threads"})
    ->ArgsProduct({{100}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_ShapeClustersOnTheFloor)
    ->ArgNames({"bodies", "threads"})
    ->ArgsProduct({{100}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
