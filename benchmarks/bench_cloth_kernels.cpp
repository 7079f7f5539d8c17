// The cloth solve's kernels on a regular n x n vertex sheet (spacing 1 cm, triangles with
// alternating diagonals; stretch constraints on the unique triangle edges, hinges on the
// interior edges; 100 x 100: 29 601 edges and 29 205 hinges), perturbed so that every
// constraint is active. One XPBD iteration of: stretch (distance constraints), dihedral bending,
// isometric bending, and stretch + isometric bending together (the cloth solve's inner loop).
// Reports the real time per iteration (ms), items_per_second (constraints solved per second),
// s_per_constraint (seconds in CSV/JSON, shown with an SI prefix: "3.1ns") and, as the label, a
// hash of the positions after 10 warm-up iterations (the same with any thread count).
// The sheet of each size is built once (1024 x 1024: a few seconds) and every benchmark run
// starts from a copy of it.
// Args: n (vertices per side: 100, 256, 512, 1024, i.e. 10k, 65k, 262k and 1M vertices),
// threads (1, 2, 4, ... and std::thread::hardware_concurrency()).
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <thread>
#include <vector>

#include "seiche/kernels/dihedral_bending.hpp"
#include "seiche/kernels/distance_constraint.hpp"
#include "seiche/kernels/isometric_bending.hpp"

using namespace seiche;

namespace {

constexpr float kSpacing = 0.01f;     // m
constexpr float kDt = 1.0f / 600.0f;  // s: 60 fps, 10 substeps

struct Cloth {
  std::vector<float> x, y, z, px, py, pz, vx, vy, vz, w;
  kernels::DistanceConstraints stretch;
  kernels::Hinges dihedral;
  kernels::IsometricBending isometric;

