// The bench's sweep (bench.hpp): the reference first (its trajectory is kept), then its check
// and every swept setting, each compared with it frame by frame.
#include "seiche/bench.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <set>

#include <fmt/format.h>
#include <fmt/ostream.h>

#include "families/cloth/cloth_solver.hpp"
#include "families/distance/distance_solver.hpp"
#include "implicit_reference.hpp"
#include "run/progress.hpp"
#include "seiche/kernels/simd_info.hpp"
#include "seiche/simulation.hpp"
#include "seiche/thread_count.hpp"
#include "trajectory.hpp"

namespace seiche {

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

std::string trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string_view::npos) return {};
  return std::string(s.substr(b, s.find_last_not_of(" \t") - b + 1));
}

std::vector<SweepAxis> default_sweep() {
  return {{"solver.substeps", {"1", "2", "4", "8", "16"}}, {"solver.iterations", {"1", "2", "4", "8"}}};
}

// Every combination of the axes' values, the first axis outermost.
std::vector<std::vector<std::string>> combinations(const std::vector<SweepAxis>& axes) {
  std::vector<std::vector<std::string>> out{{}};
  for (const SweepAxis& axis : axes) {
    std::vector<std::vector<std::string>> next;
    for (const auto& prefix : out)
      for (const std::string& v : axis.values) {
        next.push_back(prefix);
        next.back().push_back(v);
      }
    out = std::move(next);
  }
  return out;
}

std::vector<std::string> overrides_of(const std::vector<SweepAxis>& axes, const std::vector<std::string>& values) {
  std::vector<std::string> o;
  for (std::size_t a = 0; a < axes.size(); ++a) o.push_back(axes[a].key + "=" + values[a]);
  return o;
}

// The length errors are measured in: the fluid's spacing, else the mean cloth edge, else the
// mean rest length of the distance constraints.
std::pair<double, std::string> spacing_of(const Simulation& sim) {
  if (!sim.scene().fluids.empty()) return {sim.scene().fluids[0].spacing, "the fluid spacing"};
  auto mean_rest = [](const kernels::DistanceConstraints& c) {
    double sum = 0.0;
    for (float l : c.rest_length) sum += l;
    return c.size() ? sum / double(c.size()) : 0.0;
  };
  if (const double edge = sim.cloth() ? mean_rest(sim.cloth()->stretch()) : 0.0; edge > 0.0)
    return {edge, "the mean cloth edge"};
  if (const double link = sim.distance() ? mean_rest(sim.distance()->constraints()) : 0.0; link > 0.0)
    return {link, "the mean rest length of the distance constraints"};
  return {1.0, "1 m (the scene has no fluid, cloth or distance constraint)"};
}

// One XPBD run of `frames` frames: its time, its constraint errors and, with a reference, its
// position error; with `record`, its trajectory.
BenchRun run_xpbd(const SceneDef& scene, int frames, double spacing, const Trajectory* reference,
                  Trajectory* record, std::ostream* progress_out, std::string_view label) {
  Simulation sim(scene);
  Progress progress(progress_out, frames);
  BenchRun run;
  run.substeps = scene.solver.substeps;
  run.iterations = scene.solver.iterations;
  std::optional<TrajectoryDifference> difference;
  if (reference) difference.emplace(*reference);
  std::vector<FrameMetrics> metrics;
  double seconds = 0.0;
  for (int f = 0; f < frames; ++f) {
    const auto start = Clock::now();
    const FrameMetrics m = sim.step_frame();
    seconds += std::chrono::duration<double>(Clock::now() - start).count();
    if (m.non_finite > 0) {
      run.diverged = true;
      break;
    }
    metrics.push_back(m);
    run.frames = f + 1;
    if (difference) difference->add_frame(std::size_t(f), sim.particles());
    if (record) record->add_frame(sim.particles());
    progress.frame_done(f + 1, seconds, f + 1, label);
  }
  progress.end_line();
  run.ms_per_frame = seconds * 1e3 / double(run.frames + (run.diverged ? 1 : 0));
  run.constraint_errors = summarize_errors(metrics);
  double iterations_run = 0.0;
  for (const FrameMetrics& m : metrics) iterations_run += m.iterations_mean;
  run.iterations_run = metrics.empty() ? 0.0 : iterations_run / double(metrics.size());
  if (difference) {
    run.error_rms = run.diverged ? kInfinity : difference->rms() / spacing;
    run.error_max = run.diverged ? kInfinity : difference->max() / spacing;
  }
  return run;
}

