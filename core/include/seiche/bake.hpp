// `seiche bake`: the production run, safe to stop at any time.
//
// A bake steps a scene from frame 1 to frame B and writes, for every frame of the range A..B,
// what the scene's output section asks for: the particle files (output.particles, in the formats
// of output.particle_formats: particles.%04d.ply, particles.%04d.vtp with their series
// particles.pvd; run/particle_files.hpp) and the files of every exporter (.vdb, .obj, ...; the
// bake does not know what they hold). Every file is
// written atomically (write_file_atomically), so a crash, a kill or a full disk never leaves a
// torn one.
//
// Resuming: DIR/bake.json, written before the first frame, holds everything a resume needs
// without the original files (the scene's text, the --set overrides, the frame range and the
// Seiche version), and the fingerprints of the files the scene refers to (its OBJ meshes,
// input_fingerprint.hpp): a resume refuses a missing or changed one unless told to accept it. DIR/checkpoint.bin holds the simulation state (checkpoint.hpp) and is
// replaced every output.checkpoint_every frames, on an interrupt and at the end; the rename is
// atomic, so the previous checkpoint stays valid until the next one is complete. Per frame the
// files come first and the checkpoint second: a checkpoint at frame c means frames up to c are
// on disk. A resume rebuilds the scene from bake.json, restores the checkpoint and steps on; the
// frames after c come out bit for bit as in an uninterrupted bake (frames a killed bake wrote
// after c are rewritten with the same bytes).
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "seiche/checkpoint.hpp"
#include "seiche/frame_exporter.hpp"
#include "seiche/input_fingerprint.hpp"
#include "seiche/runner.hpp"
#include "seiche/scene.hpp"

namespace seiche {

inline constexpr const char* kBakeRecipeFile = "bake.json";
inline constexpr const char* kCheckpointFile = "checkpoint.bin";
inline constexpr const char* kBakeReportFile = "report.json";

/// DIR/bake.json: what was baked, enough to rebuild the scene without the original file.
struct BakeRecipe {
  std::string seiche_version;          ///< the version that started the bake
  std::string scene_name;              ///< the scene's name (a file's stem when it has none)
  std::string scene_source;            ///< the scene file, or "<default scene>" (for messages)
  /// Absolute folder of the scene file ("" for the default scene): relative mesh paths in the
  /// scene are resolved against it, also when a resume runs from another working directory.
  std::string scene_dir;
  std::string scene_json;              ///< the scene's text, as read
  std::vector<std::string> overrides;  ///< --set KEY=VALUE, applied on top of scene_json
  /// The files the scene refers to (OBJ meshes), fingerprinted as the loader read them: a resume
  /// checks them (check_recorded_inputs_present, check_inputs_unchanged).
  std::vector<InputFile> inputs;
  int first_frame = 1;                 ///< frames first_frame..last_frame are written
  int last_frame = 1;
  /// The kernels' arithmetic of the build that started the bake (kernels::simd_info): builds
  /// whose multiply-adds are fused (x86-64-v3 and up) and those whose are not (the x86-64
  /// baseline) compute different bits, so a resume needs the same kind (docs/design.md, "The
  /// determinism contract"). `simd` is the starting build's description, for messages.
  std::string family;  ///< kernels::SimdInfo::family of the starting build
  bool fused_multiply_add = true;
  std::string simd;

  /// Which scene a checkpoint belongs to: FNV-1a over name, text and overrides.
  std::uint64_t scene_fingerprint() const;
};

/// A recipe of this Seiche version.
BakeRecipe make_bake_recipe(std::string scene_name, std::string scene_source,
                            std::string scene_json, std::vector<std::string> overrides,
                            int first_frame, int last_frame);
std::string encode_bake_recipe(const BakeRecipe& recipe);
/// Reads `dir`/bake.json. Throws ResumeError naming the folder or the file when the folder or
/// the file is missing, the file is damaged, or it was written by another Seiche version.
BakeRecipe read_bake_recipe(const std::filesystem::path& dir);
/// The recipe's scene, loaded and checked like a scene file (SceneError names `recipe_file`).
SceneDef load_recipe_scene(const BakeRecipe& recipe, const std::filesystem::path& recipe_file);

struct BakeOptions {
  std::filesystem::path out_dir;  ///< required
  int threads = 0;                ///< 0 = every core
  bool resume =
      false;  ///< continue from out_dir/checkpoint.bin (from frame 1 when none exists yet)
  std::vector<FrameExporter*> exporters;  ///< writers of the frame files other than the particles'
  std::ostream* progress = nullptr;       ///< progress lines (stderr in the CLI); null = quiet
  std::ostream* summary = nullptr;        ///< settings, pass table, files written at the end
  /// Set (by a signal handler) to stop after the current frame, with a checkpoint.
  const std::atomic<bool>* interrupt = nullptr;
  /// Called after each frame's files are written, before its checkpoint (a test hook).
  std::function<void(int frame)> after_frame;
};

struct BakeResult {
  enum class Status { Complete, AlreadyComplete, Interrupted };
  Status status = Status::Complete;
  int first_frame = 1, last_frame = 1;  ///< the range written
  int start_frame = 0;       ///< frames done when this session started (the checkpoint's frame)
  int frames_done = 0;       ///< the last frame stepped
  int checkpoint_frame = 0;  ///< the frame of the checkpoint on disk (0: none)
  std::uint64_t bytes_written = 0;
  std::size_t files_written = 0;
  double simulate_seconds = 0.0;  ///< stepping, metrics included
  double export_seconds = 0.0;    ///< writing frame files and checkpoints
  RunResult run;                  ///< metrics and pass timers of the frames this session stepped
};

/// "seiche bake --resume DIR", quoted for a shell when DIR needs it.
std::string resume_command(const std::filesystem::path& dir);

/// Bakes (or, with options.resume, continues baking) `scene`, described by `recipe`. Checks before
/// stepping anything that every exporter's files lie inside the folder and that the folder, the
/// report and the checkpoint can be written. A new bake (not a resume) into a folder with an
/// earlier bake.json removes that bake's frame files outside the new range (earlier_bake.hpp). Throws IoError (a file could not be
/// written; what() names it and says which frame and checkpoint are kept), SimulationError (the
/// state became non-finite; no checkpoint of it is written), ResumeError (the checkpoint cannot
/// be used) or SceneError.
BakeResult bake_scene(const SceneDef& scene, const BakeRecipe& recipe, const BakeOptions& options);

}  // namespace seiche
