// The cloth solve's kernels on a regular n x n vertex sheet (spacing 1 cm, triangles with
// alternating diagonals; stretch constraints on the unique triangle edges, hinges on the
// interior edges; 100 x 100: 29 601 edges and 29 205 hinges), perturbed so that every
// constraint is active. One XPBD iteration of: stretch (distance constraints), dihedral bending,
// isometric bending, and stretch + isometric bending together (the cloth solve's inner loop).
// Reports s_per_constraint (shown with an SI prefix: "3.1n" is 3.1 ns) and, as the label, a
// hash of the positions after 10 warm-up iterations (the same with any thread count).
// Args: n (vertices per side), threads.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
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
  std::vector<std::uint32_t> ei, ej, hinges;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::array<std::uint32_t, 3>> open;
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3], third = t[(k + 2) % 3];
      const auto key = std::minmax(a, b);
      const auto it = open.find(key);
      if (it == open.end()) {
        open[key] = {a, b, third};
        ei.push_back(a), ej.push_back(b);
      } else {
        hinges.insert(hinges.end(), {it->second[0], it->second[1], it->second[2], third});
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

template <int passes>
void BM_Cloth(benchmark::State& state) {
  const int n = int(state.range(0));
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(1));
  Cloth c = make_cloth(n);
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
  state.counters["s_per_constraint"] = benchmark::Counter(
      constraints, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.SetLabel(label);
}

void sizes(benchmark::internal::Benchmark* b) {
  b->ArgsProduct({{100, 256}, {1, 2}})
      ->ArgNames({"n", "threads"})
      ->Unit(benchmark::kMicrosecond)
      ->UseRealTime();
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