// A setting's time, what the Pareto front compares. The measured run (run_xpbd) was the warm-up:
// caches, page faults and the thread pool have settled. Then the setting runs again from its
// initial state, its frames unmeasured (FrameMeasure::Skip: the simulation alone), at least
// kMinTimedRuns times and until kMinTimedSeconds are timed in all (at most kMaxTimedRuns); the
// median is its time, its quartiles the spread (and the fastest and slowest run are kept). A
// diverged run keeps its one time.
constexpr int kMinTimedRuns = 3;
constexpr double kMinTimedSeconds = 0.5;
constexpr int kMaxTimedRuns = 100;

// The q-quantile of sorted values, linear between neighbours (q = 0.5: the median).
double quantile(const std::vector<double>& sorted, double q) {
  const double at = q * double(sorted.size() - 1);
  const std::size_t below = std::size_t(at);
  const std::size_t above = std::min(below + 1, sorted.size() - 1);
  return sorted[below] + (at - double(below)) * (sorted[above] - sorted[below]);
}

void one_timed_run(BenchRun& run) {
  run.ms_per_frame_min = run.ms_per_frame_max = run.ms_per_frame;
  run.ms_per_frame_q1 = run.ms_per_frame_q3 = run.ms_per_frame;
  run.timed_runs = 1;
}

void time_setting(const SceneDef& scene, BenchRun& run) {
  one_timed_run(run);
  if (run.diverged || run.frames == 0) return;
  std::vector<double> ms;
  double total = 0.0;
  while (int(ms.size()) < kMinTimedRuns || (total < kMinTimedSeconds && int(ms.size()) < kMaxTimedRuns)) {
    Simulation sim(scene);
    const auto start = Clock::now();
    for (int f = 0; f < run.frames; ++f) sim.step_frame(FrameMeasure::Skip);
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    total += seconds;
    ms.push_back(seconds * 1e3 / run.frames);
  }
  std::sort(ms.begin(), ms.end());
  run.ms_per_frame = quantile(ms, 0.5);
  run.ms_per_frame_q1 = quantile(ms, 0.25);
  run.ms_per_frame_q3 = quantile(ms, 0.75);
  run.ms_per_frame_min = ms.front();
  run.ms_per_frame_max = ms.back();
  run.timed_runs = int(ms.size());
}

// The implicit-Euler reference: `substeps` steps per frame, each solved by Newton's method.
// Counts the steps whose Newton solve stopped before its tolerance in `unconverged`.
BenchRun run_implicit(const SceneDef& scene, int substeps, int frames, double spacing,
                      const Trajectory* reference, Trajectory* record, int& unconverged, std::ostream* progress_out,
                      std::string_view label) {
  Progress progress(progress_out, frames);
  const Simulation sim(scene);  // for its initial state and constraints, exactly as XPBD starts
  ImplicitReferenceSystem built = implicit_reference_system(sim);
  const std::vector<std::int32_t> id_of_index = std::move(built.id_of_index);
  ImplicitEulerStepper stepper(std::move(built.system));
  Trajectory frame_positions(sim.particles().size());
  std::optional<TrajectoryDifference> difference;
  if (reference) difference.emplace(*reference);
  BenchRun run;
  run.substeps = substeps;
  const double h = scene.solver.frame_dt / substeps;
  const Vec3 &lo = scene.domain.min, &hi = scene.domain.max;
  double seconds = 0.0;
  for (int f = 0; f < frames; ++f) {
    const auto start = Clock::now();
    for (int s = 0; s < substeps; ++s)
      if (!stepper.step(h).converged) ++unconverged;
    seconds += std::chrono::duration<double>(Clock::now() - start).count();
    const std::vector<double>& x = stepper.positions();
    for (std::size_t k = 0; k < x.size(); ++k)
      if (x[k] < lo[k % 3] || x[k] > hi[k % 3])
        throw BenchError(fmt::format(
            "the implicit-Euler reference has no walls, and a particle left the domain in frame {}: "
            "use --reference xpbd (or a larger domain)",
            f + 1));
    frame_positions.add_frame(x, id_of_index);
    if (difference) difference->add_frame(std::size_t(f), frame_positions);
    run.frames = f + 1;
    progress.frame_done(f + 1, seconds, f + 1, label);
  }
  progress.end_line();
  if (record) *record = std::move(frame_positions);
  run.ms_per_frame = run.frames ? seconds * 1e3 / run.frames : 0.0;
  if (difference) run.error_rms = difference->rms() / spacing, run.error_max = difference->max() / spacing;
  return run;
}

