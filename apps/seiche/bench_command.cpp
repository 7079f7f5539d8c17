#include "bench_command.hpp"

#include <cstdlib>
#include <filesystem>
#include <iostream>

#include <fmt/format.h>
#include <fmt/ostream.h>

#include "seiche/bench.hpp"
#include "seiche/output_files.hpp"
#include "seiche/scene_loader.hpp"
#include "seiche/memory_estimate.hpp"
#include "seiche/stability.hpp"

namespace seiche_cli {

namespace {

constexpr int kExitIo = 3;
constexpr int kExitStabilityFailed = 5;

// The plot script: next to the sources this seiche was built from, unless SEICHE_PLOT_SCRIPT
// names another.
std::filesystem::path plot_script() {
  if (const char* s = std::getenv("SEICHE_PLOT_SCRIPT")) return s;
  return SEICHE_PLOT_SCRIPT;
}

// Debian's python3 (which has Debian's python3-matplotlib), even when another python3 comes
// first on the PATH; SEICHE_PYTHON names another.
std::string python() {
  if (const char* p = std::getenv("SEICHE_PYTHON")) return p;
  return std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Draws DIR/bench.png from DIR/bench.csv with matplotlib. Returns false (after saying why) when
// it could not.
bool draw_plot(const std::filesystem::path& csv, const std::filesystem::path& png, const std::string& title,
               const std::string& unit) {
  const std::filesystem::path script = plot_script();
  const std::string command =
      fmt::format("{} {} {} {} --title {} --unit {}", python(), shell_quote(script.string()), shell_quote(csv.string()),
                  shell_quote(png.string()), shell_quote(title), shell_quote(unit));
  if (!std::filesystem::exists(script)) {
    std::cerr << fmt::format("seiche: error: the plot script {} does not exist (set SEICHE_PLOT_SCRIPT); {} is complete\n",
                             script.string(), csv.string());
    return false;
  }
  if (std::system(command.c_str()) != 0) {
    std::cerr << fmt::format("seiche: error: the plot could not be drawn (needs python3 and python3-matplotlib); "
                             "{} is complete; to draw it: {}\n",
                             csv.string(), command);
    return false;
  }
  return true;
}

int stability_command(const BenchArgs& a) {
  if (a.size != "full" && a.size != "reduced")
    throw seiche::BenchError(fmt::format("--size: expected full or reduced, got \"{}\"", a.size));
  const std::filesystem::path dir = a.out.empty() ? std::filesystem::path("out/stability") : std::filesystem::path(a.out);
  seiche::prepare_output_directory(dir);
  const auto cases = seiche::stability_cases(a.size == "full" ? seiche::SuiteSize::Full : seiche::SuiteSize::Reduced);
  std::vector<seiche::StabilityResult> results;
  for (std::size_t k = 0; k < cases.size(); ++k) {
    std::cerr << fmt::format("stability: case {}/{}: {} ({})\n", k + 1, cases.size(), cases[k].name,
                             cases[k].description);
    results.push_back(seiche::run_stability_case(cases[k], a.threads, &std::cerr));
    const seiche::StabilityResult& r = results.back();
    std::cerr << fmt::format("stability: {}{}\n", r.passed ? "PASS" : "FAIL: ", r.failure);
  }
  seiche::write_file_atomically(dir / "stability.csv", seiche::stability_csv(results));
  seiche::print_stability_table(std::cout, results);
  std::cout << fmt::format("results: {}\n", (dir / "stability.csv").string());
  for (const auto& r : results)
    if (!r.passed) return kExitStabilityFailed;
  return 0;
}

}  // namespace

int bench_command(const BenchArgs& a) {
  if (a.stability) return stability_command(a);
  seiche::BenchOptions o;
  for (const std::string& s : a.sweeps) o.sweep.push_back(seiche::parse_sweep(s));
  o.frames = a.frames;
  o.threads = a.threads;
  o.reference = seiche::parse_reference_kind(a.reference);
  o.reference_substeps = a.reference_substeps;
  o.reference_iterations = a.reference_iterations;
  o.progress = &std::cerr;
  const seiche::SceneFactory load = [&](const std::vector<std::string>& bench_overrides) {
    std::vector<std::string> overrides = a.overrides;  // the bench's own come last and win
    overrides.insert(overrides.end(), bench_overrides.begin(), bench_overrides.end());
    seiche::SceneDef scene = a.scene.empty()
                                 ? seiche::load_scene_text(seiche::default_scene_json(), "<default scene>", overrides)
                                 : seiche::load_scene_file(a.scene, overrides);
    const std::string source = a.scene.empty() ? "<default scene>" : a.scene;
    seiche::check_scene_memory(scene, source, a.max_memory);
    seiche::check_scene_work(scene, source, a.allow_huge_work);
    return scene;
  };
  seiche::check_bench(load, o);  // a bad scene or sweep stops here, before any folder is made
  const std::string name = load({}).name;
  const std::filesystem::path dir =
      a.out.empty() ? std::filesystem::path("out/bench") / name : std::filesystem::path(a.out);
  seiche::prepare_output_directory(dir);

  const seiche::BenchResult result = seiche::run_bench(load, o);
  seiche::write_file_atomically(dir / "bench.csv", seiche::bench_csv(result));
  seiche::print_bench_table(std::cout, result);
  std::cout << fmt::format("\nresults: {}\n", (dir / "bench.csv").string());
  if (!a.plot) return 0;
  const std::string title =
      fmt::format("{}: {} frames, {} particles, {} threads; reference: {}", result.scene, result.frames,
                  result.particles, result.threads, result.reference);
  const std::string unit = fmt::format("{}, {:.4g} m", result.spacing_source, result.spacing);
  if (!draw_plot(dir / "bench.csv", dir / "bench.png", title, unit)) return kExitIo;
  std::cout << fmt::format("plot: {}\n", (dir / "bench.png").string());
  return 0;
}

}  // namespace seiche_cli
