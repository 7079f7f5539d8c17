#include "seiche/runner.hpp"

#include <chrono>
#include <optional>

#include <fmt/format.h>
#include <fmt/ostream.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <unistd.h>

#include "run_report.hpp"
#include "seiche/output_files.hpp"
#include "seiche/simulation.hpp"

namespace seiche {

namespace {

using Clock = std::chrono::steady_clock;

// One progress line: rewritten in place on a terminal, throttled to about one a second in logs.
class Progress {
 public:
  Progress(std::ostream* out, int frames, std::size_t particles)
      : out_(out), frames_(frames), particles_(particles), tty_(out && ::isatty(2)) {}

  void frame_done(int frame, double elapsed, double frame_ms) {
    if (!out_) return;
    const bool last = frame == frames_;
    if (!tty_ && !last && frame != 1 && elapsed - last_print_ < 1.0) return;
    last_print_ = elapsed;
    const double eta = elapsed / frame * (frames_ - frame);
    const std::string line = fmt::format("frame {}/{}  {} particles  {:.1f} ms/frame  ETA {:.1f} s",
                                         frame, frames_, particles_, frame_ms, eta);
    if (tty_)
      *out_ << "\r" << line << "\x1b[K" << (last ? "\n" : "") << std::flush;
    else
      *out_ << line << "\n" << std::flush;
  }

 private:
  std::ostream* out_;
  int frames_;
  std::size_t particles_;
  bool tty_;
  double last_print_ = -1.0;
};

void print_summary(std::ostream& out, const SceneDef& scene, const RunResult& r,
                   const std::vector<std::string>& pipeline) {
  fmt::print(out, "\n{}: {} frames, {} particles, {} substeps x {} iterations, {} threads, {:.2f} s\n",
             scene.name, r.frames, r.particles, scene.solver.substeps, scene.solver.iterations,
             r.threads, r.wall_seconds);
  fmt::print(out, "pipeline: {}\n\n", fmt::join(pipeline, " -> "));
  double total = 0.0;
  for (const auto& e : r.timer.entries()) total += e.total_seconds;
  fmt::print(out, "{:<16} {:>10} {:>10} {:>7}\n", "pass", "total ms", "ms/frame", "share");
  for (const auto& e : r.timer.entries())
    fmt::print(out, "{:<16} {:>10.1f} {:>10.2f} {:>6.1f}%\n", e.name, e.total_seconds * 1e3,
               e.total_seconds * 1e3 / std::max(r.frames, 1),
               total > 0 ? 100.0 * e.total_seconds / total : 0.0);
  if (r.metrics.empty()) return;
  // Error of each active constraint family: mean over frames of the frame mean, and the
  // largest frame max.
  auto family = [&](const char* name, auto get) {
    double mean = 0.0, max = 0.0;
    for (const FrameMetrics& m : r.metrics) {
      const auto e = get(m);
      mean += e.mean;
      max = std::max(max, e.max);
    }
    fmt::print(out, "{:<16} {:>9.3f}% {:>9.3f}%\n", name, 100.0 * mean / r.metrics.size(), 100.0 * max);
  };
  fmt::print(out, "\n{:<16} {:>10} {:>10}\n", "error", "mean", "max");
  if (r.metrics.front().fluid) family("fluid density", [](const FrameMetrics& m) { return *m.fluid; });
  if (r.metrics.front().distance)
    family("distance", [](const FrameMetrics& m) { return *m.distance; });
  const FrameMetrics& last = r.metrics.back();
  fmt::print(out, "\nlast frame: kinetic energy {:.4g} J, max speed {:.3g} m/s\n", last.kinetic_energy,
             last.max_speed);
}

}  // namespace

RunResult run_scene(const SceneDef& scene, const RunOptions& options) {
  RunResult result;
  result.threads = options.threads > 0 ? options.threads : tbb::info::default_concurrency();
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              std::size_t(result.threads));
  const int frames = options.frames > 0 ? options.frames : scene.output.frames;

  Simulation sim(scene);  // before any folder is made: a scene that cannot be built writes nothing
  if (!options.out_dir.empty()) prepare_output_directory(options.out_dir);
  if (!options.report.empty() && options.report.has_parent_path())
    prepare_output_directory(options.report.parent_path());

  result.particles = sim.particles().size();
  const std::vector<std::string> pipeline = sim.pipeline();
  RunReport report(scene, result.particles, frames, result.threads, pipeline);
  Progress progress(options.progress, frames, result.particles);
  auto write_report = [&] {
    if (!options.report.empty()) write_file_atomically(options.report, report.dump());
  };

  const auto start = Clock::now();
  try {
    for (int f = 1; f <= frames; ++f) {
      const auto frame_start = Clock::now();
      FrameMetrics m = sim.step_frame();
      report.add_frame(m, sim.timer());
      result.metrics.push_back(m);
      if (m.non_finite > 0)
        throw SimulationError(fmt::format(
            "frame {}: {} non-finite values in positions or velocities; the simulation diverged "
            "(try more substeps or iterations)",
            f, m.non_finite));
      if (!options.out_dir.empty())
        write_file_atomically(options.out_dir / frame_file_name("particles", f, "ply"),
                              encode_particles_ply(sim.particles()));
      result.frames = f;
      const std::chrono::duration<double> elapsed = Clock::now() - start;
      const std::chrono::duration<double> frame_time = Clock::now() - frame_start;
      progress.frame_done(f, elapsed.count(), frame_time.count() * 1e3);
    }
  } catch (const std::exception& e) {
    report.set_error(e.what());
    try {
      write_report();
    } catch (const IoError&) {
      // the first error is the one to tell
    }
    throw;
  }
  result.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  result.timer = sim.timer();
  write_report();
  if (options.summary) {
    print_summary(*options.summary, scene, result, pipeline);
    if (!options.out_dir.empty())
      fmt::print(*options.summary, "\noutput: {}/particles.0001.ply .. {}\n", options.out_dir.string(),
                 frame_file_name("particles", result.frames, "ply"));
    if (!options.report.empty()) fmt::print(*options.summary, "report: {}\n", options.report.string());
  }
  return result;
}

}  // namespace seiche