// A sweep run is on the Pareto front when no other run is at least as fast and at least as
// accurate, and strictly better in one of the two.
void mark_pareto_front(std::vector<BenchRun>& runs) {
  for (BenchRun& r : runs) {
    if (r.role != BenchRun::Role::Sweep || r.diverged) continue;
    r.pareto = std::none_of(runs.begin(), runs.end(), [&](const BenchRun& o) {
      return &o != &r && o.role == BenchRun::Role::Sweep && !o.diverged && o.ms_per_frame <= r.ms_per_frame &&
             o.error_rms <= r.error_rms && (o.ms_per_frame < r.ms_per_frame || o.error_rms < r.error_rms);
    });
  }
}

std::string describe(const BenchRun& r) {
  return r.iterations > 0 ? fmt::format("{} substeps x {} iterations", r.substeps, r.iterations)
                          : fmt::format("{} steps per frame", r.substeps);
}

std::string format_value(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : "inf"; }

// The sweep as loaded: every combination's values and scene, and the base scene.
struct LoadedSweep {
  std::vector<SweepAxis> axes;
  std::vector<std::vector<std::string>> settings;
  std::vector<SceneDef> scenes;
  SceneDef base;
  int max_substeps = 1, max_iterations = 1;
  bool implicit_reference = false;
};

LoadedSweep load_sweep(const SceneFactory& load_scene, const BenchOptions& options) {
  LoadedSweep l;
  l.axes = options.sweep.empty() ? default_sweep() : options.sweep;
  std::set<std::string> keys;
  for (const SweepAxis& a : l.axes)
    if (!keys.insert(a.key).second) throw BenchError(fmt::format("--sweep: {} is swept twice", a.key));
  l.settings = combinations(l.axes);
  for (const auto& values : l.settings) {
    l.scenes.push_back(load_scene(overrides_of(l.axes, values)));
    l.max_substeps = std::max(l.max_substeps, l.scenes.back().solver.substeps);
    l.max_iterations = std::max(l.max_iterations, l.scenes.back().solver.iterations);
  }
  l.base = load_scene({});
  const std::string unsupported = implicit_reference_unsupported(l.base);
  if (options.reference == ReferenceKind::ImplicitEuler && !unsupported.empty())
    throw BenchError(fmt::format("--reference implicit: {}", unsupported));
  l.implicit_reference = options.reference == ReferenceKind::ImplicitEuler ||
                         (options.reference == ReferenceKind::Auto && unsupported.empty());
  return l;
}

}  // namespace

ReferenceKind parse_reference_kind(std::string_view name) {
  if (name == "auto") return ReferenceKind::Auto;
  if (name == "xpbd") return ReferenceKind::Xpbd;
  if (name == "implicit") return ReferenceKind::ImplicitEuler;
  throw BenchError(fmt::format("--reference: expected auto, xpbd or implicit, got \"{}\"", name));
}

