// seiche: the command line. Thin: parse arguments, load the scene, run or bake it, map errors to
// exit codes (0 ok, 2 bad input, 3 output could not be written, 4 the simulation diverged,
// 5 a stability case of `seiche bench --stability` failed, 130 a bake stopped by Ctrl-C / SIGTERM
// with a checkpoint to resume from).
//
// Test hooks (environment variables, for tests/app_tests.cpp; not for users):
//   SEICHE_TEST_INTERRUPT_AFTER_FRAME=k  a bake raises SIGINT after frame k's files are written,
//                                        exactly as a Ctrl-C at that moment would
//   SEICHE_TEST_FRAME_DELAY_MS=t         a bake sleeps t ms after each frame (so that a test can
//                                        kill it mid-way)
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <cstdint>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include "bench_command.hpp"
#include "seiche/bake.hpp"
#include "seiche/bench.hpp"
#include "seiche/export/scene_exporters.hpp"
#include "seiche/input_fingerprint.hpp"
#include "seiche/kernels/simd_info.hpp"
#include "seiche/memory_estimate.hpp"
#include "seiche/output_files.hpp"
#include "seiche/runner.hpp"
#include "seiche/scene_loader.hpp"

namespace {

constexpr int kExitBadInput = 2;
constexpr int kExitIo = 3;
constexpr int kExitDiverged = 4;
constexpr int kExitInterrupted = 130;  // 128 + SIGINT, what shells report for Ctrl-C

/// CLI11's PositiveNumber says "Value -5 not in range 0.000000 to 1797693...": the largest double
/// in 309 digits. This one says what is wrong in a few words (runs on the text, before conversion).
const CLI::Validator kPositiveNumber(
    [](std::string& text) -> std::string {
      double value = 0.0;
      if (CLI::detail::lexical_cast(text, value) && value > 0.0) return {};
      return fmt::format("must be a number > 0, got {}", text.size() > 40 ? text.substr(0, 40) + "..." : text);
    },
    "POSITIVE");

/// CLI11 answers an unknown first word with "A subcommand is required": name it and the
/// subcommands instead. Returns the message, or nothing when the first argument is an option or
/// a subcommand.
std::optional<std::string> unknown_subcommand(CLI::App& app, int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return std::nullopt;
  const std::string word = argv[1];
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    if (sub->check_name(word)) return std::nullopt;
    names.push_back(sub->get_name());
  }
  return fmt::format("unknown subcommand '{}'; the subcommands are {}", word, fmt::join(names, ", "));
}

/// Bad command-line input that is not a scene error (a frame range, a memory size).
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What the command was doing, for the message of an allocation failure (exit 1).
std::string g_stage = "starting";

// --max-memory and --allow-huge-work (run, bake, bench): the checks of memory_estimate.hpp.
struct ResourceArgs {
  std::string max_memory;  // empty = the machine's available memory only
  bool allow_huge_work = false;

  std::optional<std::uint64_t> max_memory_bytes() const {
    if (max_memory.empty()) return std::nullopt;
    const std::optional<std::uint64_t> bytes = seiche::parse_memory_size(max_memory);
    if (!bytes)
      throw UsageError(fmt::format("--max-memory: expected a size such as 512M, 8G or 1.5GiB, got \"{}\"", max_memory));
    return bytes;
  }
};

void add_resource_options(CLI::App* command, ResourceArgs& args) {
  command->add_option("--max-memory", args.max_memory,
                      "Refuse a scene whose estimated memory is over SIZE (e.g. 8G, 512M); the machine's "
                      "available memory is always a limit");
  command->add_flag("--allow-huge-work", args.allow_huge_work,
                    "Run a scene past the work bound (1e5 solver iterations or 1e11 particle-iterations per frame)");
}

