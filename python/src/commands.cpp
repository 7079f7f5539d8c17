#include "commands.hpp"

#include <atomic>
#include <iostream>
#include <optional>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "errors.hpp"
#include "scene_input.hpp"
#include "seiche/bake.hpp"
#include "seiche/bench.hpp"
#include "seiche/export/scene_exporters.hpp"
#include "seiche/input_fingerprint.hpp"
#include "seiche/output_files.hpp"
#include "seiche/runner.hpp"

namespace py = pybind11;

namespace seiche_py {

namespace {

std::filesystem::path fspath(const py::object& path) {
  return py::module_::import("os").attr("fspath")(path).cast<std::string>();
}

// out, or out/<scene name> as the CLI's default
std::filesystem::path output_dir(const py::object& out, const std::string& default_dir) {
  return out.is_none() ? std::filesystem::path(default_dir) : fspath(out);
}

// seiche run: returns the run report's JSON text.
std::string run(const py::object& scene_arg, const py::object& set, int frames, const py::object& out,
                const py::object& report, int threads, const py::object& max_memory, bool allow_huge_work,
                const py::object& base_dir, bool progress) {
  const seiche::SceneDef scene =
      load_checked_scene(scene_input(scene_arg, base_dir), scene_overrides(set), scene_limits(max_memory, allow_huge_work));
  seiche::RunOptions o;
  o.frames = frames;
  o.threads = threads;
  if (!out.is_none()) o.out_dir = fspath(out);
  if (!report.is_none()) o.report = fspath(report);
  if (progress) o.progress = &std::cerr;
  py::gil_scoped_release release;
  return seiche::run_scene(scene, o).report;
}

// seiche bake (a new bake; resume with the CLI). `first`..`last`: 0 = 1..output.frames.
py::dict bake(const py::object& scene_arg, const py::object& set, const py::object& out, int first, int last,
              int threads, const py::object& max_memory, bool allow_huge_work, const py::object& base_dir,
              bool progress) {
  const SceneInput input = scene_input(scene_arg, base_dir);
  const std::vector<std::string> overrides = scene_overrides(set);
  const seiche::SceneDef scene = load_checked_scene(input, overrides, scene_limits(max_memory, allow_huge_work));
  if (last == 0) first = 1, last = scene.output.frames;
  if (!(1 <= first && first <= last))
    throw_input_error(fmt::format("frames: expected N (frames 1..N) or (A, B) with 1 <= A <= B, got {}..{}", first, last));
  const std::filesystem::path dir = output_dir(out, "out/" + scene.name);
  seiche::BakeRecipe recipe =
      seiche::make_bake_recipe(scene.name, input.source, scene_json_text(input), overrides, first, last);
  recipe.scene_dir = scene.base_dir;
  recipe.inputs = seiche::scene_input_files(scene);
  const auto exporters = seiche::scene_exporters(scene, input.source, false, &std::cerr);

  std::atomic<bool> interrupt{false};
  seiche::BakeOptions o;
  o.out_dir = dir;
  o.threads = threads;
  for (const auto& e : exporters) o.exporters.push_back(e.get());
  if (progress) o.progress = &std::cerr;
  o.interrupt = &interrupt;
  o.after_frame = [&](int) {  // Ctrl-C: finish this frame, checkpoint, stop (as the CLI does)
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) {
      PyErr_Clear();
      interrupt = true;
    }
  };
  seiche::BakeResult r;
  {
    py::gil_scoped_release release;
    r = seiche::bake_scene(scene, recipe, o);
  }
  if (r.status == seiche::BakeResult::Status::Interrupted) {
    PyErr_SetString(PyExc_KeyboardInterrupt,
                    fmt::format("interrupted after frame {} of {}; resume with: {}", r.frames_done, r.last_frame,
                                seiche::resume_command(dir))
                        .c_str());
    throw py::error_already_set();
  }
  py::dict d;
  d["out"] = dir.string();
  d["status"] = r.status == seiche::BakeResult::Status::Complete ? "complete" : "already_complete";
  d["first_frame"] = r.first_frame;
  d["last_frame"] = r.last_frame;
  d["frames_done"] = r.frames_done;
  d["checkpoint_frame"] = r.checkpoint_frame;
  d["bytes_written"] = r.bytes_written;
  d["files_written"] = r.files_written;
  d["simulate_seconds"] = r.simulate_seconds;
  d["export_seconds"] = r.export_seconds;
  return d;
}

// seiche bench SCENE --sweep ...: the result's facts and its CSV (bench.csv's text).
py::dict bench(const py::object& scene_arg, const py::object& set, const std::vector<std::string>& sweeps, int frames,
               const py::object& out, int threads, const std::string& reference, int reference_substeps,
               int reference_iterations, const py::object& max_memory, bool allow_huge_work, const py::object& base_dir,
               bool progress) {
  const SceneInput input = scene_input(scene_arg, base_dir);
  const std::vector<std::string> user_overrides = scene_overrides(set);
  const SceneLimits limits = scene_limits(max_memory, allow_huge_work);
  seiche::BenchOptions o;
  for (const std::string& s : sweeps) o.sweep.push_back(seiche::parse_sweep(s));
  o.frames = frames;
  o.threads = threads;
  o.reference = seiche::parse_reference_kind(reference);
  o.reference_substeps = reference_substeps;
  o.reference_iterations = reference_iterations;
  if (progress) o.progress = &std::cerr;
  const seiche::SceneFactory load = [&](const std::vector<std::string>& bench_overrides) {
    std::vector<std::string> overrides = user_overrides;  // the bench's own come last and win
    overrides.insert(overrides.end(), bench_overrides.begin(), bench_overrides.end());
    return load_checked_scene(input, overrides, limits);
  };
  seiche::check_bench(load, o);
  std::optional<std::filesystem::path> dir;
  if (!out.is_none()) {
    dir = fspath(out);
    seiche::prepare_output_directory(*dir);
  }
  seiche::BenchResult result;
  {
    py::gil_scoped_release release;
    result = seiche::run_bench(load, o);
  }
  const std::string csv = seiche::bench_csv(result);
  if (dir) seiche::write_file_atomically(*dir / "bench.csv", csv);
  py::dict d;
  d["scene"] = result.scene;
  d["axes"] = result.axes;
  d["reference"] = result.reference;
  d["spacing"] = result.spacing;
  d["spacing_source"] = result.spacing_source;
  d["frames"] = result.frames;
  d["threads"] = result.threads;
  d["particles"] = result.particles;
  d["csv"] = csv;
  return d;
}

}  // namespace

void register_commands(py::module_& m) {
  m.def("run", &run, py::arg("scene"), py::arg("set"), py::arg("frames"), py::arg("out"), py::arg("report"),
        py::arg("threads"), py::arg("max_memory"), py::arg("allow_huge_work"), py::arg("base_dir"), py::arg("progress"));
  m.def("bake", &bake, py::arg("scene"), py::arg("set"), py::arg("out"), py::arg("first"), py::arg("last"),
        py::arg("threads"), py::arg("max_memory"), py::arg("allow_huge_work"), py::arg("base_dir"), py::arg("progress"));
  m.def("bench", &bench, py::arg("scene"), py::arg("set"), py::arg("sweep"), py::arg("frames"), py::arg("out"),
        py::arg("threads"), py::arg("reference"), py::arg("reference_substeps"), py::arg("reference_iterations"),
        py::arg("max_memory"), py::arg("allow_huge_work"), py::arg("base_dir"), py::arg("progress"));
}

}  // namespace seiche_py
