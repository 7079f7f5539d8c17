// libFuzzer target: the scene loader (load_scene_text) on arbitrary bytes, meshes included. A
// SceneError is the expected answer to bad input; any other exception escapes and aborts the
// run, and a crash, a leak or an AddressSanitizer/UBSan report stops it too: each is a finding.
//
// The input is a scene, optionally followed by a line "--- fuzz.obj ---" and the bytes of an OBJ
// file, which is written as fuzz.obj into the folder relative mesh paths resolve against: the
// loader reads and checks the meshes a scene names, so the fuzzer mutates both. That folder also
// links meshes/ to scenes/meshes (the shipped scenes of the seed corpus name them) and data/ to
// tests/data. SEICHE_FUZZ_VERBOSE=1 prints each refusal (when replaying an input).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "seiche/scene_loader.hpp"

namespace {

namespace fs = std::filesystem;

constexpr std::string_view kMeshSeparator = "\n--- fuzz.obj ---\n";

const fs::path& mesh_folder() {
  static const fs::path dir = [] {
    const fs::path d =
        fs::temp_directory_path() / ("seiche_fuzz_scene_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    fs::create_directory_symlink(fs::path(SEICHE_SOURCE_DIR) / "scenes" / "meshes", d / "meshes");
    fs::create_directory_symlink(fs::path(SEICHE_SOURCE_DIR) / "tests" / "data", d / "data");
    std::atexit([] { std::error_code ignored; fs::remove_all(mesh_folder(), ignored); });
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string_view scene(reinterpret_cast<const char*>(data), size);
  const fs::path mesh = mesh_folder() / "fuzz.obj";
  if (const auto at = scene.find(kMeshSeparator); at != std::string_view::npos) {
    const std::string_view obj = scene.substr(at + kMeshSeparator.size());
    std::ofstream(mesh, std::ios::binary | std::ios::trunc)
        .write(obj.data(), std::streamsize(obj.size()));
    scene = scene.substr(0, at);
  } else {
    std::error_code ignored;
    fs::remove(mesh, ignored);
  }
  try {
    (void)seiche::load_scene_text(scene, "fuzz.json", {}, mesh_folder());
  } catch (const seiche::SceneError& e) {
    // bad input, refused with a message: what the loader must do
    if (std::getenv("SEICHE_FUZZ_VERBOSE") != nullptr) std::fprintf(stderr, "%s\n", e.what());
  }
  return 0;
}