SweepAxis parse_sweep(std::string_view text) {
  const auto eq = text.find('=');
  if (eq == std::string_view::npos)
    throw BenchError(fmt::format("--sweep {}: expected KEY=V1,V2,... (e.g. substeps=1,2,4)", text));
  SweepAxis axis;
  axis.key = trim(text.substr(0, eq));
  if (axis.key.empty()) throw BenchError(fmt::format("--sweep {}: the key is empty", text));
  if (axis.key.find('.') == std::string::npos && axis.key.find('[') == std::string::npos)
    axis.key = "solver." + axis.key;
  std::string_view rest = text.substr(eq + 1);
  while (true) {
    const auto comma = rest.find(',');
    axis.values.push_back(trim(rest.substr(0, comma)));
    if (axis.values.back().empty()) throw BenchError(fmt::format("--sweep {}: an empty value", text));
    if (comma == std::string_view::npos) break;
    rest = rest.substr(comma + 1);
  }
  return axis;
}

const BenchRun& BenchResult::reference_run() const {
  for (const BenchRun& r : runs)
    if (r.role == BenchRun::Role::Reference) return r;
  throw std::logic_error("BenchResult: no reference run");
}

const BenchRun& BenchResult::reference_check() const {
  for (const BenchRun& r : runs)
    if (r.role == BenchRun::Role::ReferenceCheck) return r;
  throw std::logic_error("BenchResult: no reference check");
}

void check_bench(const SceneFactory& load_scene, const BenchOptions& options) { load_sweep(load_scene, options); }

namespace {

// The sweep itself, already on its `threads` threads (run_bench).
BenchResult run_bench_on_threads(const SceneFactory& load_scene, const BenchOptions& options,
                                 int threads) {
  // Every swept scene is loaded (and so checked) before anything runs.
  const LoadedSweep sweep = load_sweep(load_scene, options);
  const std::vector<SweepAxis>& axes = sweep.axes;
  const std::vector<std::vector<std::string>>& settings = sweep.settings;
  const std::vector<SceneDef>& scenes = sweep.scenes;
  const SceneDef& base = sweep.base;
  const int max_substeps = sweep.max_substeps, max_iterations = sweep.max_iterations;
  const bool implicit = sweep.implicit_reference;

  BenchResult result;
  result.scene = base.name;
  for (const SweepAxis& a : axes) result.axes.push_back(a.key);
  result.frames = options.frames > 0 ? options.frames : base.output.frames;
  result.threads = threads;

  const int ref_substeps = options.reference_substeps > 0 ? options.reference_substeps : std::max(64, 4 * max_substeps);
  const int ref_iterations =
      options.reference_iterations > 0 ? options.reference_iterations : std::max(16, 2 * max_iterations);
  auto reference_scene = [&](int substeps) {
    return load_scene({fmt::format("solver.substeps={}", substeps), fmt::format("solver.iterations={}", ref_iterations)});
  };
  {
    const Simulation probe(base);
    result.particles = probe.particles().size();
    std::tie(result.spacing, result.spacing_source) = spacing_of(probe);
  }

  const std::size_t total_runs = settings.size() + 2;
  std::size_t runs_done = 0;
  auto label = [&](std::string_view what) { return fmt::format("run {}/{} ({})", runs_done + 1, total_runs, what); };
  auto report = [&](const BenchRun& r, std::string_view what) {
    ++runs_done;
    if (!options.progress) return;
    fmt::print(*options.progress, "bench: run {}/{} ({}): {:.2f} ms/frame", runs_done, total_runs, what,
               r.ms_per_frame);
    if (r.timed_runs > 1)
      fmt::print(*options.progress, " (median of {}, quartiles {:.2f}-{:.2f})", r.timed_runs, r.ms_per_frame_q1,
                 r.ms_per_frame_q3);
    if (r.diverged) fmt::print(*options.progress, ", diverged after {} frames", r.frames);
    else if (r.role != BenchRun::Role::Reference) fmt::print(*options.progress, ", rms error {:.3g}", r.error_rms);
    fmt::print(*options.progress, "\n");
    options.progress->flush();
  };

  // The reference and its check.
  Trajectory reference(result.particles);
  BenchRun ref, check;
  int unconverged = 0;
  if (implicit) {
    const SceneDef s = reference_scene(ref_substeps);
    const char* ref_what = "reference, implicit Euler";
    ref = run_implicit(s, ref_substeps, result.frames, result.spacing, nullptr, &reference, unconverged,
                       options.progress, label(ref_what));
    ref.role = BenchRun::Role::Reference;
    report(ref, ref_what);
    const char* check_what = "reference check, implicit Euler at twice the steps";
    check = run_implicit(s, 2 * ref_substeps, result.frames, result.spacing, &reference, nullptr, unconverged,
                         options.progress, label(check_what));
    report(check, check_what);
  } else {
    const char* ref_what = "reference, XPBD";
    ref = run_xpbd(reference_scene(ref_substeps), result.frames, result.spacing, nullptr, &reference, options.progress,
                   label(ref_what));
    if (ref.diverged)
      throw std::runtime_error(fmt::format("the XPBD reference ({}) diverged after {} frames: it cannot judge anything",
                                           describe(ref), ref.frames));
    ref.role = BenchRun::Role::Reference;
    report(ref, ref_what);
    const char* check_what = "reference check, XPBD at twice the substeps";
    check = run_xpbd(reference_scene(2 * ref_substeps), result.frames, result.spacing, &reference, nullptr,
                     options.progress, label(check_what));
    report(check, check_what);
  }
  check.role = BenchRun::Role::ReferenceCheck;
  for (BenchRun* r : {&ref, &check}) one_timed_run(*r);  // one run each: their time is not compared
  result.reference =
      implicit ? fmt::format("implicit Euler, {} steps per frame, each solved by Newton's method to 1e-12 m{}",
                             ref_substeps,
                             unconverged ? fmt::format(" ({} steps stopped short of that)", unconverged) : "")
               : fmt::format("XPBD, {} substeps x {} iterations", ref_substeps, ref_iterations);

  for (std::size_t k = 0; k < settings.size(); ++k) {
    const std::string what = fmt::format("{}", fmt::join(overrides_of(axes, settings[k]), ", "));
    BenchRun run = run_xpbd(scenes[k], result.frames, result.spacing, &reference, nullptr, options.progress, label(what));
    time_setting(scenes[k], run);
    run.values = settings[k];
    report(run, what);
    result.runs.push_back(std::move(run));
  }
  result.runs.push_back(std::move(ref));
  result.runs.push_back(std::move(check));
  mark_pareto_front(result.runs);
  return result;
}

}  // namespace

