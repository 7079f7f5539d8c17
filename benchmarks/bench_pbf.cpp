// One Position Based Fluids iteration (density/lambda pass + correction pass) over a cube of
// n^3 fluid particles on a jittered lattice (spacing s = 0.05, h = 2 s, about 30 neighbors),
// as in the neighbor benchmark. Reports ms per iteration and particle-iterations per second.
// Args: n (cube edge), threads (1, 2, 4, ... and std::thread::hardware_concurrency()).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>
#include <thread>
#include <vector>

#include <tbb/global_control.h>

#include "seiche/kernels/pbf_density.hpp"
#include "lattice_block.hpp"
#include "seiche/neighbor/cell_grid.hpp"
#include "seiche/neighbor/neighbor_list.hpp"

using namespace seiche;

namespace {

struct Block {
  std::vector<float> x, y, z;
  std::vector<kernels::Float4> packed;
  neighbor::NeighborList list;
  kernels::PbfParams prm;
};

Block make_block(int n) {
  const float s = 0.05f, h = 2.0f * s;
  Block b;
  std::mt19937 rng(42);
  bench::append_jittered_lattice(n, s, rng, b.x, b.y, b.z);
  const std::size_t count = b.x.size();
  const neighbor::CellGrid grid = bench::sort_by_cell(n * s, h, b.x, b.y, b.z);
  neighbor::build_neighbor_list(grid, b.x.data(), b.y.data(), b.z.data(), count, h, b.list);
  b.packed.resize(count);
  for (std::size_t k = 0; k < count; ++k) b.packed[k] = {b.x[k], b.y[k], b.z[k], 0.0f};
  b.prm.h = h;
  b.prm.mass = float(1000.0 / kernels::lattice_kernel_sum(s, h));
  b.prm.epsilon = float(0.01 * kernels::lattice_lambda_denominator(s, h));
  b.prm.lambda_scale = float(1.0 / kernels::lattice_lambda_denominator(s, h));
  b.prm.tensile_k = 0.1f;
  return b;
}

void BM_PbfIteration(benchmark::State& state) {
  const int n = int(state.range(0));
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(1));
  static Block block;  // built once per size
  static int built = 0;
  if (built != n) block = make_block(n), built = n;
  const std::size_t count = block.x.size();
  std::vector<float> density(count), lambda(count);
  std::vector<float> px = block.x, py = block.y, pz = block.z;
  const kernels::NeighborSpan nbr{block.list.offsets.data(), block.list.indices.data()};
  for (auto _ : state) {
    kernels::pbf_density_lambda(block.packed.data(), nbr, count, block.prm, density.data(), lambda.data());
    for (std::size_t i = 0; i < count; ++i) block.packed[i].w = lambda[i];
    kernels::pbf_apply_correction(block.packed.data(), nbr, count, block.prm, px.data(), py.data(), pz.data());
    benchmark::ClobberMemory();
  }
  state.counters["particles"] = double(count);
  state.counters["neighbors_per_particle"] = double(block.list.indices.size()) / double(count);
  state.counters["particle_iterations_per_s"] =
      benchmark::Counter(double(count), benchmark::Counter::kIsIterationInvariantRate);
}

void sizes(benchmark::internal::Benchmark* b) {
  const int all = int(std::max(1u, std::thread::hardware_concurrency()));
  for (int n : {40, 64, 100}) {
    for (int threads = 1; threads < all; threads *= 2) b->Args({n, threads});
    b->Args({n, all});
  }
  b->ArgNames({"n", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

}  // namespace

BENCHMARK(BM_PbfIteration)->Apply(sizes);

BENCHMARK_MAIN();