// The stage an allocation failure names from now on: `doing` scene, its particles and its estimate.
void set_simulating_stage(const char* doing, const seiche::SceneDef& scene) {
  const seiche::MemoryEstimate estimate = seiche::estimate_scene_memory(scene);
  g_stage = fmt::format("{} scene {} ({} particles, estimated {})", doing, scene.name, estimate.particles,
                        seiche::format_memory_size(estimate.total()));
}

// Loads the scene (`source` empty: the built-in one) and checks it against the memory and work bounds.
seiche::SceneDef load_checked_scene(const std::string& source, const std::vector<std::string>& overrides,
                                    const ResourceArgs& resources) {
  const std::optional<std::uint64_t> max_memory = resources.max_memory_bytes();
  const std::string name = source.empty() ? "<default scene>" : source;
  g_stage = "loading " + name;
  seiche::SceneDef scene = source.empty() ? seiche::load_scene_text(seiche::default_scene_json(), name, overrides)
                                          : seiche::load_scene_file(source, overrides);
  seiche::check_scene_memory(scene, name, max_memory);
  seiche::check_scene_work(scene, name, resources.allow_huge_work);
  set_simulating_stage("building and simulating", scene);
  return scene;
}

struct RunArgs {
  std::string scene;  // empty = the embedded default scene
  int frames = 0;
  std::string out;
  int threads = 0;
  std::string report;
  std::vector<std::string> overrides;
  ResourceArgs resources;
};