BenchResult run_bench(const SceneFactory& load_scene, const BenchOptions& options) {
  const int threads = resolve_thread_count(options.threads);
  return run_with_threads(threads,
                          [&] { return run_bench_on_threads(load_scene, options, threads); });
}

namespace {

// The error rows any run of the sweep measured (a run that diverged may have none), in order.
RunErrors rows_of_any_run(const BenchResult& result) {
  RunErrors rows;
  for (const BenchRun& r : result.runs)
    for (const ErrorRow& e : r.constraint_errors)
      if (!find_error(rows, e.key)) rows.push_back(e);
  return rows;
}

}  // namespace

std::string bench_csv(const BenchResult& result) {
  const RunErrors rows = rows_of_any_run(result);
  std::string csv = "role";
  for (const std::string& key : result.axes) csv += "," + key;
  csv += ",substeps,iterations,iterations_run,frames,diverged,ms_per_frame,ms_per_frame_q1,ms_per_frame_q3,"
         "ms_per_frame_min,ms_per_frame_max,timed_runs,error_rms,error_max,spacing_m";
  for (const ErrorRow& e : rows) csv += "," + e.key + "_mean," + e.key + "_max";
  csv += ",pareto\n";
  for (const BenchRun& r : result.runs) {
    csv += r.role == BenchRun::Role::Sweep ? "sweep" : r.role == BenchRun::Role::Reference ? "reference" : "reference_check";
    for (std::size_t a = 0; a < result.axes.size(); ++a) csv += "," + (a < r.values.size() ? r.values[a] : "");
    csv += fmt::format(",{},{},{},{},{},{},{},{},{},{},{},{},{},{}", r.substeps, r.iterations,
                       format_value(r.iterations_run), r.frames, r.diverged ? 1 : 0, format_value(r.ms_per_frame),
                       format_value(r.ms_per_frame_q1), format_value(r.ms_per_frame_q3),
                       format_value(r.ms_per_frame_min), format_value(r.ms_per_frame_max), r.timed_runs,
                       format_value(r.error_rms), format_value(r.error_max), format_value(result.spacing));
    for (const ErrorRow& row : rows) {
      const ErrorRow* e = find_error(r.constraint_errors, row.key);
      csv += e ? fmt::format(",{},{}", format_value(e->mean), format_value(e->max)) : std::string(",,");
    }
    csv += fmt::format(",{}\n", r.pareto ? 1 : 0);
  }
  return csv;
}