  kernels::ParticleView view() {
    return {x.size(),  x.data(),  y.data(),  z.data(),  px.data(), py.data(),
            pz.data(), vx.data(), vy.data(), vz.data(), w.data(),  nullptr};
  }
};

Cloth make_cloth(int n) {
  Cloth c;
  const std::size_t count = std::size_t(n) * n;
  for (int r = 0; r < n; ++r)
    for (int col = 0; col < n; ++col)
      c.x.push_back(col * kSpacing), c.y.push_back(0.0f), c.z.push_back(r * kSpacing);
  c.w.assign(count, 1.0f);
  c.vx.assign(count, 0.0f), c.vy = c.vx, c.vz = c.vx;

  // Triangles with alternating diagonals; edges and hinges from them (hinges.hpp orientation).
  auto id = [n](int r, int col) { return std::uint32_t(r * n + col); };
  std::vector<std::array<std::uint32_t, 3>> tris;
  for (int r = 0; r + 1 < n; ++r)
    for (int col = 0; col + 1 < n; ++col) {
      const std::uint32_t v00 = id(r, col), v01 = id(r, col + 1), v10 = id(r + 1, col),
                          v11 = id(r + 1, col + 1);
      if ((r + col) % 2 == 0) {
        tris.push_back({v00, v10, v11}), tris.push_back({v00, v11, v01});
      } else {
        tris.push_back({v00, v10, v01}), tris.push_back({v01, v10, v11});
      }
    }
  // Triangle edge e = 3 t + k runs from t[k] to t[k + 1]. An edge's first occurrence (in that
  // order) makes a stretch constraint, its second one a hinge with the first's wing: the
  // half-edges sorted by (undirected edge, e) give both, without a map (1M vertices: 6M edges).
  std::vector<std::pair<std::uint64_t, std::uint32_t>> half(3 * tris.size());
  for (std::uint32_t e = 0; e < half.size(); ++e) {
    const auto [lo, hi] = std::minmax(tris[e / 3][e % 3], tris[e / 3][(e + 1) % 3]);
    half[e] = {std::uint64_t(lo) << 32 | hi, e};
  }
  std::sort(half.begin(), half.end());
  constexpr std::uint32_t kFirst = ~std::uint32_t(0);
  std::vector<std::uint32_t> first(half.size(), kFirst);  // per second occurrence: the first
  for (std::size_t k = 0; k + 1 < half.size(); ++k)
    if (half[k].first == half[k + 1].first) first[half[k + 1].second] = half[k].second;
  auto vertex = [&tris](std::uint32_t e, int offset) { return tris[e / 3][(e + offset) % 3]; };
  std::vector<std::uint32_t> ei, ej, hinges;
  for (std::uint32_t e = 0; e < half.size(); ++e) {
    if (first[e] == kFirst) {
      ei.push_back(vertex(e, 0)), ej.push_back(vertex(e, 1));
    } else {
      const std::uint32_t f = first[e];
      hinges.insert(hinges.end(), {vertex(f, 0), vertex(f, 1), vertex(f, 2), vertex(e, 2)});
    }
  }
  std::vector<float> rest(ei.size()), stretch_compliance(ei.size(), 1e-8f);
  for (std::size_t k = 0; k < ei.size(); ++k)
    rest[k] = std::hypot(c.x[ei[k]] - c.x[ej[k]], c.z[ei[k]] - c.z[ej[k]]);
  const std::vector<float> bend_compliance(hinges.size() / 4, 10.0f);
  c.px = c.x, c.py = c.y, c.pz = c.z;
  const kernels::ParticleView rest_view = c.view();
  kernels::color_distance_constraints(ei, ej, rest, stretch_compliance, count, c.stretch);
  kernels::build_dihedral_bending(hinges, bend_compliance, rest_view, c.dihedral);
  kernels::build_isometric_bending(hinges, bend_compliance, rest_view, c.isometric);

  // Perturb the predicted positions (a third of the spacing): every constraint is violated.
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> u(-0.3f * kSpacing, 0.3f * kSpacing);
  for (std::size_t i = 0; i < count; ++i) c.px[i] += u(rng), c.py[i] += u(rng), c.pz[i] += u(rng);
  return c;
}

std::uint64_t hash_positions(const Cloth& c) {  // FNV-1a over the bits of px, py, pz
  std::uint64_t h = 1469598103934665603ull;
  for (const auto* column : {&c.px, &c.py, &c.pz})
    for (float v : *column) {
      std::uint32_t bits;
      std::memcpy(&bits, &v, 4);
      h = (h ^ bits) * 1099511628211ull;
    }
  return h;
}

enum Pass { kStretch = 1, kDihedral = 2, kIsometric = 4 };

// The cloth of size n, built on first use and kept until another size is asked for (a run calls
// a benchmark function several times).
const Cloth& cached_cloth(int n) {
  static std::unique_ptr<Cloth> cloth;
  static int built = 0;
  if (built != n) cloth.reset(), cloth = std::make_unique<Cloth>(make_cloth(n)), built = n;
  return *cloth;
}

template <int passes>
void BM_Cloth(benchmark::State& state) {
  const int n = int(state.range(0));
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(1));
  Cloth c = cached_cloth(n);
  const kernels::ParticleView p = c.view();
  auto iteration = [&] {
    if (passes & kStretch) kernels::solve_distance_constraints(p, c.stretch, kDt);
    if (passes & kDihedral) kernels::solve_dihedral_bending(p, c.dihedral, kDt);
    if (passes & kIsometric) kernels::solve_isometric_bending(p, c.isometric, kDt);
  };
  for (int warm = 0; warm < 10; ++warm) iteration();
  char label[32];
  std::snprintf(label, sizeof label, "hash %016llx",
                static_cast<unsigned long long>(hash_positions(c)));
  for (auto _ : state) {
    iteration();
    benchmark::ClobberMemory();
  }
  double constraints = 0.0;
  if (passes & kStretch) constraints += double(c.stretch.size());
  if (passes & kDihedral) constraints += double(c.dihedral.size());
  if (passes & kIsometric) constraints += double(c.isometric.size());
  double colors = 0.0;
  if (passes & kStretch) colors += double(c.stretch.color_start.size() - 1);
  if (passes & kDihedral) colors += double(c.dihedral.colors());
  if (passes & kIsometric) colors += double(c.isometric.hinges.colors());
  state.counters["constraints"] = constraints;
  state.counters["colors"] = colors;
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(constraints));
  state.counters["s_per_constraint"] = benchmark::Counter(
      constraints, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.SetLabel(label);
}

void sizes(benchmark::internal::Benchmark* b) {
  const int all = int(std::max(1u, std::thread::hardware_concurrency()));
  for (int n : {100, 256, 512, 1024}) {
    for (int threads = 1; threads < all; threads *= 2) b->Args({n, threads});
    b->Args({n, all});
  }
  b->ArgNames({"n", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
  // With --benchmark_repetitions: the fastest repetition too (the least disturbed on a shared
  // machine), next to the mean and median.
  b->ComputeStatistics(
      "min", [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); });
}

}  // namespace

BENCHMARK_TEMPLATE(BM_Cloth, kStretch)->Name("Stretch")->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Cloth, kDihedral)->Name("DihedralBending")->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Cloth, kIsometric)->Name("IsometricBending")->Apply(sizes);
BENCHMARK_TEMPLATE(BM_Cloth, kStretch | kIsometric)->Name("StretchIsometric")->Apply(sizes);

BENCHMARK_MAIN();
