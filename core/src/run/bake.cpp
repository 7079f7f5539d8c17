// The bake loop (the idea is written at the top of bake.hpp). One frame:
//   step          sim.step_frame(); stop on a non-finite state (no checkpoint of it)
//   write         the particle files (particle_files.hpp) and every exporter's files, if the
//                 frame is in the range
//   checkpoint    every output.checkpoint_every frames, at the last frame, and on an interrupt
//   progress      frame k/N, simulate and export ms per frame, ETA, bytes written
// A write that fails throws IoError; the message then says which frames and which checkpoint are
// complete on disk and how to resume.
#include "seiche/bake.hpp"

#include <fmt/format.h>
#include <fmt/ostream.h>

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <limits>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "earlier_bake.hpp"
#include "particle_files.hpp"
#include "progress.hpp"
#include "run_report.hpp"
#include "seiche/kernels/simd_info.hpp"
#include "seiche/output_files.hpp"
#include "seiche/scene_loader.hpp"
#include "seiche/simulation.hpp"
#include "seiche/thread_count.hpp"
#include "scene/output_name.hpp"

namespace seiche {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// A frame number of bake.json: a whole number in [1, INT_MAX]. Read as a double and checked
// before the conversion (get<int> truncates 2.5 to 2, and a value past int's range is undefined
// behaviour).
int read_frame_number(const nlohmann::json& doc, const char* key, const fs::path& file) {
  const nlohmann::json& v = doc.at(key);
  constexpr double kMaxFrame = std::numeric_limits<int>::max();
  const double d = v.is_number() ? v.get<double>() : 0.0;
  if (!v.is_number() || !(d >= 1.0 && d <= kMaxFrame) || std::floor(d) != d)
    throw ResumeError(fmt::format("{}: damaged bake description: {} must be a whole number in [1, {}], got {}",
                                  file.string(), key, std::numeric_limits<int>::max(), v.dump()));
  return static_cast<int>(d);
}

}  // namespace

// ---- bake.json -------------------------------------------------------------------------------

namespace {

// One entry of bake.json's "inputs" (encode_bake_recipe writes them).
InputFile read_input_file(const nlohmann::json& entry) {
  InputFile f;
  f.json_path = entry.at("json_path").get<std::string>();
  f.file = entry.at("file").get<std::string>();
  f.bytes = entry.at("bytes").get<std::uint64_t>();
  const std::string hash = entry.at("fnv1a64").get<std::string>();
  const auto [end, ec] = std::from_chars(hash.data(), hash.data() + hash.size(), f.fnv1a64, 16);
  if (ec != std::errc() || end != hash.data() + hash.size() || hash.size() != 16)
    throw nlohmann::json::other_error::create(501, "inputs: fnv1a64 \"" + hash + "\" is not 16 hex digits", &entry);
  return f;
}

}  // namespace

std::uint64_t BakeRecipe::scene_fingerprint() const {
  std::uint64_t h = fnv1a64(scene_name);
  h = fnv1a64(std::string_view("\0", 1), h);
  h = fnv1a64(scene_json, h);
  for (const std::string& o : overrides) {
    h = fnv1a64(std::string_view("\0", 1), h);
    h = fnv1a64(o, h);
  }
  return h;
}

BakeRecipe make_bake_recipe(std::string scene_name, std::string scene_source,
                            std::string scene_json, std::vector<std::string> overrides,
                            int first_frame, int last_frame) {
  BakeRecipe r;
  r.seiche_version = SEICHE_VERSION;
  r.scene_name = std::move(scene_name);
  r.scene_source = std::move(scene_source);
  r.scene_json = std::move(scene_json);
  r.overrides = std::move(overrides);
  r.first_frame = first_frame;
  r.last_frame = last_frame;
  const kernels::SimdInfo simd = kernels::simd_info();
  r.family = simd.family;
  r.fused_multiply_add = simd.fused_multiply_add;
  r.simd = kernels::simd_description();
  return r;
}