int run_command(const RunArgs& a) {
  const seiche::SceneDef scene = load_checked_scene(a.scene, a.overrides, a.resources);
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

// ---- bake ----------------------------------------------------------------------------------------

struct BakeArgs {
  std::string scene;  // empty = the embedded default scene
  std::string out;
  std::string frames;  // "N" or "A-B"; empty = 1..output.frames
  int threads = 0;
  std::vector<std::string> overrides;
  std::string resume;  // a bake folder
  bool accept_changed_inputs = false;
  ResourceArgs resources;
};

// Ctrl-C and SIGTERM: the first asks the bake to stop after the current frame (with a
// checkpoint); the second stops at once. Files are never torn either way (atomic renames).
std::atomic<bool> g_interrupt{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void on_interrupt(int) {
  if (g_interrupt.exchange(true)) ::_exit(kExitInterrupted);
  static const char note[] =
      "\nseiche: stopping after this frame, with a checkpoint (Ctrl-C again stops at once)\n";
  [[maybe_unused]] const ssize_t n = ::write(2, note, sizeof(note) - 1);
}

void install_interrupt_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  // A file size limit (ulimit -f) then makes write() fail with EFBIG, reported like a full
  // disk (exit 3, the last complete frame kept), instead of killing the process mid-write.
  std::signal(SIGXFSZ, SIG_IGN);
}

int env_int(const char* name) {
  const char* v = std::getenv(name);
  return v ? std::atoi(v) : 0;
}

// "N" (frames 1..N) or "A-B", 1 <= A <= B.
std::pair<int, int> parse_frame_range(const std::string& text) {
  const auto bad = [&] {
    return UsageError(fmt::format(
        "--frames: expected N (frames 1..N) or A-B with 1 <= A <= B (frames count from 1), got \"{}\"", text));
  };
  auto number = [&](std::string_view s) {
    if (s.empty() || s.size() > 9 || s.find_first_not_of("0123456789") != std::string_view::npos) throw bad();
    return std::stoi(std::string(s));
  };
  const auto dash = text.find('-');
  const int first = dash == std::string::npos ? 1 : number(std::string_view(text).substr(0, dash));
  const int last = number(dash == std::string::npos ? std::string_view(text) : std::string_view(text).substr(dash + 1));
  if (!(1 <= first && first <= last)) throw bad();
  return {first, last};
}

std::string read_text(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  if (!in) throw UsageError(fmt::format("{}: cannot be read", file));
  return s.str();
}

int bake_command(const BakeArgs& a) {
  const bool resuming = !a.resume.empty();
  std::filesystem::path dir;
  seiche::SceneDef scene;
  seiche::BakeRecipe recipe;
  if (resuming) {
    dir = a.resume;
    recipe = seiche::read_bake_recipe(dir);
    const std::filesystem::path recipe_file = dir / seiche::kBakeRecipeFile;
    seiche::check_recorded_inputs_present(recipe.inputs, recipe_file);
    const std::optional<std::uint64_t> max_memory = a.resources.max_memory_bytes();
    g_stage = "loading " + recipe_file.string();
    scene = seiche::load_recipe_scene(recipe, recipe_file);
    seiche::check_inputs_unchanged(recipe.inputs, seiche::scene_input_files(scene), recipe_file,
                                   a.accept_changed_inputs, &std::cerr);
    recipe.inputs = seiche::scene_input_files(scene);  // as accepted: the next resume compares with these
    seiche::check_scene_memory(scene, recipe_file.string(), max_memory);
    seiche::check_scene_work(scene, recipe_file.string(), a.resources.allow_huge_work);
    set_simulating_stage("resuming the bake of", scene);
  } else {
    std::optional<std::pair<int, int>> range;
    if (!a.frames.empty()) range = parse_frame_range(a.frames);
    scene = load_checked_scene(a.scene, a.overrides, a.resources);
    if (!range) range = std::pair{1, scene.output.frames};
    dir = a.out.empty() ? std::filesystem::path("out") / scene.name : std::filesystem::path(a.out);
    recipe = seiche::make_bake_recipe(scene.name, a.scene.empty() ? "<default scene>" : a.scene,
                                      a.scene.empty() ? std::string(seiche::default_scene_json()) : read_text(a.scene),
                                      a.overrides, range->first, range->second);
    recipe.scene_dir = scene.base_dir;
    recipe.inputs = seiche::scene_input_files(scene);
  }
  const auto exporters = seiche::scene_exporters(
      scene, resuming ? (dir / seiche::kBakeRecipeFile).string() : recipe.scene_source, resuming, &std::cerr);

  seiche::BakeOptions o;
  o.out_dir = dir;
  o.threads = a.threads;
  o.resume = resuming;
  for (const auto& e : exporters) o.exporters.push_back(e.get());
  o.progress = &std::cerr;
  o.summary = &std::cout;
  o.interrupt = &g_interrupt;
  const int interrupt_after = env_int("SEICHE_TEST_INTERRUPT_AFTER_FRAME");
  const int delay_ms = env_int("SEICHE_TEST_FRAME_DELAY_MS");
  if (interrupt_after > 0 || delay_ms > 0)
    o.after_frame = [=](int frame) {
      if (frame == interrupt_after) std::raise(SIGINT);
      if (delay_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    };
  install_interrupt_handlers();

  const seiche::BakeResult r = seiche::bake_scene(scene, recipe, o);
  switch (r.status) {
    case seiche::BakeResult::Status::AlreadyComplete:
      fmt::print("{}: the bake of {} is already complete (frames {}-{}); nothing to do\n", dir.string(), scene.name,
                 r.first_frame, r.last_frame);
      return 0;
    case seiche::BakeResult::Status::Interrupted:
      std::cerr << fmt::format("seiche: interrupted after frame {} of {}; resume with: {}\n", r.frames_done,
                               r.last_frame, seiche::resume_command(dir));
      return kExitInterrupted;
    case seiche::BakeResult::Status::Complete:
      break;
  }
  return 0;
}

// `seiche --version`: what a benchmark figure or a golden hash depends on besides the version: the
// SIMD the kernels were built for, the compiler and the flags (from CMake, apps/CMakeLists.txt).
std::string version_text() {
  return fmt::format("seiche {}\nsimd: {}\ncompiler: {}\nbuild type: {}\nflags: {}", SEICHE_VERSION,
                     seiche::kernels::simd_description(), SEICHE_COMPILER, SEICHE_BUILD_TYPE,
                     SEICHE_BUILD_FLAGS);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Seiche: a particle engine for fluids (Position Based Fluids, XPBD)", "seiche"};
  app.set_version_flag("--version", version_text,
                       "Print the version, the SIMD width, the compiler and flags, and exit");
  app.require_subcommand(1);

  RunArgs run;
  CLI::App* run_cmd = app.add_subcommand("run", "Simulate a scene and write particle frames");
  run_cmd->add_option("scene", run.scene, "Scene file (JSON); default: the built-in dam break");
  run_cmd->add_option("--frames", run.frames, "Number of frames (default: the scene's output.frames)")
      ->check(kPositiveNumber);
  run_cmd->add_option("--out", run.out, "Output folder (default: out/<scene name>)");
  run_cmd->add_option("--threads", run.threads, "Worker threads (default: all cores)")
      ->check(kPositiveNumber);
  run_cmd->add_option("--report", run.report, "Write a JSON run report to this file");
  run_cmd->add_option("--set", run.overrides,
                      "Override a scene value by its JSON path, e.g. --set solver.iterations=8");
  add_resource_options(run_cmd, run.resources);

  BakeArgs bake;
  CLI::App* bake_cmd = app.add_subcommand(
      "bake", "Simulate a scene and write every output it asks for (.ply, .vtp, .vdb, .obj), with checkpoints");
  bake_cmd->footer(
      "Stop at any time with Ctrl-C (or SIGTERM): the current frame is finished and checkpointed, and\n"
      "`seiche bake --resume DIR` continues bit for bit. bake.json fingerprints the scene's OBJ meshes: a resume\n"
      "refuses one that is missing or changed (exit 2, naming it) unless --accept-changed-inputs is given.\n"
      "Exit codes: 0 done, 2 bad input, 3 output could not be written, 4 the simulation diverged, 130 interrupted.");
  auto* bake_scene_opt = bake_cmd->add_option("scene", bake.scene, "Scene file (JSON); default: the built-in dam break");
  auto* bake_out_opt = bake_cmd->add_option("--out", bake.out, "Output folder (default: out/<scene name>)");
  auto* bake_frames_opt = bake_cmd->add_option(
      "--frames", bake.frames, "N: frames 1..N; A-B: simulate from the start, write frames A..B (default: 1..output.frames)");
  bake_cmd->add_option("--threads", bake.threads, "Worker threads (default: all cores)")->check(kPositiveNumber);
  auto* bake_set_opt = bake_cmd->add_option("--set", bake.overrides,
                                            "Override a scene value by its JSON path, e.g. --set solver.iterations=8");
  bake_cmd->add_option("--resume", bake.resume,
                       "Continue the bake in this folder from its last checkpoint (scene, frames and overrides "
                       "come from DIR/bake.json)")
      ->excludes(bake_scene_opt)
      ->excludes(bake_out_opt)
      ->excludes(bake_frames_opt)
      ->excludes(bake_set_opt);
  bake_cmd->add_flag("--accept-changed-inputs", bake.accept_changed_inputs,
                     "With --resume: continue although an input file of the scene (an OBJ mesh) changed since the "
                     "bake started (the frames after the checkpoint then use the file as it is now)")
      ->needs("--resume");
  add_resource_options(bake_cmd, bake.resources);

  seiche_cli::BenchArgs bench;
  CLI::App* bench_cmd = app.add_subcommand(
      "bench", "Error against run time: sweep settings against a converged reference (CSV and plot), or run "
               "the stability suite");
  bench_cmd->footer(
      "Example: seiche bench scenes/flag.json --sweep substeps=1,2,4,8,16 --sweep iterations=1,2,4,8 --frames 60\n"
      "Writes DIR/bench.csv (one row per setting, then the reference and its check) and DIR/bench.png.\n"
      "--stability runs the stiff and extreme cases instead and writes DIR/stability.csv; exit code 5 if one fails.");
  auto* bench_scene_opt =
      bench_cmd->add_option("scene", bench.scene, "Scene file (JSON); default: the built-in dam break");
  auto* bench_sweep_opt = bench_cmd->add_option(
      "--sweep", bench.sweeps,
      "KEY=V1,V2,...: a scene key and its values (a key without a dot is a solver key); repeat for more keys; "
      "default: substeps=1,2,4,8,16 and iterations=1,2,4,8");
  auto* bench_frames_opt =
      bench_cmd->add_option("--frames", bench.frames, "Frames per run (default: the scene's output.frames)")
          ->check(kPositiveNumber);
  bench_cmd->add_option("--out", bench.out, "Output folder (default: out/bench/<scene name>, out/stability)");
  bench_cmd->add_option("--threads", bench.threads, "Worker threads (default: all cores)")->check(kPositiveNumber);
  auto* bench_set_opt =
      bench_cmd->add_option("--set", bench.overrides, "Override a scene value by its JSON path for every run");
  auto* bench_ref_opt =
      bench_cmd->add_option("--reference", bench.reference,
                            "auto (implicit Euler where the scene allows it, else XPBD), xpbd or implicit")
          ->capture_default_str();
  auto* bench_ref_sub_opt = bench_cmd->add_option("--reference-substeps", bench.reference_substeps,
                                                  "Reference substeps (default: 4x the largest swept, at least 64)")
                                ->check(kPositiveNumber);
  auto* bench_ref_it_opt = bench_cmd->add_option(
      "--reference-iterations", bench.reference_iterations,
      "XPBD reference iterations (default: 2x the largest swept, at least 16)")->check(kPositiveNumber);
  bool no_plot = false;
  CLI::Option* bench_no_plot = bench_cmd->add_flag("--no-plot", no_plot, "Write the CSV only (no matplotlib)");
  auto* bench_stability = bench_cmd->add_flag("--stability", bench.stability, "Run the stability suite instead");
  bench_cmd->add_option("--size", bench.size, "Stability suite size: full or reduced (as in CI)")
      ->capture_default_str()
      ->needs(bench_stability);
  for (CLI::Option* o : {bench_scene_opt, bench_sweep_opt, bench_frames_opt, bench_set_opt, bench_ref_opt, bench_ref_sub_opt,
                  bench_ref_it_opt, bench_no_plot})
    bench_stability->excludes(o);

  if (const auto unknown = unknown_subcommand(app, argc, argv)) {
    std::cerr << *unknown << "\nRun with --help for more information.\n";
    return kExitBadInput;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : kExitBadInput;
  }

  ResourceArgs bench_resources;
  add_resource_options(bench_cmd, bench_resources);

  try {
    if (*run_cmd) return run_command(run);
    if (*bake_cmd) return bake_command(bake);
    if (*bench_cmd) {
      bench.plot = !no_plot;
      bench.max_memory = bench_resources.max_memory_bytes();
      bench.allow_huge_work = bench_resources.allow_huge_work;
      g_stage = "running the bench";
      return seiche_cli::bench_command(bench);
    }
  } catch (const seiche::SceneError& e) {
    std::cerr << "seiche: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const seiche::ResumeError& e) {
    std::cerr << "seiche: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const seiche::BenchError& e) {
    std::cerr << "seiche: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const UsageError& e) {
    std::cerr << "seiche: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const seiche::ExportUnavailableError& e) {
    std::cerr << "seiche: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const seiche::IoError& e) {
    std::cerr << "seiche: error: " << e.what() << "\n";
    return kExitIo;
  } catch (const seiche::SimulationError& e) {
    std::cerr << "\nseiche: error: " << e.what() << "\n";
    return kExitDiverged;
  } catch (const std::bad_alloc&) {
    std::cerr << "\nseiche: error: out of memory while " << g_stage << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "seiche: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
