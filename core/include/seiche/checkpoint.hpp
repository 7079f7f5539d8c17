// A checkpoint: the simulation state after a frame, in one file, so that a bake can stop at any
// time and continue later bit for bit (`seiche bake --resume`).
//
// What makes a continuation bit-identical: every state column of the store, in its current (cell)
// order, since the neighbor search's sort is stable (its result depends on the input order) and
// the solvers sum in index order. Everything else is either rebuilt from the scene (constraints,
// rest lengths, particle mass, the grid) or recomputed every substep (neighbor lists, density,
// lambda, vorticity), except the cloth stretch multipliers of the last substep, which the
// stretch forests' geometric stiffness reads in the next one (kernels/distance_tree.hpp).
// Restoring builds a fresh Simulation from the same scene, reorders it into the saved order
// (which remaps every index held elsewhere) and overwrites the state columns.
//
// File layout (little-endian), format version 2:
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
//     u32           column count (12), then the columns, n values each, in this order:
//                   x y z px py pz vx vy vz w (f32), phase (u32), id (i32)
//     u64           m, then m f32: the cloth stretch multipliers of the last substep, in the
//                   constraints' (scene-determined) order; m = 0 without stretch forests
// A truncated file fails the size check, a flipped bit the checksum: either way the reader says
// which file and what is wrong, and nothing is restored.
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

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
  ParticleStore state;  ///< every state column, in the saved (cell) order
  std::vector<float> stretch_multipliers;  ///< the cloth stretch forests' tension (may be empty)
};

/// FNV-1a 64-bit hash: the checksum of checkpoints and the scene fingerprint.
std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t hash = 0xcbf29ce484222325ull);

/// The checkpoint file of the simulation's current state.
std::string encode_checkpoint(const Simulation& sim, std::uint64_t scene_fingerprint);

/// Reads and verifies a checkpoint file (magic, format version, size, checksum, ids form a
/// permutation). Throws ResumeError naming `file` when it cannot be used.
Checkpoint read_checkpoint(const std::filesystem::path& file);

/// Puts a checkpoint's state into `sim`, a simulation built from the checkpoint's scene. Checks
/// the fingerprint and the particle count first; throws ResumeError naming `file` (the
/// checkpoint's origin, for messages) when they do not match.
void restore_checkpoint(Simulation& sim, const Checkpoint& checkpoint,
                        std::uint64_t scene_fingerprint, const std::filesystem::path& file);

}  // namespace seiche