std::string encode_bake_recipe(const BakeRecipe& r) {
  nlohmann::ordered_json doc;
  doc["seiche_version"] = r.seiche_version;
  doc["scene_name"] = r.scene_name;
  doc["scene_source"] = r.scene_source;
  doc["scene_dir"] = r.scene_dir;
  doc["first_frame"] = r.first_frame;
  doc["last_frame"] = r.last_frame;
  doc["overrides"] = r.overrides;
  doc["family"] = r.family;
  doc["fused_multiply_add"] = r.fused_multiply_add;
  doc["simd"] = r.simd;
  nlohmann::ordered_json inputs = nlohmann::ordered_json::array();
  for (const InputFile& f : r.inputs)
    inputs.push_back({{"json_path", f.json_path},
                      {"file", f.file},
                      {"bytes", f.bytes},
                      {"fnv1a64", fmt::format("{:016x}", f.fnv1a64)}});
  doc["inputs"] = std::move(inputs);
  doc["scene_fingerprint"] = fmt::format("{:016x}", r.scene_fingerprint());
  doc["scene"] = r.scene_json;
  return doc.dump(2) + "\n";
}

BakeRecipe read_bake_recipe(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw ResumeError(fmt::format(
        "{}: no such folder (seiche bake --resume takes the folder of a bake)", dir.string()));
  const fs::path file = dir / kBakeRecipeFile;
  std::ifstream in(file, std::ios::binary);
  if (!in)
    throw ResumeError(fmt::format("{}: cannot be read ({}); {} is not the folder of a seiche bake",
                                  file.string(), std::strerror(errno), dir.string()));
  std::stringstream text;
  text << in.rdbuf();
  BakeRecipe r;
  try {
    const nlohmann::json doc = nlohmann::json::parse(text.str());
    r.seiche_version = doc.at("seiche_version").get<std::string>();
    r.scene_name = doc.at("scene_name").get<std::string>();
    r.scene_source = doc.at("scene_source").get<std::string>();
    r.scene_json = doc.at("scene").get<std::string>();
    r.scene_dir = doc.value("scene_dir", std::string());
    r.overrides = doc.at("overrides").get<std::vector<std::string>>();
    r.first_frame = read_frame_number(doc, "first_frame", file);
    r.last_frame = read_frame_number(doc, "last_frame", file);
    r.family = doc.at("family").get<std::string>();
    r.fused_multiply_add = doc.at("fused_multiply_add").get<bool>();
    r.simd = doc.at("simd").get<std::string>();
    for (const nlohmann::json& f : doc.value("inputs", nlohmann::json::array()))
      r.inputs.push_back(read_input_file(f));
    if (doc.at("scene_fingerprint").get<std::string>() !=
        fmt::format("{:016x}", r.scene_fingerprint()))
      throw ResumeError(
          fmt::format("{}: the scene fingerprint does not match the scene (was the file edited?)",
                      file.string()));
  } catch (const nlohmann::json::exception& e) {
    throw ResumeError(fmt::format("{}: damaged bake description: {}", file.string(), e.what()));
  }
  if (!(1 <= r.first_frame && r.first_frame <= r.last_frame))
    throw ResumeError(fmt::format("{}: damaged bake description: frame range {}-{}", file.string(),
                                  r.first_frame, r.last_frame));
  if (r.seiche_version != SEICHE_VERSION)
    throw ResumeError(fmt::format(
        "{}: the bake was started by seiche {}, this is seiche {}: a bake continues bit "
        "for bit only with the version that started it",
        file.string(), r.seiche_version, SEICHE_VERSION));
  const kernels::SimdInfo here = kernels::simd_info();
  if (r.family != here.family)
    throw ResumeError(fmt::format(
        "{}: the bake was started on a {} build ({}); this is a {} build ({}): the two compute "
        "different bits, so it would not continue the bake bit for bit. Resume it with a {} build",
        file.string(), r.family, r.simd, here.family, kernels::simd_description(), r.family));
  if (r.fused_multiply_add != here.fused_multiply_add) {
    auto kind = [](bool fused) { return fused ? "fused (rounded once)" : "unfused (rounded twice)"; };
    throw ResumeError(fmt::format(
        "{}: the bake was started by a build whose multiply-adds are {} ({}); this build's are {} "
        "({}), so it would not continue the bake bit for bit. Resume it with a build of the same "
        "kind: -DSEICHE_MARCH=x86-64-v3 or newer for fused, -DSEICHE_MARCH=x86-64 for unfused",
        file.string(), kind(r.fused_multiply_add), r.simd, kind(!r.fused_multiply_add),
        kernels::simd_description()));
  }
  return r;
}

