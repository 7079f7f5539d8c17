// Export cost per frame: the bytes of <name>.%04d.vdb and .obj from n^3 fluid particles (a cube
// block at spacing 0.027 m, the dam break's, with +-1 % jitter; or the same particles after a
// splash: every particle thrown 0..8 spacings in a random direction, so sheets, spray and
// droplets replace most of the block) at the default voxel size (half the spacing).
// Parts, measured apart: surface + density (.vdb with both grids, Blosc), points (.vdb with the
// VDB Points grid), mesh (.obj). Args: n (cube edge), threads, splash (0/1). Reports ms per frame,
// the megabytes written and a hash of the bytes (the same for 1 and 2 threads). The aim: under one
// simulated frame (dam break, 50k particles, about 105 ms/frame at 2 threads; about 2 s/frame at 1M
// particles).
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include "seiche/export/vdb_exporter.hpp"

using namespace seiche;

namespace {

constexpr float kSpacing = 0.027f;

FluidParticles make_particles(int n, bool splash) {
  FluidParticles p;
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> jitter(-0.01f * kSpacing, 0.01f * kSpacing),
      unit(0.0f, 1.0f);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  const std::size_t count = std::size_t(n) * n * n;
  p.x.reserve(count), p.y.reserve(count), p.z.reserve(count);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        float x = (i + 0.5f) * kSpacing + jitter(rng), y = (j + 0.5f) * kSpacing + jitter(rng),
              z = (k + 0.5f) * kSpacing + jitter(rng);
        if (splash) {
          const float gx = normal(rng), gy = normal(rng), gz = normal(rng);
          const float length = std::sqrt(gx * gx + gy * gy + gz * gz);
          const float throw_distance = 8.0f * kSpacing * unit(rng) * unit(rng);
          if (length > 1e-6f)
            x += throw_distance * gx / length, y += throw_distance * gy / length,
                z += throw_distance * gz / length;
        }
        p.x.push_back(x), p.y.push_back(y), p.z.push_back(z);
        p.vx.push_back(0.1f * float(i)), p.vy.push_back(-0.2f), p.vz.push_back(0.05f * float(k));
        p.id.push_back(std::int32_t(p.id.size()));
      }
  return p;
}

/// FNV-1a, 32 bits (exact in a benchmark counter's double).
std::uint32_t fnv1a(const std::string& bytes) {
  std::uint32_t h = 2166136261u;
  for (const char c : bytes) h = (h ^ std::uint8_t(c)) * 16777619u;
  return h;
}

enum class Part { SurfaceDensity, Points, Mesh };

void bench_part(benchmark::State& state, Part part) {
  const int n = int(state.range(0));
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              std::size_t(state.range(1)));
  const bool splash = state.range(2) != 0;
  static FluidParticles particles;  // built once per shape
  static std::pair<int, bool> built{0, false};
  if (built != std::pair{n, splash}) particles = make_particles(n, splash), built = {n, splash};

  FluidExportSettings s;
  s.scene_name = "bench";
  s.spacing = kSpacing;
  s.surface = s.density = part == Part::SurfaceDensity;
  s.points = part == Part::Points;
  s.mesh = part == Part::Mesh;
  EncodedFluidFrame frame;
  for (auto _ : state) {
    frame = encode_fluid_frame(particles, s, {1, 0.0});
    benchmark::DoNotOptimize(frame.vdb.data());
  }
  state.counters["particles"] = double(particles.size());
  state.counters["MB"] = double(frame.vdb.size() + frame.obj.size()) / 1e6;
  state.counters["hash"] = double(fnv1a(frame.vdb) ^ fnv1a(frame.obj));
}

void BM_SurfaceDensity(benchmark::State& state) { bench_part(state, Part::SurfaceDensity); }
void BM_Points(benchmark::State& state) { bench_part(state, Part::Points); }
void BM_Mesh(benchmark::State& state) { bench_part(state, Part::Mesh); }

}  // namespace

BENCHMARK(BM_SurfaceDensity)
    ->ArgsProduct({{40, 64, 100}, {1, 2}, {0, 1}})
    ->ArgNames({"n", "threads", "splash"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Points)
    ->ArgsProduct({{40, 64, 100}, {1, 2}, {0}})
    ->ArgNames({"n", "threads", "splash"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Mesh)
    ->ArgsProduct({{40, 64, 100}, {1, 2}, {0, 1}})
    ->ArgNames({"n", "threads", "splash"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