void print_bench_table(std::ostream& out, const BenchResult& result) {
  const BenchRun& check = result.reference_check();
  fmt::print(out, "\nsimd: {}\n", kernels::simd_description());
  fmt::print(out, "{}: {} frames, {} particles, {} threads\n", result.scene, result.frames, result.particles,
             result.threads);
  fmt::print(out, "error: the particle positions' difference to the reference over every frame, in units of {} ({:.4g} m)\n",
             result.spacing_source, result.spacing);
  fmt::print(out, "reference: {}\n", result.reference);
  fmt::print(out, "reference check ({}): rms error {:.3g}, max {:.3g}\n\n", describe(check), check.error_rms,
             check.error_max);

  // Columns: the swept keys, time, the position error, then every family the runs measured.
  std::vector<std::string> header;
  for (const std::string& key : result.axes) header.push_back(key.substr(key.find_last_of('.') + 1));
  const RunErrors rows = rows_of_any_run(result);
  // Iterations actually run, when a density tolerance added some to any run.
  const bool adaptive = std::any_of(result.runs.begin(), result.runs.end(), [](const BenchRun& r) {
    return r.iterations > 0 && r.iterations_run > r.iterations + 1e-9;
  });
  if (adaptive) header.push_back("iterations run");
  for (const char* h : {"ms/frame", "quartiles", "rms error", "max error"}) header.push_back(h);
  for (const ErrorRow& e : rows) header.push_back(e.label + " mean/max");
  header.push_back("pareto");
  std::vector<std::size_t> width;
  for (const std::string& h : header) width.push_back(std::max<std::size_t>(h.size(), 10));
  auto print_row = [&](const std::vector<std::string>& cells) {
    std::string line;
    for (std::size_t c = 0; c < cells.size(); ++c) line += fmt::format("{:>{}}  ", cells[c], width[c]);
    fmt::print(out, "{}\n", line.substr(0, line.find_last_not_of(' ') + 1));
  };
  print_row(header);
  const BenchRun* best = nullptr;
  for (const BenchRun& r : result.runs) {
    if (r.role != BenchRun::Role::Sweep) continue;
    std::vector<std::string> cells = r.values;
    if (adaptive) cells.push_back(fmt::format("{:.2f}", r.iterations_run));
    cells.push_back(fmt::format("{:.2f}", r.ms_per_frame));
    cells.push_back(r.timed_runs > 1 ? fmt::format("{:.2f}-{:.2f}", r.ms_per_frame_q1, r.ms_per_frame_q3) : "-");
    cells.push_back(r.diverged ? "diverged" : fmt::format("{:.3g}", r.error_rms));
    cells.push_back(r.diverged ? fmt::format("at frame {}", r.frames + 1) : fmt::format("{:.3g}", r.error_max));
    for (const ErrorRow& row : rows) {
      const ErrorRow* e = find_error(r.constraint_errors, row.key);
      const bool angle = row.unit == ErrorUnit::Radians;
      const double scale = angle ? 180.0 / 3.14159265358979323846 : 100.0;
      cells.push_back(e ? fmt::format("{:.3g}/{:.3g}{}", scale * e->mean, scale * e->max, angle ? "deg" : "%") : "-");
    }
    cells.push_back(r.pareto ? "*" : "");
    print_row(cells);
    if (!r.diverged && (!best || r.error_rms < best->error_rms)) best = &r;
  }
  if (best && check.error_rms >= best->error_rms)
    fmt::print(out,
               "\nwarning: the reference's own error ({:.3g}) is not below the smallest error it judges ({:.3g}): "
               "the best settings are not resolved; raise --reference-substeps\n",
               check.error_rms, best->error_rms);
}

}  // namespace seiche