SceneDef load_recipe_scene(const BakeRecipe& recipe, const fs::path& recipe_file) {
  SceneDef scene = load_scene_text(recipe.scene_json, recipe_file.string(), recipe.overrides, recipe.scene_dir);
  // The name the bake was started with (a file's stem, perhaps) names its files: checked as a
  // scene's name is.
  if (const std::string problem = detail::output_name_problem(recipe.scene_name); !problem.empty())
    throw SceneError(recipe_file.string(), "scene_name", problem);
  scene.name = recipe.scene_name;
  return scene;
}

std::string resume_command(const fs::path& dir) {
  std::string d = dir.string();
  if (d.find_first_of(" \t'\"$`\\!*?&;|<>()") != std::string::npos) {
    std::string quoted = "'";
    for (char c : d) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    d = quoted + "'";
  }
  return "seiche bake --resume " + d;
}

// ---- The loop --------------------------------------------------------------------------------

namespace {

// The frame files of one bake: the particle files (if asked) and every exporter's files.
class FrameWriter {
 public:
  FrameWriter(const SceneDef& scene, const fs::path& dir, int first_frame,
              const std::vector<FrameExporter*>& exporters)
      : scene_(scene), dir_(dir), particle_files_(scene, first_frame, scene.output.particles),
        exporters_(exporters) {}

  const ParticleFiles& particle_files() const { return particle_files_; }

  /// Writes frame `frame` of `sim`; returns the bytes written.
  std::uint64_t write(const Simulation& sim, int frame, std::size_t& files) {
    std::uint64_t bytes = 0;
    for (const FrameExporter::EncodedFile& file : particle_files_.encode(sim.particles(), frame)) {
      write_file_atomically(dir_ / file.name, file.bytes);
      bytes += file.bytes.size();
      ++files;
    }
    const std::vector<BodyPose> bodies = sim.body_poses();
    const FrameView view{sim.particles(), scene_, frame, sim.time(), bodies};
    for (FrameExporter* e : exporters_) {
      bytes += e->write_frame(view, dir_);
      files += e->files(frame).size();
    }
    return bytes;
  }

  /// The names of frame `frame`'s files, relative to the folder.
  std::vector<std::string> files(int frame) const {
    std::vector<std::string> names = particle_files_.frame_names(frame);
    for (const FrameExporter* e : exporters_)
      for (const fs::path& f : e->files(frame)) names.push_back(f.string());
    return names;
  }

  /// "particles.0001.ply .. particles.0020.ply", one line per kind of file.
  std::vector<std::string> describe(int first, int last) const {
    std::vector<std::string> lines = particle_files_.describe(first, last);
    auto range = [&](const std::string& a, const std::string& b) {
      return first == last ? a : a + " .. " + b;
    };
    for (const FrameExporter* e : exporters_) {
      const auto a = e->files(first), b = e->files(last);
      for (std::size_t k = 0; k < a.size() && k < b.size(); ++k)
        lines.push_back(range(a[k].string(), b[k].string()) + "  (" + e->name() + ")");
    }
    return lines;
  }

 private:
  const SceneDef& scene_;
  fs::path dir_;
  ParticleFiles particle_files_;
  const std::vector<FrameExporter*>& exporters_;
};

// The ".<name>.tmp" files (write_file_atomically's) that a killed bake left behind.
void remove_temporary_files(const fs::path& dir) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() > 5 && name.front() == '.' && name.ends_with(".tmp") && e.is_regular_file(ec))
      fs::remove(e.path(), ec);
  }
}

