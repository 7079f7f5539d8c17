// Scene loading (load_scene_text: parse, duplicate-key check, read and check every value) on
// scenes generated in memory, to show that the load time is linear in the scene's size:
// - BM_LoadRawParticles/n: n raw particles, each {"x": [..], "v": [..], "mass": ..}, in a 2 m
//   domain (about 60 bytes of JSON per particle);
// - BM_ParseObjectKeys/n: a scene whose "particles[0]" object holds n keys. Only "x" is a known
//   key, so the load fails at the first unknown key after the whole text was parsed and checked
//   for duplicates: the time is the parse's.
// Reported: the time per load, and the input's bytes per second (the benchmark's bytes_per_second).
#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <string>

#include "seiche/scene_loader.hpp"

using namespace seiche;

namespace {

std::string raw_particles_scene(long n) {
  std::string text = R"({"domain": {"min": [-1, -1, -1], "max": [1, 1, 1]}, "particles": [)";
  text.reserve(text.size() + static_cast<std::size_t>(n) * 64);
  for (long k = 0; k < n; ++k) {
    // A deterministic spread of positions in [-0.9, 0.9]^3, written as a scene author would.
    const double x = -0.9 + 1.8 * static_cast<double>((k * 7919) % 1000) / 1000.0;
    const double y = -0.9 + 1.8 * static_cast<double>((k * 104729) % 997) / 997.0;
    const double z = -0.9 + 1.8 * static_cast<double>(k % 991) / 991.0;
    fmt::format_to(std::back_inserter(text), R"({}{{"x": [{:.4f}, {:.4f}, {:.4f}], "v": [0, 0, 0], "mass": 1}})",
                   k == 0 ? "" : ",", x, y, z);
  }
  text += "]}";
  return text;
}

std::string many_keys_scene(long n) {
  std::string text = R"({"particles": [{"x": [0, 0, 0])";
  for (long k = 0; k < n; ++k) fmt::format_to(std::back_inserter(text), R"(, "key{}": {})", k, k);
  text += "}]}";
  return text;
}

void BM_LoadRawParticles(benchmark::State& state) {
  const std::string text = raw_particles_scene(state.range(0));
  for (auto _ : state) {
    const SceneDef scene = load_scene_text(text, "<bench>");
    if (static_cast<long>(scene.particles.size()) != state.range(0)) state.SkipWithError("wrong particle count");
    benchmark::DoNotOptimize(scene.particles.data());
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * text.size()));
}
BENCHMARK(BM_LoadRawParticles)->Arg(40'000)->Arg(160'000)->Arg(2'000'000)->Unit(benchmark::kMillisecond);

void BM_ParseObjectKeys(benchmark::State& state) {
  const std::string text = many_keys_scene(state.range(0));
  for (auto _ : state) {
    bool refused = false;
    try {
      load_scene_text(text, "<bench>");
    } catch (const SceneError& e) {
      refused = e.json_path().starts_with("particles[0].key");  // the first unknown key
    }
    if (!refused) state.SkipWithError("the unknown keys were not refused");
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * text.size()));
}
BENCHMARK(BM_ParseObjectKeys)->Arg(10'000)->Arg(100'000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
