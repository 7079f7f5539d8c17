// The scene argument of the Python API, turned into a checked SceneDef exactly as the command
// line does it (apps/seiche/main.cpp): None is the built-in dam break, a dict is the scene as JSON
// (json.dumps), a str or path-like is a scene file; `set` holds --set overrides ("KEY=VALUE"
// strings, or a dict {KEY: value} whose values are written as JSON); the scene is then checked
// against the memory and work bounds (max_memory: None, bytes, or a size such as "8G").
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/pybind11.h>

#include "seiche/scene.hpp"

namespace seiche_py {

/// Where a scene comes from: its JSON text and the name messages give it.
struct SceneInput {
  std::string text;
  std::string source;          ///< the file, "<scene dict>" or "<default scene>"
  std::filesystem::path file;  ///< empty unless it is a file
  std::filesystem::path base_dir;  ///< relative mesh paths of a dict scene resolve here (default: cwd)
};

/// The bounds of the CLI's --max-memory and --allow-huge-work.
struct SceneLimits {
  std::optional<std::uint64_t> max_memory;
  bool allow_huge_work = false;
};

SceneInput scene_input(const pybind11::object& scene, const pybind11::object& base_dir);
std::vector<std::string> scene_overrides(const pybind11::object& set);
SceneLimits scene_limits(const pybind11::object& max_memory, bool allow_huge_work);

/// Loads the scene with `overrides` (seiche::load_scene_file or load_scene_text) and checks it
/// against the limits. Throws SceneError as the CLI's loader does.
seiche::SceneDef load_checked_scene(const SceneInput& input, const std::vector<std::string>& overrides,
                                    const SceneLimits& limits);

/// The scene's JSON text as read (what a bake records in bake.json).
std::string scene_json_text(const SceneInput& input);

}  // namespace seiche_py