void print_bake_summary(std::ostream& out, const BakeResult& r, const fs::path& dir,
                        const FrameWriter& writer) {
  fmt::print(out, "\noutput: {}\n", dir.string());
  const int first_new = std::max(r.first_frame, r.start_frame + 1);
  if (first_new <= r.last_frame)
    for (const std::string& line : writer.describe(first_new, r.last_frame))
      fmt::print(out, "  {}\n", line);
  fmt::print(out, "  {} (frame {}), {}, {}\n", kCheckpointFile, r.checkpoint_frame, kBakeRecipeFile,
             kBakeReportFile);
  const int stepped = std::max(r.frames_done - r.start_frame, 1);
  fmt::print(out,
             "written: {} ({} frame files, checkpoints, {}, {}); simulate {:.1f} ms/frame, export "
             "{:.1f} ms/frame\n",
             format_bytes(r.bytes_written), r.files_written, kBakeRecipeFile, kBakeReportFile,
             1e3 * r.simulate_seconds / stepped, 1e3 * r.export_seconds / stepped);
}

// The bake itself, already on its `threads` threads (bake_scene).
BakeResult bake_on_threads(const SceneDef& scene, const BakeRecipe& recipe,
                           const BakeOptions& options, int threads) {
  const fs::path& dir = options.out_dir;
  if (!(1 <= recipe.first_frame && recipe.first_frame <= recipe.last_frame))
    throw std::invalid_argument(
        fmt::format("bake_scene: bad frame range {}-{}", recipe.first_frame, recipe.last_frame));
  BakeResult result;
  result.first_frame = recipe.first_frame;
  result.last_frame = recipe.last_frame;
  result.run.threads = threads;
  const std::uint64_t fingerprint = recipe.scene_fingerprint();
  const fs::path checkpoint_file = dir / kCheckpointFile;

  // Everything that can be rejected is checked before anything is written: the scene builds,
  // the checkpoint (on a resume) is sound and belongs to this scene, the folder is writable.
  Simulation sim(scene);
  if (options.resume && fs::exists(checkpoint_file)) {
    const Checkpoint cp = read_checkpoint(checkpoint_file);
    restore_checkpoint(sim, cp, fingerprint, checkpoint_file);
    result.start_frame = result.frames_done = result.checkpoint_frame = cp.frame;
    if (cp.frame >= recipe.last_frame) {
      result.status = BakeResult::Status::AlreadyComplete;
      return result;
    }
    if (options.progress)
      fmt::print(*options.progress,
                 "resuming {} from the checkpoint of frame {} (frames {}-{} into {})\n", scene.name,
                 cp.frame, recipe.first_frame, recipe.last_frame, dir.string());
  } else if (options.resume && options.progress) {
    fmt::print(*options.progress, "no checkpoint in {} yet: baking {} from frame 1\n", dir.string(),
               scene.name);
  }
  // Every place the bake writes: the frame files lie inside the folder; the folder, the report
  // and the checkpoint can be written (bake.json is written below, a real write test).
  FrameWriter writer(scene, dir, recipe.first_frame, options.exporters);
  writer.particle_files().check_names_inside(dir, recipe.first_frame, recipe.last_frame);
  for (const FrameExporter* e : options.exporters)
    check_frame_files_inside(*e, dir, recipe.first_frame, recipe.last_frame);
  prepare_output_directory(dir);
  check_output_file_writable(dir / kBakeReportFile);
  check_output_file_writable(checkpoint_file);
  // The particle series lists this bake's frames up to its checkpoint before anything else is
  // written (an earlier or a killed bake's series is replaced; particle_files.hpp).
  if (writer.particle_files().writes_series()) {
    const FrameExporter::EncodedFile series = writer.particle_files().encode_series(result.start_frame);
    write_file_atomically(dir / series.name, series.bytes);
    result.bytes_written += series.bytes.size();
  }
  // A new bake replaces an earlier one in the folder: none of its frames may stay beside ours.
  if (!options.resume)
    remove_earlier_bake_frames(
        dir, recipe.first_frame, recipe.last_frame, [&](int frame) { return writer.files(frame); },
        options.progress);
  const std::string recipe_text = encode_bake_recipe(recipe);
  // A resume rewrites the same bytes: a real write test (access() says yes to root everywhere).
  write_file_atomically(dir / kBakeRecipeFile, recipe_text);
  result.bytes_written += recipe_text.size();
  if (options.resume) remove_temporary_files(dir);
  if (!options.resume) {
    std::error_code ec;
    fs::remove(checkpoint_file, ec);  // an earlier bake's state must not pass for this one's
    if (ec)
      throw IoError(fmt::format("{}: cannot remove the old checkpoint: {}",
                                checkpoint_file.string(), ec.message()));
  }

  RunResult& run = result.run;
  run.particles = sim.particles().size();
  const std::vector<std::string> pipeline = sim.pipeline();
  RunReport report(scene, run.particles, recipe.last_frame, run.threads, pipeline);
  Progress progress(options.progress, recipe.last_frame);
  const int every = std::max(scene.output.checkpoint_every, 1);
  auto interrupted = [&] { return options.interrupt && options.interrupt->load(); };
  auto write_report = [&] {
    const std::string text = report.dump();
    write_file_atomically(dir / kBakeReportFile, text);
    result.bytes_written += text.size();
  };

  int last_written = 0;  // the last frame whose files are all on disk (this session)
  const auto start = Clock::now();
  try {
    for (int f = result.start_frame + 1; f <= recipe.last_frame; ++f) {
      const auto frame_start = Clock::now();
      const FrameMetrics m = sim.step_frame();
      report.add_frame(m, sim.timer());
      run.metrics.push_back(m);
      throw_if_diverged(m, f);
      result.frames_done = f;
      result.simulate_seconds += seconds_since(frame_start);

      auto export_start = Clock::now();
      std::uint64_t frame_bytes = 0;
      if (f >= recipe.first_frame) {
        frame_bytes += writer.write(sim, f, result.files_written);
        last_written = f;
      }
      double frame_export_seconds = seconds_since(export_start);
      if (options.after_frame) options.after_frame(f);
      const bool stop = interrupted() && f < recipe.last_frame;  // read once: a checkpoint if so
      if (f % every == 0 || f == recipe.last_frame || stop) {
        export_start = Clock::now();
        const std::string cp = encode_checkpoint(sim, fingerprint);
        write_file_atomically(checkpoint_file, cp);
        frame_bytes += cp.size();
        result.checkpoint_frame = f;
        frame_export_seconds += seconds_since(export_start);
      }
      result.bytes_written += frame_bytes;
      result.export_seconds += frame_export_seconds;
      report.add_frame_output(1e3 * frame_export_seconds, frame_bytes);

      const int session_frames = f - result.start_frame;
      progress.frame_done(f, seconds_since(start), session_frames,
                          fmt::format("{} particles  simulate {:.1f} + export {:.1f} ms/frame",
                                      run.particles, 1e3 * result.simulate_seconds / session_frames,
                                      1e3 * result.export_seconds / session_frames),
                          fmt::format("  {} written", format_bytes(result.bytes_written)));
      if (stop) {
        progress.end_line();
        result.status = BakeResult::Status::Interrupted;
        report.set_error(fmt::format("interrupted after frame {} of {}", f, recipe.last_frame));
        write_report();
        return result;
      }
    }
  } catch (const std::exception& e) {
    progress.end_line();
    report.set_error(e.what());
    try {
      write_report();
    } catch (const IoError&) {
      // the first error is the one to tell
    }
    if (dynamic_cast<const IoError*>(&e)) {
      const std::string frames =
          last_written > 0
              ? fmt::format("frames up to {} are complete in {}", last_written, dir.string())
              : fmt::format("this run completed no frame files in {}", dir.string());
      throw IoError(fmt::format(
          "{}\n  {}; {}", e.what(), frames,
          result.checkpoint_frame > 0
              ? fmt::format("the checkpoint of frame {} is kept: {} continues from it",
                            result.checkpoint_frame, resume_command(dir))
              : fmt::format("no checkpoint was written yet: {} starts over from frame 1",
                            resume_command(dir))));
    }
    throw;
  }
  run.wall_seconds = seconds_since(start);
  run.frames = result.frames_done - result.start_frame;
  run.timer = sim.timer();
  write_report();
  if (options.summary) {
    print_run_summary(*options.summary, scene, run, pipeline);
    print_bake_summary(*options.summary, result, dir, writer);
  }
  return result;
}

}  // namespace

BakeResult bake_scene(const SceneDef& scene, const BakeRecipe& recipe, const BakeOptions& options) {
  const int threads = resolve_thread_count(options.threads);
  return run_with_threads(threads,
                          [&] { return bake_on_threads(scene, recipe, options, threads); });
}

}  // namespace seiche
