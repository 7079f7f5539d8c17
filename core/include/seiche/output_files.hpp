// Writing output files so that a crash never leaves a torn one: the bytes go to a temporary
// file next to the target, are flushed to disk, and only then renamed over the target (rename
// is atomic on POSIX file systems). Any failure (full disk, no permission) throws IoError
// naming the file and the reason, and removes the temporary file. And the checks a run or a
// bake makes before its first frame: every file it will write lies inside its output folder,
// and every folder and file it will write can be written.
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

/// Creates `dir` (and parents) and checks that a file can be written in it: a real write test
/// (a probe file, created and removed), since access() says yes to root even where nothing can
/// be created (/proc).
void prepare_output_directory(const std::filesystem::path& dir);

/// Checks, before anything is written, that `file` (a report, a checkpoint) can be written:
/// it is not a folder, its folder exists or can be created, and a file can be created next to it
/// (its temporary twin, created and removed). Throws IoError naming `file`.
void check_output_file_writable(const std::filesystem::path& file);

/// Checks that `name`, a file name an exporter will write under `dir`, is one plain file name:
/// relative, a single part, not "." or "..", so that dir / name lies inside dir (lexically;
/// write_file_atomically follows no symbolic link at the name either). Throws IoError naming dir
/// and name. Scene names are checked when the scene is read; this guards every exporter.
void check_file_name_inside(const std::filesystem::path& dir, const std::filesystem::path& name);

/// Binary little-endian PLY: float x y z vx vy vz, int id; one vertex per particle, in id order.
std::string encode_particles_ply(const ParticleStore& store);

/// "particles.0007.ply" for frame 7.
std::string frame_file_name(std::string_view stem, int frame, std::string_view extension);

}  // namespace seiche
