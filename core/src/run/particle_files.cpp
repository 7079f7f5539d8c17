// The particle files of a run or a bake (the rules: particle_files.hpp).
#include "particle_files.hpp"

#include "seiche/output_files.hpp"
#include "seiche/vtk_particles.hpp"

namespace seiche {

namespace {

constexpr const char* kStem = "particles";

}  // namespace

ParticleFiles::ParticleFiles(const SceneDef& scene, int first_frame, bool enabled)
    : ply_(enabled && scene.output.particles_ply),
      vtp_(enabled && scene.output.particles_vtp),
      first_frame_(first_frame),
      frame_dt_(scene.solver.frame_dt) {}

std::vector<FrameExporter::EncodedFile> ParticleFiles::encode(const ParticleStore& particles, int frame) const {
  std::vector<FrameExporter::EncodedFile> files;
  if (ply_) files.push_back({frame_file_name(kStem, frame, "ply"), encode_particles_ply(particles)});
  if (vtp_) {
    files.push_back({frame_file_name(kStem, frame, "vtp"), encode_particles_vtp(particles)});
    files.push_back(encode_series(frame));
  }
  return files;
}

FrameExporter::EncodedFile ParticleFiles::encode_series(int last_frame) const {
  return {kParticleSeriesFile, encode_particle_series_pvd(kStem, first_frame_, last_frame, frame_dt_)};
}

std::vector<std::string> ParticleFiles::frame_names(int frame) const {
  std::vector<std::string> names;
  if (ply_) names.push_back(frame_file_name(kStem, frame, "ply"));
  if (vtp_) names.push_back(frame_file_name(kStem, frame, "vtp"));
  return names;
}

std::size_t ParticleFiles::files_per_frame() const { return (ply_ ? 1 : 0) + (vtp_ ? 2 : 0); }

std::vector<std::string> ParticleFiles::describe(int first, int last) const {
  std::vector<std::string> lines;
  const std::vector<std::string> a = frame_names(first), b = frame_names(last);
  for (std::size_t k = 0; k < a.size(); ++k) lines.push_back(first == last ? a[k] : a[k] + " .. " + b[k]);
  if (vtp_) lines.push_back(std::string(kParticleSeriesFile) + "  (the .vtp frames as one ParaView time series)");
  return lines;
}

void ParticleFiles::check_names_inside(const std::filesystem::path& dir, int first, int last) const {
  for (const int frame : {first, last})
    for (const std::string& name : frame_names(frame)) check_file_name_inside(dir, name);
  if (vtp_) check_file_name_inside(dir, kParticleSeriesFile);
}

}  // namespace seiche
