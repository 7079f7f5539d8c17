// The particle files of a run or a bake, in the formats output.particle_formats lists:
//   "ply"  particles.%04d.ply (encode_particles_ply, output_files.hpp)
//   "vtp"  particles.%04d.vtp, and particles.pvd: the series of the .vtp frames with their times,
//          which ParaView opens as one time series (vtk_particles.hpp)
// The series belongs to no frame. It is rewritten after every frame's .vtp and lists the frames
// first_frame..frame, so it never names a .vtp that is not complete on disk (each file is renamed
// into place whole, the .vtp before the series). A bake also writes it before its first frame,
// listing the frames up to its checkpoint (none for a new bake): the series of an earlier bake in
// the folder, whose frames the new one removes or replaces, and that of a killed bake, which
// lists frames after its checkpoint, are replaced before anything else is written. A kill
// between a frame's .vtp and the series leaves that frame unlisted until the resume rewrites both;
// a complete bake's or run's series lists exactly its frames first_frame..last, the same bytes
// whether or not the bake was stopped and resumed.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "seiche/frame_exporter.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

inline constexpr const char* kParticleSeriesFile = "particles.pvd";

class ParticleFiles {
 public:
  /// The formats of `scene.output`, for frames from `first_frame` on; `enabled` false writes
  /// nothing (a bake with output.particles = false).
  ParticleFiles(const SceneDef& scene, int first_frame, bool enabled);

  /// Whether particles.pvd is written.
  bool writes_series() const { return vtp_; }
  /// Frame `frame`'s particle files in the order they must reach the disk: the PLY, the .vtp,
  /// then the series rewritten to list the frames first_frame..frame.
  std::vector<FrameExporter::EncodedFile> encode(const ParticleStore& particles, int frame) const;
  /// The series listing the frames first_frame..last_frame (none when last_frame < first_frame).
  FrameExporter::EncodedFile encode_series(int last_frame) const;
  /// The names of the files that belong to frame `frame` (the series belongs to none).
  std::vector<std::string> frame_names(int frame) const;
  /// How many files encode() gives for a frame.
  std::size_t files_per_frame() const;
  /// "particles.0001.ply .. particles.0020.ply", one line per kind of file, the series last.
  std::vector<std::string> describe(int first, int last) const;
  /// check_file_name_inside (output_files.hpp) for every name written for frames first..last.
  void check_names_inside(const std::filesystem::path& dir, int first, int last) const;

 private:
  bool ply_ = false, vtp_ = false;
  int first_frame_ = 1;
  double frame_dt_ = 0.0;
};

}  // namespace seiche
