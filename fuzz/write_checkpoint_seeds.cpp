// Writes the checkpoint fuzzer's seed corpus: real checkpoints of the fuzz scene
// (checkpoint_fuzz_scene.hpp) after 0, 1 and 3 frames, into the folder given as the argument.
// Generated at fuzz time rather than committed, so that the seeds always match this seiche's
// checkpoint format and version.
#include <cstdio>
#include <filesystem>
#include <string>

#include "checkpoint_fuzz_scene.hpp"
#include "seiche/checkpoint.hpp"
#include "seiche/output_files.hpp"
#include "seiche/scene_loader.hpp"
#include "seiche/simulation.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <seed folder>\n", argv[0]);
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);
  seiche::Simulation sim(
      seiche::load_scene_text(seiche::fuzz::kCheckpointScene, "fuzz_checkpoint.json"));
  constexpr std::uint64_t kFingerprint = 0x5e1c4e;  // the fuzzer restores with the file's own
  for (int frames : {0, 1, 3}) {
    while (sim.frame() < frames) sim.step_frame(seiche::FrameMeasure::Skip);
    seiche::write_file_atomically(dir / ("checkpoint_frame" + std::to_string(frames) + ".bin"),
                                  seiche::encode_checkpoint(sim, kFingerprint));
  }
  return 0;
}
