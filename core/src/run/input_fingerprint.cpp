// Input files and their fingerprints (the contract is in input_fingerprint.hpp). The hash is the
// one the loader computed over the bytes it read (ClothMesh::source_fnv1a64, BodyMesh's), so the record is
// what the simulation used, not a second read that could see another file.
#include "seiche/input_fingerprint.hpp"

#include <fmt/format.h>
#include <fmt/ostream.h>

#include <fstream>
#include <iterator>
#include <system_error>

#include "../families/cloth/cloth_mesh.hpp"
#include "../families/rigid/body_mesh.hpp"
#include "../families/shape/shape_sites.hpp"
#include "seiche/checkpoint.hpp"

namespace seiche {

namespace fs = std::filesystem;

namespace {

// The file as the loader read it (its size and hash, where `loaded` holds them), else read now.
template <class Loaded>
InputFile fingerprint(std::string json_path, const std::string& file, const Loaded* loaded) {
  InputFile in{std::move(json_path), file, 0, 0};
  if (loaded) {
    in.bytes = loaded->source_bytes;
    in.fnv1a64 = loaded->source_fnv1a64;
    return in;
  }
  std::ifstream stream(file, std::ios::binary);
  const std::string text{std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>()};
  in.bytes = text.size();
  in.fnv1a64 = fnv1a64(text);
  return in;
}

std::string describe(const InputFile& f) {
  return fmt::format("{} bytes, fnv1a64 {:016x}", f.bytes, f.fnv1a64);
}

}  // namespace

std::vector<InputFile> scene_input_files(const SceneDef& scene) {
  std::vector<InputFile> files;
  for (std::size_t k = 0; k < scene.cloths.size(); ++k) {
    const ClothDef& c = scene.cloths[k];
    if (c.mesh)
      files.push_back(fingerprint(fmt::format("cloths[{}].mesh.file", k), c.mesh->file, c.loaded_mesh.get()));
  }
  for (std::size_t k = 0; k < scene.colliders.size(); ++k) {
    const ColliderDef& c = scene.colliders[k];
    if (c.shape == ColliderDef::Shape::Mesh)
      files.push_back(fingerprint(fmt::format("colliders[{}].mesh.file", k), c.mesh.file, c.loaded_mesh.get()));
  }
  for (std::size_t k = 0; k < scene.shapes.size(); ++k) {
    const ShapeDef& s = scene.shapes[k];
    if (s.kind == ShapeDef::Kind::Mesh)
      files.push_back(fingerprint(fmt::format("shapes[{}].mesh.file", k), s.mesh.file, s.loaded_sites.get()));
  }
  for (std::size_t k = 0; k < scene.rigid_bodies.size(); ++k) {
    const RigidBodyDef& b = scene.rigid_bodies[k];
    if (b.shape == "mesh")
      files.push_back(fingerprint(fmt::format("rigid_bodies[{}].mesh.file", k), b.mesh.file, b.loaded_mesh.get()));
  }
  return files;
}

void check_recorded_inputs_present(const std::vector<InputFile>& recorded, const fs::path& recipe_file) {
  std::vector<std::string> missing;
  for (const InputFile& f : recorded) {
    std::error_code ec;
    const fs::file_status status = fs::status(f.file, ec);
    if (ec || !fs::exists(status))
      missing.push_back(fmt::format("{} ({}): missing ({})", f.file, f.json_path,
                                    ec ? ec.message() : std::string("no such file")));
    else if (!fs::is_regular_file(status))
      missing.push_back(fmt::format("{} ({}): not a regular file", f.file, f.json_path));
  }
  if (missing.empty()) return;
  throw ResumeError(fmt::format(
      "{}: an input file of the bake is gone:\n  {}\nthe bake read it when it started; put it back (the same bytes) "
      "to resume: no simulation can continue without it",
      recipe_file.string(), fmt::join(missing, "\n  ")));
}

std::vector<std::string> input_file_changes(const std::vector<InputFile>& recorded,
                                            const std::vector<InputFile>& current) {
  std::vector<std::string> changes;
  for (const InputFile& was : recorded) {
    const InputFile* now = nullptr;
    for (const InputFile& c : current)
      if (c.json_path == was.json_path) now = &c;
    if (!now)
      changes.push_back(fmt::format("{} ({}): no longer in the scene", was.file, was.json_path));
    else if (now->file != was.file)
      changes.push_back(fmt::format("{}: was {}, now {}", was.json_path, was.file, now->file));
    else if (now->bytes != was.bytes || now->fnv1a64 != was.fnv1a64)
      changes.push_back(fmt::format("{} ({}): changed since the bake started (was {}; now {})", was.file,
                                    was.json_path, describe(was), describe(*now)));
  }
  for (const InputFile& c : current) {
    bool known = false;
    for (const InputFile& was : recorded) known = known || was.json_path == c.json_path;
    if (!known) changes.push_back(fmt::format("{} ({}): not recorded when the bake started", c.file, c.json_path));
  }
  return changes;
}

void check_inputs_unchanged(const std::vector<InputFile>& recorded, const std::vector<InputFile>& current,
                            const fs::path& recipe_file, bool accept_changed, std::ostream* warnings) {
  const std::vector<std::string> changes = input_file_changes(recorded, current);
  if (changes.empty()) return;
  if (!accept_changed)
    throw ResumeError(fmt::format(
        "{}: an input file of the bake changed:\n  {}\nthe frames after the checkpoint would not continue the "
        "frames before it; restore the file, or pass --accept-changed-inputs to continue with it as it is now",
        recipe_file.string(), fmt::join(changes, "\n  ")));
  if (warnings)
    fmt::print(*warnings,
               "seiche: warning: continuing with changed input files (--accept-changed-inputs); bake.json now "
               "records them as they are:\n  {}\n",
               fmt::join(changes, "\n  "));
}

}  // namespace seiche
