// Reading a scene: JSON text -> SceneDef, with every value checked before anything runs.
// Errors name the file, the JSON path and the problem ("scenes/x.json: fluids[0].spacing: must be
// > 0, got -0.1"). Overrides ("solver.iterations=8") are applied to the JSON before it is read,
// so an override is checked exactly like a value in the file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

#include "seiche/scene.hpp"

namespace seiche {

/// Bad scene input. what() is "<file>: <json path>: <problem>".
class SceneError : public std::runtime_error {
 public:
  SceneError(std::string file, std::string json_path, std::string problem);
  const std::string& file() const { return file_; }
  const std::string& json_path() const { return json_path_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string file_, json_path_, problem_;
};

/// Parses and validates a scene. `source` names the text in error messages (a file path, or
/// "<default scene>"). `overrides` are "KEY=VALUE" with KEY a dotted JSON path
/// ("solver.iterations", "fluids.0.spacing" or "fluids[0].spacing") and VALUE JSON
/// ("8", "[0,-9.81,0]", "true") or, if it does not parse as JSON, a plain string.
/// `base_dir`: the folder relative mesh paths ("cloths[k].mesh.file") are resolved against
/// (empty: the working directory).
SceneDef load_scene_text(std::string_view json_text, std::string_view source,
                         std::span<const std::string> overrides = {},
                         const std::filesystem::path& base_dir = {});

/// The largest scene file load_scene_file reads: 256 MiB, about 4 million raw particles (the
/// 2-million-particle scene of bench_scene_load is 115 MiB). Loading takes about 13 bytes of memory
/// per byte of text (the JSON document), so this bounds the loader's memory at about 3.5 GB.
inline constexpr std::uintmax_t kMaxSceneFileBytes = std::uintmax_t{256} << 20;

/// Reads a file and calls load_scene_text; the scene's name defaults to the file's stem. A path
/// that is not a regular file (a directory, a device, a FIFO) or a file over kMaxSceneFileBytes
/// is refused before it is read (SceneError, json path "(file)").
SceneDef load_scene_file(const std::filesystem::path& file,
                         std::span<const std::string> overrides = {});

/// The default scene (scenes/dam_break.json, embedded in the binary at build time).
std::string_view default_scene_json();

}  // namespace seiche
