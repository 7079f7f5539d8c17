// The scene behind the checkpoint fuzzer: small (under 100 particles, so that one restore costs
// microseconds) but with every family that keeps state in a checkpoint: a cloth (its chunk
// "cloth.stretch_multipliers"), a shape (chunk "shape.rotations"), a fluid and raw particles on a
// distance constraint (their State columns). write_checkpoint_seeds.cpp writes the seed
// checkpoints of this scene, fuzz_checkpoint_reader.cpp restores the fuzzed ones into it.
#pragma once

namespace seiche::fuzz {

inline constexpr const char* kCheckpointScene = R"({
  "name": "fuzz_checkpoint",
  "solver": { "substeps": 2, "iterations": 2 },
  "domain": { "min": [0, 0, 0], "max": [1, 1, 1] },
  "cloths": [ { "sheet": { "origin": [0.2, 0.8, 0.2], "size": [0.3, 0.3], "resolution": [4, 4] },
                "pins": [0, 3] } ],
  "shapes": [ { "box": { "min": [0.6, 0.3, 0.6], "max": [0.7, 0.4, 0.7] }, "spacing": 0.05 } ],
  "fluids": [ { "box": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.2] }, "spacing": 0.05 } ],
  "particles": [ { "x": [0.8, 0.9, 0.25], "mass": 0 }, { "x": [0.85, 0.9, 0.25] } ],
  "distance_constraints": [ { "i": 0, "j": 1 } ] })";

}  // namespace seiche::fuzz
