// Grid rebuild + complete neighbor query, the case CompactNSearch is measured on: a cube of n^3
// particles at spacing s = 0.05 jittered by +-1% of s, radius h = 2s (about 28 neighbors), cells
// of size h over the cube's bounds. One step = make spec + build + apply order to x, y, z +
// neighbor list, repeated as a simulation does (the input is sorted after the first step, which
// runs before timing).
//   BM_rebuild_and_query: static particles (the keys stay sorted: the grid's fast path).
//   BM_rebuild_and_query_moving: particles move by up to 0.1 s per step, back and forth, so a few
//     percent change cell every step (the grid's general path: atomic counting sort).
// Args: cube side, TBB threads (1, 2, 4, ... and std::thread::hardware_concurrency()).
//   BM_small_scenes: the sizes a simulation substep sees, where fixed overheads matter.
//     scene 0: 6750 particles, a 15 x 30 x 15 lattice, s = 0.02, h = 0.04, in the box
//              [0, 0.3] x [0, 1] x [0, 0.3] grown by h.
//     scene 1: 50,653 particles, a 37^3 lattice, s = 0.027, h = 0.054, in a 4 x 3 x 1.5 box grown
//              by h (mostly empty: the fluid fills 1/18 of it).
//   Args: scene, TBB threads; both the static and the moving variant.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <span>
#include <thread>
#include <vector>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "seiche/neighbor/cell_grid.hpp"
#include "seiche/neighbor/neighbor_list.hpp"

namespace {

namespace nb = seiche::neighbor;

constexpr float kSpacing = 0.05f;
constexpr float kRadius = 2 * kSpacing;

struct Cloud {
  std::vector<float> p[3];  // x, y, z
  std::vector<float> v[3];  // per-step displacement (moving case)
  float box_min[3] = {0, 0, 0}, box_max[3];
  float radius = kRadius;
};

// nx x ny x nz lattice at (i + 0.5) s, jittered by +-1% of s; box = the lattice's bounds.
Cloud jittered_lattice(int nx, int ny, int nz, float s) {
  Cloud c;
  std::mt19937 rng(20240611u);
  std::uniform_real_distribution<float> jitter(-0.01f * s, 0.01f * s);
  std::uniform_real_distribution<float> step(-0.1f * s, 0.1f * s);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const int ijk[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
          c.p[a].push_back((float(ijk[a]) + 0.5f) * s + jitter(rng));
          c.v[a].push_back(step(rng));
        }
      }
  const int dims[3] = {nx, ny, nz};
  for (int a = 0; a < 3; ++a) c.box_max[a] = float(dims[a]) * s;
  c.radius = 2 * s;
  return c;
}

Cloud jittered_cube(int side) { return jittered_lattice(side, side, side, kSpacing); }

// The small scenes of BM_small_scenes (see the top of the file).
Cloud small_scene(int scene) {
  const float h = scene == 0 ? 0.04f : 0.054f;
  Cloud c = scene == 0 ? jittered_lattice(15, 30, 15, 0.02f) : jittered_lattice(37, 37, 37, 0.027f);
  const float box[2][3] = {{0.3f, 1.0f, 0.3f}, {4.0f, 3.0f, 1.5f}};
  for (int a = 0; a < 3; ++a) c.box_min[a] = -h, c.box_max[a] = box[scene][a] + h;
  c.radius = h;
  return c;
}

// sorted[k] = unsorted[order[k]] for every column, through one scratch column.
void apply_order(std::span<const std::uint32_t> order, std::vector<float>* cols, int ncols,
                 std::vector<float>& scratch) {
  scratch.resize(order.size());
  for (int c = 0; c < ncols; ++c) {
    const float* src = cols[c].data();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), 1 << 14), [&](const auto& r) {
      for (std::size_t k = r.begin(); k < r.end(); ++k) scratch[k] = src[order[k]];
    });
    cols[c].swap(scratch);
  }
}

struct Search {
  nb::CellGrid grid;
  nb::NeighborList list;
  std::vector<float> scratch;

