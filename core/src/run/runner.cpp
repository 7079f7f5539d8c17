#include "seiche/runner.hpp"

#include <chrono>
#include <optional>

#include <fmt/format.h>
#include <fmt/ostream.h>

#include "background_writer.hpp"
#include "particle_files.hpp"
#include "progress.hpp"
#include "run_report.hpp"
#include "seiche/frame_exporter.hpp"
#include "seiche/output_files.hpp"
#include "seiche/simulation.hpp"
#include "seiche/thread_count.hpp"

namespace seiche {

namespace {

using Clock = std::chrono::steady_clock;

// The run itself, already on its `threads` threads (run_scene).
RunResult run_on_threads(const SceneDef& scene, const RunOptions& options, int threads);

}  // namespace

void throw_if_diverged(const FrameMetrics& m, int frame) {
  if (m.non_finite > 0)
    throw SimulationError(fmt::format(
        "frame {}: {} non-finite values in positions or velocities; the simulation diverged "
        "(try more substeps or iterations)",
        frame, m.non_finite));
}

RunResult run_scene(const SceneDef& scene, const RunOptions& options) {
  const int threads = resolve_thread_count(options.threads);
  return run_with_threads(threads, [&] { return run_on_threads(scene, options, threads); });
}

namespace {

RunResult run_on_threads(const SceneDef& scene, const RunOptions& options, int threads) {
  RunResult result;
  result.threads = threads;
  const int frames = options.frames > 0 ? options.frames : scene.output.frames;

  Simulation sim(scene);  // before any folder is made: a scene that cannot be built writes nothing
  const std::vector<std::unique_ptr<FrameExporter>> exporters = family_exporters(scene);  // cloth OBJ, bodies
  const ParticleFiles particle_files(scene, 1, /*enabled=*/true);  // a run writes them always
  // Every place the run writes is checked before the first frame: the frame files lie inside the
  // folder, the folder and the report can be written (a report into /proc or onto a folder fails
  // here, not after the simulation).
  if (!options.report.empty()) check_output_file_writable(options.report);
  if (!options.out_dir.empty()) {
    particle_files.check_names_inside(options.out_dir, 1, frames);
    for (const auto& e : exporters) check_frame_files_inside(*e, options.out_dir, 1, frames);
    prepare_output_directory(options.out_dir);
  }

  result.particles = sim.particles().size();
  const std::vector<std::string> pipeline = sim.pipeline();
  RunReport report(scene, result.particles, frames, result.threads, pipeline);
  Progress progress(options.progress, frames);
  auto write_report = [&] {
    if (!options.report.empty()) write_file_atomically(options.report, report.dump());
  };

  // A frame's files (the particle files, then each family exporter's: each cloth's OBJ, the
  // bodies' file) go to disk while the next frame is simulated, in that order; before a frame
  // counts, the previous frame's files are on disk. So a failed write stops the run one frame
  // later at most, before anything of the next frame is recorded or written, and every frame
  // before the failed one is complete.
  std::size_t files_per_frame = particle_files.files_per_frame();
  for (const auto& e : exporters) files_per_frame += e->files(1).size();
  BackgroundWriter frame_files(files_per_frame);
  const auto start = Clock::now();
  std::uint64_t bytes_submitted = 0, bytes_on_disk = 0;
  auto submit = [&](const std::filesystem::path& file, std::string bytes) {
    bytes_submitted += bytes.size();
    frame_files.submit(file, std::move(bytes));
  };
  try {
    for (int f = 1; f <= frames; ++f) {
      const auto frame_start = Clock::now();
      FrameMetrics m = sim.step_frame();
      frame_files.finish();  // frame f - 1's files are on disk, or their failure is thrown here
      bytes_on_disk = bytes_submitted;
      report.add_frame(m, sim.timer());
      result.metrics.push_back(m);
      throw_if_diverged(m, f);
      if (!options.out_dir.empty()) {
        for (FrameExporter::EncodedFile& file : particle_files.encode(sim.particles(), f))
          submit(options.out_dir / file.name, std::move(file.bytes));
        const std::vector<BodyPose> bodies = sim.body_poses();
        for (const auto& e : exporters)
          for (FrameExporter::EncodedFile& file : e->encode_frame({sim.particles(), scene, f, sim.time(), bodies}))
            submit(options.out_dir / file.name, std::move(file.bytes));
      }
      result.frames = f;
      const std::chrono::duration<double> elapsed = Clock::now() - start;
      const std::chrono::duration<double> frame_time = Clock::now() - frame_start;
      progress.frame_done(
          f, elapsed.count(), f, fmt::format("{} particles  {:.1f} ms/frame", result.particles, frame_time.count() * 1e3),
          options.out_dir.empty() ? std::string() : fmt::format("  {} written", format_bytes(bytes_on_disk)));
    }
    frame_files.finish();  // the last frames are on disk (or their failure is thrown) here
  } catch (const std::exception& e) {
    report.set_error(e.what());
    try {
      frame_files.finish();  // the frames before the failure are kept
    } catch (...) {
      // the first error is the one to tell
    }
    try {
      write_report();
    } catch (const IoError&) {
      // the first error is the one to tell
    }
    throw;
  }
  result.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  result.timer = sim.timer();
  result.report = report.dump();
  write_report();
  if (options.summary) {
    print_run_summary(*options.summary, scene, result, pipeline);
    if (!options.out_dir.empty()) {
      fmt::print(*options.summary, "\noutput: {}\n", options.out_dir.string());
      for (const std::string& line : particle_files.describe(1, result.frames))
        fmt::print(*options.summary, "  {}\n", line);
    }
    if (!options.report.empty())
      fmt::print(*options.summary, "report: {}\n", options.report.string());
  }
  return result;
}

}  // namespace

}  // namespace seiche
