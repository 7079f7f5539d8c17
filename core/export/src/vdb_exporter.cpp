// The fluid frame exporter: particles in id order -> surface level set (fluid_surface, or the
// anisotropic surface) -> density fog (a copy of the surface through sdfToFogVolume) ->
// velocity and points grids -> one reproducible .vdb (vdb_file) and the .obj mesh (obj_mesh),
// each written atomically.
#include "seiche/export/vdb_exporter.hpp"

#include <fmt/format.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetUtil.h>

#include <cmath>
#include <optional>
#include <stdexcept>
#include <utility>

#include "anisotropic_surface.hpp"
#include "fluid_points.hpp"
#include "fluid_surface.hpp"
#include "obj_mesh.hpp"
#include "seiche/output_files.hpp"
#include "seiche/scene_loader.hpp"
#include "vdb_file.hpp"

namespace seiche {
namespace {

constexpr float kHalfWidth = 3.0f;  // voxels: OpenVDB's standard narrow band

struct SettingsProblem {
  std::string json_path, problem;
};

std::optional<SettingsProblem> find_problem(const FluidExportSettings& s) {
  if (s.scene_name.empty())
    return SettingsProblem{"name", "the scene name is empty (it names the frame files)"};
  if (!(std::isfinite(s.spacing) && s.spacing > 0.0f))
    return SettingsProblem{"fluids[0].spacing",
                           fmt::format("the fluid spacing must be > 0 m, got {}", s.spacing)};
  if (!(std::isfinite(s.voxel_size) && s.voxel_size >= 0.0f))
    return SettingsProblem{"output.voxel_size",
                           fmt::format("must be >= 0 m (0 = automatic), got {}", s.voxel_size)};
  const float dx = s.resolved_voxel_size(), lo = 0.25f * s.spacing, hi = s.spacing;
  if (dx < lo)
    return SettingsProblem{"output.voxel_size",
                           fmt::format("{} m is finer than a quarter of the fluid spacing {} m: "
                                       "the particles hold no detail that "
                                       "small; use at least {} m (0 = automatic: half the spacing)",
                                       dx, s.spacing, lo)};
  if (dx > hi)
    return SettingsProblem{"output.voxel_size",
                           fmt::format("{} m is coarser than the fluid spacing {} m: particles "
                                       "would fall between voxels; use at "
                                       "most {} m (0 = automatic: half the spacing)",
                                       dx, s.spacing, hi)};
  if (s.compression != "blosc" && s.compression != "zip" && s.compression != "none")
    return SettingsProblem{
        "output.compression",
        fmt::format("\"{}\" is not one of \"blosc\", \"zip\", \"none\"", s.compression)};
  return std::nullopt;
}

/// Store indices of the fluid particles, in id order.
std::vector<std::uint32_t> fluid_indices_by_id(const ParticleStore& store) {
  std::vector<std::uint32_t> fluid;
  fluid.reserve(store.size());
  for (const std::uint32_t i : store.index_of_id())
    if (phase_material(store.phase[i]) == Material::Fluid) fluid.push_back(i);
  return fluid;
}

void check_lengths(const FluidParticles& p) {
  const std::size_t n = p.x.size();
  if (p.y.size() != n || p.z.size() != n || p.vx.size() != n || p.vy.size() != n ||
      p.vz.size() != n || p.id.size() != n)
    throw std::invalid_argument("encode_fluid_frame: the particle arrays differ in length");
}

openvdb::FloatGrid::Ptr anisotropic_surface(const FluidParticles& p, const FluidExportSettings& s) {
  std::vector<openvdb::Vec3f> positions(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) positions[i] = openvdb::Vec3f(p.x[i], p.y[i], p.z[i]);
  // The anisotropic surface is calibrated so that, given the spacing as the interior particle
  // radius, a resting block's surface lies on the block's faces, as the density surface does.
  return exporting::anisotropic_level_set(positions, s.spacing, s.spacing,
                                          exporting::voxel_transform(s.resolved_voxel_size()),
                                          kHalfWidth);
}

class VdbExporter final : public FrameExporter {
 public:
  explicit VdbExporter(FluidExportSettings settings) : settings_(std::move(settings)) {}

  std::string name() const override { return "vdb"; }

  std::vector<std::filesystem::path> files(int frame) const override {
    std::vector<std::filesystem::path> out;
    if (settings_.any_vdb_grid())
      out.emplace_back(frame_file_name(settings_.scene_name, frame, "vdb"));
    if (settings_.mesh) out.emplace_back(frame_file_name(settings_.scene_name, frame, "obj"));
    return out;
  }

  std::uint64_t write_frame(const FrameView& frame, const std::filesystem::path& dir) override {
    const EncodedFluidFrame encoded = encode_fluid_frame(gather_fluid_particles(frame.particles),
                                                         settings_, {frame.frame, frame.time});
    std::uint64_t bytes = 0;
    if (settings_.any_vdb_grid()) {
      write_file_atomically(dir / frame_file_name(settings_.scene_name, frame.frame, "vdb"),
                            encoded.vdb);
      bytes += encoded.vdb.size();
    }
    if (settings_.mesh) {
      write_file_atomically(dir / frame_file_name(settings_.scene_name, frame.frame, "obj"),
                            encoded.obj);
      bytes += encoded.obj.size();
    }
    return bytes;
  }