  void step(Cloud& c, bool moving) {
    const nb::GridSpec spec = nb::make_grid_spec(c.box_min, c.box_max, c.radius);
    const std::size_t n = c.p[0].size();
    grid.build(spec, c.p[0].data(), c.p[1].data(), c.p[2].data(), nullptr, n);
    apply_order(grid.order(), c.p, 3, scratch);
    if (moving) apply_order(grid.order(), c.v, 3, scratch);
    nb::build_neighbor_list(grid, c.p[0].data(), c.p[1].data(), c.p[2].data(), n, c.radius, list);
  }
};

void run(benchmark::State& state, Cloud cloud, bool moving) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              std::size_t(state.range(1)));
  const std::size_t n = cloud.p[0].size();
  Search search;
  search.step(cloud, moving);  // the first step sorts the lattice order into cell order
  float sign = 1;
  for (auto _ : state) {
    if (moving) {
      for (int a = 0; a < 3; ++a) {
        float* p = cloud.p[a].data();
        const float* v = cloud.v[a].data();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 14), [&](const auto& r) {
          for (std::size_t i = r.begin(); i < r.end(); ++i) p[i] += sign * v[i];
        });
      }
      sign = -sign;
    }
    search.step(cloud, moving);
    benchmark::DoNotOptimize(search.list.indices.data());
    benchmark::ClobberMemory();
  }
  state.counters["B_per_particle"] = double(search.grid.bytes() + search.list.bytes()) / double(n);
  state.counters["scratch_B_per_particle"] = double(nb::neighbor_list_scratch_bytes()) / double(n);
  state.counters["neighbors_per_particle"] = double(search.list.indices.size()) / double(n);
  state.counters["particles"] = double(n);
}

void BM_rebuild_and_query(benchmark::State& state) { run(state, jittered_cube(int(state.range(0))), false); }
void BM_rebuild_and_query_moving(benchmark::State& state) { run(state, jittered_cube(int(state.range(0))), true); }
void BM_small_scenes(benchmark::State& state) { run(state, small_scene(int(state.range(0))), false); }
void BM_small_scenes_moving(benchmark::State& state) { run(state, small_scene(int(state.range(0))), true); }

// Grid build alone on a shuffled input: the worst case of the general (atomic) path.
void BM_grid_build_shuffled(benchmark::State& state) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              std::size_t(state.range(1)));
  Cloud c = jittered_cube(int(state.range(0)));
  std::vector<std::uint32_t> perm(c.p[0].size());
  for (std::uint32_t i = 0; i < perm.size(); ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), std::mt19937(7));
  std::vector<float> scratch;
  apply_order(perm, c.p, 3, scratch);
  const nb::GridSpec spec = nb::make_grid_spec(c.box_min, c.box_max, kRadius);
  nb::CellGrid grid;
  for (auto _ : state) {
    grid.build(spec, c.p[0].data(), c.p[1].data(), c.p[2].data(), nullptr, perm.size());
    benchmark::DoNotOptimize(grid.order().data());
  }
}

// 1, 2, 4, ... threads and all of them.
std::vector<int> thread_counts() {
  const int all = int(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<int> counts;
  for (int threads = 1; threads < all; threads *= 2) counts.push_back(threads);
  counts.push_back(all);
  return counts;
}

void sizes(benchmark::internal::Benchmark* b) {
  for (int side : {40, 64, 100})
    for (int threads : thread_counts()) b->Args({side, threads});
  b->ArgNames({"side", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

void scenes(benchmark::internal::Benchmark* b) {
  for (int scene : {0, 1})
    for (int threads : thread_counts()) b->Args({scene, threads});
  b->ArgNames({"scene", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

}  // namespace

BENCHMARK(BM_small_scenes)->Apply(scenes);
BENCHMARK(BM_small_scenes_moving)->Apply(scenes);
BENCHMARK(BM_rebuild_and_query)->Apply(sizes);
BENCHMARK(BM_rebuild_and_query_moving)->Apply(sizes);
BENCHMARK(BM_grid_build_shuffled)->Apply(sizes);

BENCHMARK_MAIN();
