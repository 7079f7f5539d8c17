// The OpenVDB export of fluid frames: <name>.%04d.vdb (grids "surface", "density", "points",
// "v" as the scene's output section asks) and <name>.%04d.obj (the surface as a mesh).
//
// The layers, lowest first: gather_fluid_particles (the store's fluid particles in id order) ->
// encode_fluid_frame (the files' bytes, from plain arrays: what tests and benchmarks call) ->
// make_vdb_exporter (the FrameExporter a bake runs: encode, then write each file atomically).
// How the surface is built, and why: core/export/src/fluid_surface.hpp.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "seiche/frame_exporter.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

/// What a fluid frame's files hold and how they are stored: scene.output resolved against the
/// scene's fluid (see docs/scene-format.md, "output").
struct FluidExportSettings {
  std::string scene_name = "scene";
  float spacing = 0.02f;     ///< m, the fluid's rest particle spacing (fluids[0].spacing)
  float voxel_size = 0.0f;   ///< m; 0 = automatic: half the spacing. Else in [spacing/4, spacing]
  bool surface = true;       ///< grid "surface": narrow-band level set (half width 3 voxels)
  bool density = true;       ///< grid "density": fog volume, 0 outside to 1 three voxels inside
  bool points = false;       ///< grid "points": VDB Points with attributes "v" and "id"
  bool velocity = false;     ///< grid "v": velocity on the surface band, for motion blur
  bool mesh = false;         ///< the .obj surface mesh
  bool anisotropic = false;  ///< Yu & Turk 2013 ellipsoids instead of the density surface
  bool half_float = false;   ///< float grids and the points' "v" stored as 16-bit halves
  std::string compression = "blosc";  ///< "blosc", "zip" or "none"

  bool any_vdb_grid() const { return surface || density || points || velocity; }
  /// The voxel size in use (m): voxel_size, or half the spacing when it is 0.
  float resolved_voxel_size() const;
};

/// The settings scene.output asks for. Throws SceneError (json path "output.voxel_size",
/// "output.compression" or "fluids") when a value cannot be used.
FluidExportSettings fluid_export_settings(const SceneDef& scene);

/// Throws std::invalid_argument naming the setting when `settings` cannot be used: spacing not
/// > 0, voxel size outside [spacing/4, spacing] (finer adds no detail the particles hold;
/// coarser loses particles between voxels), unknown compression, empty scene name.
void check_fluid_export_settings(const FluidExportSettings& settings);

/// Fluid particles (SoA, m and m/s) in id order.
struct FluidParticles {
  std::vector<float> x, y, z, vx, vy, vz;
  std::vector<std::int32_t> id;
  std::size_t size() const { return x.size(); }
};

/// The particles of `store` whose phase material is Fluid, sorted by id.
FluidParticles gather_fluid_particles(const ParticleStore& store);

struct FrameStamp {
  int frame = 1;      ///< 1-based
  double time = 0.0;  ///< s, simulated time at the end of the frame
};

/// The bytes of one frame's files: vdb is empty when no grid is asked, obj when no mesh is.
struct EncodedFluidFrame {
  std::string vdb, obj;
};

/// Encodes one frame. The .vdb holds the asked grids in the order surface, density, v, points,
/// named so, with file metadata seiche_scene, seiche_frame, seiche_time, seiche_version,
/// seiche_spacing and seiche_voxel_size; its bytes depend only on the particles, the settings
/// and the stamp (not on the thread count, not on the time of day). Throws std::invalid_argument
/// (check_fluid_export_settings, or arrays of different lengths).
EncodedFluidFrame encode_fluid_frame(const FluidParticles& particles,
                                     const FluidExportSettings& settings, FrameStamp stamp);

/// The exporter for what scene.output asks for; null when it asks for no .vdb and no mesh, or
/// when the scene has no fluid. Throws SceneError as fluid_export_settings does.
std::unique_ptr<FrameExporter> make_vdb_exporter(const SceneDef& scene);

}  // namespace seiche