 private:
  FluidExportSettings settings_;
};

}  // namespace

float FluidExportSettings::resolved_voxel_size() const {
  return voxel_size > 0.0f ? voxel_size : 0.5f * spacing;
}

void check_fluid_export_settings(const FluidExportSettings& settings) {
  if (const auto p = find_problem(settings))
    throw std::invalid_argument(p->json_path + ": " + p->problem);
}

FluidExportSettings fluid_export_settings(const SceneDef& scene) {
  const std::string where = fmt::format("scene \"{}\"", scene.name);
  if (scene.fluids.empty()) throw SceneError(where, "fluids", "the fluid export needs a fluid");
  const OutputDef& o = scene.output;
  FluidExportSettings s;
  s.scene_name = scene.name;
  s.spacing = scene.fluids[0].spacing;
  s.voxel_size = o.voxel_size;
  s.surface = o.vdb_surface;
  s.density = o.vdb_density;
  s.points = o.vdb_points;
  s.velocity = o.vdb_velocity;
  s.mesh = o.mesh;
  s.anisotropic = o.anisotropic;
  s.half_float = o.half_float;
  s.compression = o.compression;
  if (const auto p = find_problem(s)) throw SceneError(where, p->json_path, p->problem);
  return s;
}

FluidParticles gather_fluid_particles(const ParticleStore& store) {
  const std::vector<std::uint32_t> order = fluid_indices_by_id(store);
  FluidParticles p;
  const std::size_t n = order.size();
  p.x.resize(n), p.y.resize(n), p.z.resize(n), p.vx.resize(n), p.vy.resize(n), p.vz.resize(n),
      p.id.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t i = order[k];
    p.x[k] = store.x[i], p.y[k] = store.y[i], p.z[k] = store.z[i];
    p.vx[k] = store.vx[i], p.vy[k] = store.vy[i], p.vz[k] = store.vz[i];
    p.id[k] = store.id[i];
  }
  return p;
}

EncodedFluidFrame encode_fluid_frame(const FluidParticles& p, const FluidExportSettings& s,
                                     FrameStamp stamp) {
  check_fluid_export_settings(s);
  check_lengths(p);
  exporting::initialize_openvdb();
  const float dx = s.resolved_voxel_size();
  const std::string creator = fmt::format("Seiche {}", SEICHE_VERSION);

  openvdb::FloatGrid::Ptr surface;
  openvdb::Vec3SGrid::Ptr velocity;
  if (s.surface || s.density || s.velocity || s.mesh) {
    const exporting::SurfaceShape shape{s.spacing, dx, kHalfWidth};
    const bool isotropic_surface = !s.anisotropic && (s.surface || s.density || s.mesh);
    // The velocity grid comes from the isotropic pass (on its band), anisotropic surface or not.
    if (isotropic_surface || s.velocity) {
      auto grids = exporting::fluid_surface(p.x, p.y, p.z, p.vx, p.vy, p.vz, shape, s.velocity);
      surface = std::move(grids.surface);
      velocity = std::move(grids.velocity);
    }
    if (s.anisotropic && (s.surface || s.density || s.mesh)) surface = anisotropic_surface(p, s);
  }

  EncodedFluidFrame out;
  if (s.any_vdb_grid()) {
    openvdb::GridCPtrVec grids;
    auto add_grid = [&](const openvdb::GridBase::Ptr& grid, const char* name) {
      grid->setName(name);
      grid->setCreator(creator);
      grid->setSaveFloatAsHalf(s.half_float);
      grids.push_back(grid);
    };
    if (s.surface) add_grid(surface, "surface");
    if (s.density) {
      openvdb::FloatGrid::Ptr fog = surface->deepCopy();
      openvdb::tools::sdfToFogVolume(*fog);
      add_grid(fog, "density");
    }
    if (s.velocity) add_grid(velocity, "v");
    if (s.points) {
      const exporting::FluidPointArrays arrays{p.x, p.y, p.z, p.vx, p.vy, p.vz, p.id};
      auto points = exporting::fluid_points_grid(
          arrays, exporting::kPointsVoxelPerSpacing * s.spacing, s.half_float);
      points->setCreator(creator);
      grids.push_back(points);
    }
    openvdb::MetaMap meta;
    meta.insertMeta("seiche_scene", openvdb::StringMetadata(s.scene_name));
    meta.insertMeta("seiche_frame", openvdb::Int32Metadata(stamp.frame));
    meta.insertMeta("seiche_time", openvdb::DoubleMetadata(stamp.time));
    meta.insertMeta("seiche_version", openvdb::StringMetadata(SEICHE_VERSION));
    meta.insertMeta("seiche_spacing", openvdb::FloatMetadata(s.spacing));
    meta.insertMeta("seiche_voxel_size", openvdb::FloatMetadata(dx));
    out.vdb =
        exporting::encode_vdb_file(grids, meta, exporting::parse_vdb_compression(s.compression),
                                   fmt::format("{}/{}.vdb", s.scene_name, stamp.frame));
  }
  if (s.mesh)
    out.obj = exporting::encode_obj_mesh(
        *surface,
        fmt::format("{} frame {} (t = {} s), {}", s.scene_name, stamp.frame, stamp.time, creator));
  return out;
}

std::unique_ptr<FrameExporter> make_vdb_exporter(const SceneDef& scene) {
  if (!scene.output.any_vdb() && !scene.output.mesh) return nullptr;
  if (scene.fluids.empty()) return nullptr;
  return std::make_unique<VdbExporter>(fluid_export_settings(scene));
}

}  // namespace seiche
