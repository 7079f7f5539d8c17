// seiche: the command line. Thin: parse arguments, load the scene, run it, map errors to exit
// codes (0 ok, 2 bad input, 3 output could not be written, 4 the simulation diverged).
#include <iostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "seiche/output_files.hpp"
#include "seiche/runner.hpp"
#include "seiche/scene_loader.hpp"

namespace {

constexpr int kExitBadInput = 2;
constexpr int kExitIo = 3;
constexpr int kExitDiverged = 4;

struct RunArgs {
  std::string scene;  // empty = the embedded default scene
  int frames = 0;
  std::string out;
  int threads = 0;
  std::string report;
  std::vector<std::string> overrides;
};

int run_command(const RunArgs& a) {
  const seiche::SceneDef scene =
      a.scene.empty() ? seiche::load_scene_text(seiche::default_scene_json(), "<default scene>", a.overrides)
                      : seiche::load_scene_file(a.scene, a.overrides);
  seiche::RunOptions o;
  o.frames = a.frames;
  o.threads = a.threads;
  o.out_dir = a.out.empty() ? std::filesystem::path("out") / scene.name : std::filesystem::path(a.out);
  o.report = a.report;
  o.progress = &std::cerr;
  o.summary = &std::cout;
  seiche::run_scene(scene, o);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Seiche: a particle engine for fluids (Position Based Fluids, XPBD)", "seiche"};
  app.set_version_flag("--version", std::string("seiche ") + SEICHE_VERSION);
  app.require_subcommand(1);

  RunArgs run;
  CLI::App* run_cmd = app.add_subcommand("run", "Simulate a scene and write particle frames");
  run_cmd->add_option("scene", run.scene, "Scene file (JSON); default: the built-in dam break");
  run_cmd->add_option("--frames", run.frames, "Number of frames (default: the scene's output.frames)")
      ->check(CLI::PositiveNumber);
  run_cmd->add_option("--out", run.out, "Output folder (default: out/<scene name>)");
  run_cmd->add_option("--threads", run.threads, "Worker threads (default: all cores)")
      ->check(CLI::PositiveNumber);
  run_cmd->add_option("--report", run.report, "Write a JSON run report to this file");
  run_cmd->add_option("--set", run.overrides,
                      "Override a scene value by its JSON path, e.g. --set solver.iterations=8");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : kExitBadInput;
  }

  try {
    if (*run_cmd) return run_command(run);
  } catch (const seiche::SceneError& e) {
    std::cerr << "seiche: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const seiche::IoError& e) {
    std::cerr << "seiche: error: " << e.what() << "\n";
    return kExitIo;
  } catch (const seiche::SimulationError& e) {
    std::cerr << "\nseiche: error: " << e.what() << "\n";
    return kExitDiverged;
  } catch (const std::exception& e) {
    std::cerr << "seiche: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
