// `seiche bench`: the sweep of error against run time (seiche/bench.hpp) and the stability suite
// (seiche/stability.hpp), with their files: DIR/bench.csv and DIR/bench.png (drawn by
// benchmarks/plot_bench.py), DIR/stability.csv.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace seiche_cli {

struct BenchArgs {
  std::string scene;                  // empty = the embedded default scene
  std::vector<std::string> sweeps;    // "KEY=V1,V2,..."
  int frames = 0;
  std::string out;
  int threads = 0;
  std::vector<std::string> overrides;
  std::string reference = "auto";     // auto, xpbd, implicit
  int reference_substeps = 0;
  int reference_iterations = 0;
  bool plot = true;
  bool stability = false;
  std::string size = "full";          // stability suite: full or reduced
  std::optional<std::uint64_t> max_memory;  // --max-memory, checked for every scene the bench loads
  bool allow_huge_work = false;       // --allow-huge-work
};

/// Runs the bench; returns the exit code (0; 3 when the plot could not be drawn; 5 when a
/// stability case failed). Throws what the scene loader and the simulation throw.
int bench_command(const BenchArgs& args);

}  // namespace seiche_cli
