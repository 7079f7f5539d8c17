// A checkpoint: the simulation state after a frame, in one file, so that a bake can stop at any
// time and continue later bit for bit (`seiche bake --resume`).
//
// What makes a continuation bit-identical: every State column of the store (particle_store.hpp),
// in its current (cell) order, since the neighbor search's sort is stable (its result depends on
// the input order) and the solvers sum in index order; and the state each constraint family
// carries from one substep to the next (Family::save_state: the cloth stretch multipliers of the
// last substep, which the stretch forests' geometric stiffness reads in the next one). Everything
// else is either rebuilt from the scene (constraints, rest lengths, particle mass, the Constant
// columns, the grid) or recomputed every substep (neighbor lists, the Scratch columns).
// Restoring builds a fresh Simulation from the same scene, reorders it into the saved order
// (which remaps every index held elsewhere), overwrites the State columns and hands each family
// its chunks.
//
// File layout (little-endian), format version 3:
//   char[8]  magic "SEICHECP"
//   u32      format version
//   u64      body size in bytes (everything after the checksum)
//   u64      FNV-1a 64 checksum of the body
//   body:
//     u32 + bytes   seiche version that wrote it
//     u64           scene fingerprint (scene_fingerprint(): which scene this state belongs to)
//     i32           frames done
//     f64           simulated time (s)
//     u64           particle count n
//     u32           column count, then each State column by name:
//                     u32 + bytes  name ("x", "px", "phase", "id", or a family's column)
//                     u8           element type: 0 f32, 1 u32, 2 i32
//                     n values of 4 bytes
//     u32           chunk count, then each family chunk by name (checkpoint_chunks.hpp):
//                     u32 + bytes  name ("cloth.stretch_multipliers")
//                     u64 + bytes  its size and bytes
// A truncated file fails the size check, a flipped bit the checksum, a column or chunk this
// seiche does not know (or one the scene needs that is missing) the restore: either way the
// reader says which file and what is wrong, and nothing is continued.
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "seiche/checkpoint_chunks.hpp"
#include "seiche/particle_store.hpp"

namespace seiche {

class Simulation;

/// A checkpoint or a bake folder that cannot be resumed from (missing, corrupt, of another scene
/// or another version). what() names the file and the problem.
class ResumeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The state of a simulation after `frame` frames.
struct Checkpoint {
  std::string seiche_version;
  std::uint64_t scene_fingerprint = 0;
  int frame = 0;
  double time = 0.0;
  ParticleStore state;  ///< every State column read, in the saved (cell) order
  CheckpointChunks chunks;  ///< the families' chunks
};

/// FNV-1a 64-bit hash: the checksum of checkpoints and the scene fingerprint.
std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t hash = 0xcbf29ce484222325ull);

/// The checkpoint file of the simulation's current state.
std::string encode_checkpoint(const Simulation& sim, std::uint64_t scene_fingerprint);

/// Reads and verifies a checkpoint file (magic, format version, size, checksum, every built-in
/// State column present, ids form a permutation). A column the built-in table does not have is
/// kept as a State column for restore_checkpoint to match with the scene's families. Throws
/// ResumeError naming `file` when it cannot be used.
Checkpoint read_checkpoint(const std::filesystem::path& file);

/// Puts a checkpoint's state into `sim`, a simulation built from the checkpoint's scene. Checks
/// the fingerprint, the version, the particle count, and that the checkpoint's State columns and
/// chunks are exactly those of `sim`'s store and families, first; throws ResumeError naming
/// `file` (the checkpoint's origin, for messages) when they do not match.
void restore_checkpoint(Simulation& sim, const Checkpoint& checkpoint,
                        std::uint64_t scene_fingerprint, const std::filesystem::path& file);

}  // namespace seiche
