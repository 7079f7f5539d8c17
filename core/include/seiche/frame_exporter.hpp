// An exporter writes the files of one finished frame (a .vdb surface, an .obj mesh, ...). The
// bake owns the frame loop and calls every exporter the scene asks for; exporters that need
// libraries the core must not link (OpenVDB) live in their own targets and implement this
// interface.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

/// A rigid body's state at the end of a frame (scene.rigid_bodies order), world frame.
struct BodyPose {
  std::array<double, 3> position{};          ///< centre of mass (m)
  std::array<double, 4> orientation{1, 0, 0, 0};  ///< unit quaternion [w, x, y, z], body to world
  std::array<double, 3> velocity{};          ///< m/s
  std::array<double, 3> angular_velocity{};  ///< rad/s
};

/// One finished frame, as an exporter sees it. The store is in cell order; store.id gives the
/// creation order that every export must follow.
struct FrameView {
  const ParticleStore& particles;
  const SceneDef& scene;
  int frame = 0;      ///< 1-based frame number
  double time = 0.0;  ///< simulated time at the end of the frame (s)
  std::span<const BodyPose> bodies = {};  ///< every rigid body (Simulation::body_poses)
};

class FrameExporter {
 public:
  virtual ~FrameExporter() = default;
  /// Short name for progress lines and errors ("vdb").
  virtual std::string name() const = 0;
  /// The files write_frame() writes for `frame`, relative to the output folder.
  virtual std::vector<std::filesystem::path> files(int frame) const = 0;
  /// Writes this frame's files into `dir`, each atomically (write_file_atomically). Returns the
  /// bytes written. Throws IoError when a file cannot be written. By default, the files of
  /// encode_frame(); an exporter whose library writes its own files overrides it.
  virtual std::uint64_t write_frame(const FrameView& frame, const std::filesystem::path& dir);

  /// One file of a frame as bytes: its name relative to the output folder and its contents.
  struct EncodedFile {
    std::filesystem::path name;
    std::string bytes;
  };
  /// This frame's files as bytes, for a caller that writes them itself (seiche run hands them
  /// to its background writer). Empty for an exporter whose library writes its own files
  /// (OpenVDB): such an exporter is only used through write_frame().
  virtual std::vector<EncodedFile> encode_frame(const FrameView&) const { return {}; }
};

/// The exporters of the scene's families, in the registry's order (core/src/loop/
/// family_registry.cpp): every cloth's OBJ and the rigid bodies' bodies.%04d.jsonl today. The fluid's .vdb and mesh exporter lives in
/// its own target (it links OpenVDB) and the app adds it.
std::vector<std::unique_ptr<FrameExporter>> family_exporters(const SceneDef& scene);

/// Checks before the first frame that every file `exporter` writes for frames first_frame and
/// last_frame (the names differ only in the frame number) lies inside `dir`
/// (check_file_name_inside, output_files.hpp). Throws IoError.
void check_frame_files_inside(const FrameExporter& exporter, const std::filesystem::path& dir, int first_frame,
                              int last_frame);

}  // namespace seiche
