// Writing output files so that a crash never leaves a torn one: the bytes go to a temporary
// file next to the target, are flushed to disk, and only then renamed over the target (rename
// is atomic on POSIX file systems). Any failure (full disk, no permission) throws IoError
// naming the file and the reason, and removes the temporary file.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

#include "seiche/particle_store.hpp"

namespace seiche {

class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

/// Creates `dir` (and parents) and checks that a file can be written in it.
void prepare_output_directory(const std::filesystem::path& dir);

/// Binary little-endian PLY: float x y z vx vy vz, int id; one vertex per particle, in id order.
std::string encode_particles_ply(const ParticleStore& store);

/// "particles.0007.ply" for frame 7.
std::string frame_file_name(std::string_view stem, int frame, std::string_view extension);

}  // namespace seiche
