// The input files of a scene (every cloth's, mesh collider's, mesh shape's and mesh rigid body's OBJ) and their
// fingerprints: the size and FNV-1a 64 hash of the bytes the scene loader read, so that what is recorded is what the
// simulation used. A bake records them in bake.json (bake.hpp); a resume compares the files as
// the loader reads them again with the record and refuses a missing or changed one, naming it,
// unless the user accepts the change (`seiche bake --resume DIR --accept-changed-inputs`).
#pragma once

#include <cstdint>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "seiche/scene.hpp"

namespace seiche {

struct InputFile {
  std::string json_path;  ///< where the scene names it: "colliders[1].mesh.file"
  std::string file;       ///< the path the loader read (absolute for a scene file's meshes)
  std::uint64_t bytes = 0;
  std::uint64_t fnv1a64 = 0;

  bool operator==(const InputFile&) const = default;
};

/// The input files of a loaded scene, in scene order (cloths, colliders, shapes, then rigid bodies), with the
/// fingerprints of the bytes the loader read. A definition made in code without a loaded mesh
/// has its file read and hashed here.
std::vector<InputFile> scene_input_files(const SceneDef& scene);

/// Before a resume loads its scene: throws ResumeError naming `recipe_file` and every recorded
/// input that is missing or not a readable regular file (no override continues without it).
void check_recorded_inputs_present(const std::vector<InputFile>& recorded,
                                   const std::filesystem::path& recipe_file);

/// After a resume loaded its scene: the differences between the recorded inputs and the scene's
/// (a changed size or hash, a file no longer or newly referred to), one line each naming the file,
/// its JSON path and what changed; empty when they match.
std::vector<std::string> input_file_changes(const std::vector<InputFile>& recorded,
                                            const std::vector<InputFile>& current);

/// Refuses (ResumeError naming `recipe_file`, each change and the override flag) when
/// input_file_changes() is not empty; with `accept_changed`, writes the changes to `warnings` (if
/// not null) as a warning instead.
void check_inputs_unchanged(const std::vector<InputFile>& recorded, const std::vector<InputFile>& current,
                            const std::filesystem::path& recipe_file, bool accept_changed,
                            std::ostream* warnings);

}  // namespace seiche
