// libFuzzer target: the checkpoint reader. The input bytes are written to a file and read with
// read_checkpoint (magic, version, size, checksum, columns, chunks, ids). Since almost every
// mutation breaks the checksum, a second read gets the same bytes with the header's body size and
// FNV-1a checksum made right, so that the fuzzer reaches the body's parser; a checkpoint that
// reads is then restored (restore_checkpoint) into a simulation of the seed scene
// (checkpoint_fuzz_scene.hpp), which runs the families' chunk readers and the reordering.
// A ResumeError is the expected answer to bad input; anything else (another exception, a crash,
// a leak, an AddressSanitizer/UBSan report) is a finding. SEICHE_FUZZ_VERBOSE=1 prints each
// refusal (to see how far an input gets when replaying it: fuzz_checkpoint_reader <file>).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>

#include "checkpoint_fuzz_scene.hpp"
#include "seiche/checkpoint.hpp"
#include "seiche/scene_loader.hpp"
#include "seiche/simulation.hpp"

namespace {

namespace fs = std::filesystem;

// The header: magic (8 bytes), format version (u32), body size (u64), body checksum (u64).
constexpr std::size_t kSizeAt = 12, kChecksumAt = 20, kBodyAt = 28;

const fs::path& scratch_file() {
  static const fs::path file =
      fs::temp_directory_path() / ("seiche_fuzz_checkpoint_" + std::to_string(::getpid()) + ".bin");
  return file;
}

seiche::Simulation& scene_simulation() {
  static const auto sim = std::make_unique<seiche::Simulation>(
      seiche::load_scene_text(seiche::fuzz::kCheckpointScene, "fuzz_checkpoint.json"));
  return *sim;
}

void read_and_restore(std::string_view bytes) {
  const fs::path& file = scratch_file();
  std::ofstream(file, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), std::streamsize(bytes.size()));
  try {
    const seiche::Checkpoint cp = seiche::read_checkpoint(file);
    seiche::restore_checkpoint(scene_simulation(), cp, cp.scene_fingerprint, file);
  } catch (const seiche::ResumeError& e) {
    // refused with a message naming the file: what the reader must do
    if (std::getenv("SEICHE_FUZZ_VERBOSE") != nullptr) std::fprintf(stderr, "%s\n", e.what());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  read_and_restore(bytes);
  if (bytes.size() >= kBodyAt) {
    const std::uint64_t body_size = bytes.size() - kBodyAt;
    const std::uint64_t checksum = seiche::fnv1a64(std::string_view(bytes).substr(kBodyAt));
    std::memcpy(bytes.data() + kSizeAt, &body_size, sizeof body_size);
    std::memcpy(bytes.data() + kChecksumAt, &checksum, sizeof checksum);
    read_and_restore(bytes);
  }
  return 0;
}
