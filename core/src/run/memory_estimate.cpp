// The memory estimate and the work bound of a scene (the model is written in memory_estimate.hpp).
#include "seiche/memory_estimate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>

#include "../families/cloth/cloth_mesh.hpp"
#include "../families/fluid_body/body_boundary.hpp"
#include "../families/rigid/body_mesh.hpp"
#include "../families/rigid/body_shape.hpp"
#include "../families/lattice.hpp"
#include "../families/shape/shape_sites.hpp"
#include "seiche/aligned_column.hpp"
#include "seiche/scene_loader.hpp"

namespace seiche {

namespace {

constexpr std::uint64_t kBuiltInColumns = 13;  // x y z px py pz vx vy vz w phase id radius
constexpr std::uint64_t kReorderSpares = 3;    // one per element type
constexpr std::uint64_t kFluidColumns = 2;     // density, lambda
constexpr std::uint64_t kVorticityColumns = 3; // omega_x omega_y omega_z
// A shape's cluster member: its store index, rest offset and mass share; a member of overlapping
// region clusters also its goal (3 doubles) and its entry in its particle's list.
constexpr std::uint64_t kShapeBytesPerMember = 20;
constexpr std::uint64_t kRegionBytesPerMember = 48;
constexpr std::uint64_t kGridBytesPerParticle = 13;  // cell key, sorted order, in_grid flag, offset
constexpr std::uint64_t kMaxGridCells = std::uint64_t(1) << 24;  // neighbor::make_grid_spec's cap
constexpr std::uint64_t kMaxSdfSamples = std::uint64_t(1) << 26; // build_mesh_sdf's cap
constexpr std::uint64_t kSdfBytesPerSample = 8;

std::uint64_t column_bytes(std::size_t n) { return padded_count(n) * 4; }

// The particles of a cloth: a sheet's grid, or an OBJ once loaded.
std::pair<std::uint64_t, std::uint64_t> cloth_vertices_and_triangles(const ClothDef& c) {
  if (c.loaded_mesh) return {c.loaded_mesh->vertex_count(), c.loaded_mesh->triangles.size()};
  if (c.sheet) {
    const std::uint64_t a = std::uint64_t(std::max(c.sheet->resolution[0], 0));
    const std::uint64_t b = std::uint64_t(std::max(c.sheet->resolution[1], 0));
    return {a * b, 2 * (a > 0 ? a - 1 : 0) * (b > 0 ? b - 1 : 0)};
  }
  return {0, 0};
}

std::uint64_t sdf_samples(const ColliderDef& c) {
  if (!c.loaded_mesh || c.loaded_mesh->positions.empty()) return 0;
  Vec3 lo = c.loaded_mesh->positions[0], hi = lo;
  for (const Vec3& p : c.loaded_mesh->positions)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  const float extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  const double voxel = c.voxel_size > 0.0f ? c.voxel_size : std::max(extent / 64.0, 1e-6);
  double samples = 1.0;
  for (int a = 0; a < 3; ++a) samples *= std::ceil((hi[a] - lo[a]) / voxel) + 10.0;  // + the 4-voxel band
  return std::uint64_t(std::min(samples, double(kMaxSdfSamples)));
}

// A mesh body's field (rigid/body_solid.cpp): a voxel of 1/64 of the body-frame mesh's largest
// extent, a band of 4 voxels, as build_mesh_sdf lays it out.
std::uint64_t body_sdf_samples(const rigid::BodyMesh& mesh) {
  if (mesh.vertices.empty()) return 0;
  rigid::Vec3d lo = mesh.vertices[0], hi = lo;
  for (const rigid::Vec3d& v : mesh.vertices) {
    lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
    hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
  }
  const double span[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
  const double voxel = std::max(std::max({span[0], span[1], span[2]}) / 64.0, 1e-6);
  double samples = 1.0;
  for (const double a : span) samples *= std::max(1.0, std::ceil((a + 8.0 * voxel) / voxel * (1.0 - 1e-6))) + 1.0;
  return std::uint64_t(std::min(samples, double(kMaxSdfSamples)));
}

// The key that sizes body `def`: its size for a box, its radius for a sphere or a capsule, its
// mesh's scale.
const char* body_size_key(const RigidBodyDef& def) {
  switch (rigid::body_shape_of(def.shape)) {
    case rigid::BodyShape::Box: return "size";
    case rigid::BodyShape::Mesh: return "mesh.scale";
    default: return "radius";
  }
}

// The coupling of the fluid with rigid bodies and shapes (families/fluid_body/): the bodies'
// boundary sites and their grids, the bodies' mesh fields, the fluid-shape pairs and the per-fluid
// particle arrays.
void add_fluid_coupling(const SceneDef& scene, MemoryEstimate& e) {
  for (std::size_t k = 0; k < scene.rigid_bodies.size(); ++k) {
    const RigidBodyDef& def = scene.rigid_bodies[k];
    if (def.loaded_mesh && rigid::body_shape_of(def.shape) == rigid::BodyShape::Mesh) {
      const std::uint64_t samples = body_sdf_samples(*def.loaded_mesh);
      e.items.push_back({fmt::format("rigid_bodies[{}].mesh.file", k),
                         fmt::format("rigid_bodies[{}] (distance field of {} samples)", k, samples),
                         samples * kSdfBytesPerSample});
    }
  }
  if (scene.fluids.empty() || (scene.rigid_bodies.empty() && scene.shapes.empty())) return;
  const FluidDef& fluid = scene.fluids[0];
  const double spacing = fluid.spacing, h = double(fluid.kernel_radius) * spacing;
  for (std::size_t k = 0; k < scene.rigid_bodies.size(); ++k) {
    const RigidBodyDef& def = scene.rigid_bodies[k];
    if (rigid::body_shape_of(def.shape) == rigid::BodyShape::Mesh && !def.loaded_mesh) continue;  // not read yet
    const rigid::ShapeDims dims = rigid::body_shape_def(def);
    const double extent = rigid::mass_properties(dims).extent;
    const double sites = fluid_body::boundary_site_bound(dims, extent, spacing, h);
    const double cells = fluid_body::boundary_grid_cell_bound(dims, extent, h);
    const double bytes = sites * double(kBoundaryBytesPerSite) + cells * double(kBoundaryBytesPerCell);
    e.items.push_back({fmt::format("rigid_bodies[{}].{}", k, body_size_key(def)),
                       fmt::format("rigid_bodies[{}] (fluid boundary, at most {:.0f} sites)", k, sites),
                       std::uint64_t(std::min(bytes, 1.8e19))});
  }
  const double neighbors = 2.0 * 4.0 / 3.0 * std::numbers::pi * std::pow(double(fluid.kernel_radius), 3.0);
  for (std::size_t k = 0; k < scene.shapes.size(); ++k) {
    const double particles = double(shape_site_count(scene.shapes[k]));
    const double bytes = particles * (double(kShapeBoundaryBytesPerParticle) + neighbors * double(kFluidShapeBytesPerPair));
    e.items.push_back({fmt::format("shapes[{}].spacing", k),
                       fmt::format("shapes[{}] (fluid pairs, at most {:.0f})", k, particles * neighbors),
                       std::uint64_t(bytes)});
  }
  std::uint64_t fluid_particles = 0;
  for (const FluidDef& f : scene.fluids) fluid_particles += lattice_size(f.box, f.spacing);
  e.items.push_back({"fluids[0].spacing",
                     fmt::format("fluid boundary per fluid particle ({} particles)", fluid_particles),
                     fluid_particles * (kCouplingBytesPerFluidParticle +
                                        (scene.shapes.empty() ? 0 : kFluidShapeBytesPerFluidParticle))});
}

}  // namespace

std::uint64_t MemoryEstimate::total() const {
  std::uint64_t sum = kProcessBytes;
  for (const Item& i : items) sum += i.bytes;
  return sum;
}

const MemoryEstimate::Item& MemoryEstimate::largest() const {
  return *std::max_element(items.begin(), items.end(),
                           [](const Item& a, const Item& b) { return a.bytes < b.bytes; });
}

std::string MemoryEstimate::describe() const {
  std::vector<const Item*> sorted;
  for (const Item& i : items) sorted.push_back(&i);
  std::stable_sort(sorted.begin(), sorted.end(), [](const Item* a, const Item* b) { return a->bytes > b->bytes; });
  std::string parts;
  for (std::size_t k = 0; k < sorted.size() && k < 3; ++k)
    parts += fmt::format("{}{}: {}", k ? "; " : "", sorted[k]->what, format_memory_size(sorted[k]->bytes));
  return fmt::format("{} ({})", format_memory_size(total()), parts);
}

std::size_t scene_particle_count(const SceneDef& scene) {
  std::size_t n = scene.particles.size();
  for (const FluidDef& f : scene.fluids) n += lattice_size(f.box, f.spacing);
  for (const ShapeDef& s : scene.shapes) n += shape_site_count(s);
  for (const ClothDef& c : scene.cloths) n += cloth_vertices_and_triangles(c).first;
  return n;
}

MemoryEstimate estimate_scene_memory(const SceneDef& scene) {
  MemoryEstimate e;
  const std::uint64_t n = scene_particle_count(scene);
  e.particles = n;
  bool vorticity = false;
  for (const FluidDef& f : scene.fluids) vorticity = vorticity || f.vorticity > 0.0f;

  std::uint64_t columns = kBuiltInColumns + kReorderSpares;
  if (!scene.fluids.empty()) columns += kFluidColumns + (vorticity ? kVorticityColumns : 0);
  e.particle_store = columns * column_bytes(n);
  // A frame's particle files, encoded together (particle_files.hpp).
  const std::uint64_t export_bytes = (scene.output.particles_ply ? kExportBytesPerParticle : 0) +
                                     (scene.output.particles_vtp ? kVtpExportBytesPerParticle : 0);
  e.items.push_back({"", fmt::format("particle store ({} particles)", n), e.particle_store + export_bytes * n});

  for (std::size_t k = 0; k < scene.fluids.size(); ++k) {
    const FluidDef& f = scene.fluids[k];
    const double count = double(lattice_size(f.box, f.spacing));
    const double neighbors = 2.0 * 4.0 / 3.0 * std::numbers::pi * std::pow(double(f.kernel_radius), 3.0);
    std::uint64_t bytes = std::uint64_t(count * (4.0 * neighbors + kGridBytesPerParticle));
    if (k == 0) {  // one grid for every fluid: cells of the kernel radius over the domain, capped
      const double h = std::max(double(f.kernel_radius) * f.spacing, 1e-9);
      double cells = 1.0;
      for (int a = 0; a < 3; ++a) cells *= std::ceil((scene.domain.max[a] - scene.domain.min[a]) / h) + 2.0;
      bytes += 4 * std::uint64_t(std::min(cells, double(kMaxGridCells)));
    }
    e.items.push_back({fmt::format("fluids[{}].spacing", k),
                       fmt::format("fluids[{}] ({:.0f} particles, neighbor lists)", k, count), bytes});
  }
  for (std::size_t k = 0; k < scene.cloths.size(); ++k) {
    const ClothDef& c = scene.cloths[k];
    const auto [vertices, triangles] = cloth_vertices_and_triangles(c);
    const std::uint64_t bytes = vertices * (kClothBytesPerVertex + (c.self_collision ? kSelfContactBytesPerVertex : 0)) +
                                triangles * kClothBytesPerTriangle;
    e.items.push_back({fmt::format("cloths[{}].{}", k, c.sheet ? "sheet.resolution" : "mesh.file"),
                       fmt::format("cloths[{}] ({} vertices, {} triangles)", k, vertices, triangles), bytes});
  }
  for (std::size_t k = 0; k < scene.shapes.size(); ++k) {
    const ShapeDef& s = scene.shapes[k];
    const bool regions = s.cluster_half_width > 0;
    // A particle is in one cluster, or in (2 + 1/h)^3 region clusters of half-width h on average
    // inside the body.
    const double per_particle = regions ? std::pow(2.0 + 1.0 / s.cluster_half_width, 3.0) : 1.0;
    const double members = double(shape_site_count(s)) * per_particle;
    e.items.push_back({fmt::format("shapes[{}].{}", k, regions ? "cluster_half_width" : "spacing"),
                       fmt::format("shapes[{}] ({:.0f} cluster members)", k, members),
                       std::uint64_t(members * double(regions ? kRegionBytesPerMember : kShapeBytesPerMember))});
  }
  add_fluid_coupling(scene, e);
  for (std::size_t k = 0; k < scene.colliders.size(); ++k) {
    const std::uint64_t samples = sdf_samples(scene.colliders[k]);
    if (samples > 0)
      e.items.push_back({fmt::format("colliders[{}].mesh.voxel_size", k),
                         fmt::format("colliders[{}] (distance field of {} samples)", k, samples),
                         samples * kSdfBytesPerSample});
  }
  return e;
}

std::optional<std::uint64_t> available_memory() {
  std::optional<std::uint64_t> available;
  std::ifstream meminfo("/proc/meminfo");
  for (std::string key; meminfo >> key;) {
    std::uint64_t kib = 0;
    std::string unit;
    if (!(meminfo >> kib >> unit)) break;
    if (key == "MemAvailable:") {
      available = kib * 1024;
      break;
    }
  }
  // A cgroup (v2) limit: what this process's group may still take.
  std::uint64_t limit = 0, current = 0;
  std::ifstream max_file("/sys/fs/cgroup/memory.max"), current_file("/sys/fs/cgroup/memory.current");
  if ((max_file >> limit) && (current_file >> current)) {
    const std::uint64_t left = limit > current ? limit - current : 0;
    available = available ? std::min(*available, left) : left;
  }
  return available;
}

std::optional<std::uint64_t> parse_memory_size(std::string_view text) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || !(value > 0.0)) return std::nullopt;
  std::string_view unit(end, std::size_t(text.data() + text.size() - end));
  double scale = 1.0;
  if (!unit.empty()) {
    constexpr std::string_view prefixes = "KMGT";
    const std::size_t p = prefixes.find(char(std::toupper(static_cast<unsigned char>(unit[0]))));
    if (p != std::string_view::npos) {
      scale = std::pow(1024.0, double(p + 1));
      unit.remove_prefix(1);
      if (unit == "i" || unit == "iB" || unit == "B") unit = {};
    } else if (unit == "B") {
      unit = {};
    }
  }
  const double bytes = value * scale;
  if (!unit.empty() || !(bytes >= 1.0) || bytes > 1.8e19) return std::nullopt;
  return std::uint64_t(bytes);
}

std::string format_memory_size(std::uint64_t bytes) {
  constexpr const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  double v = double(bytes);
  int u = 0;
  while (v >= 1024.0 && u < 6) v /= 1024.0, ++u;
  return u == 0 ? fmt::format("{} B", bytes) : fmt::format("{:.{}f} {}", v, v < 10.0 ? 1 : 0, units[u]);
}

void check_scene_memory(const SceneDef& scene, const std::string& source, std::optional<std::uint64_t> max_memory) {
  const MemoryEstimate e = estimate_scene_memory(scene);
  const std::uint64_t need = e.total();
  const std::optional<std::uint64_t> available = available_memory();
  const bool over_limit = max_memory && need > *max_memory;
  const bool over_machine = available && need > *available;
  if (!over_limit && !over_machine) return;
  const std::string limit = over_limit ? fmt::format("the --max-memory limit of {}", format_memory_size(*max_memory))
                                       : fmt::format("the memory this machine has available ({})",
                                                     format_memory_size(*available));
  throw SceneError(source, e.largest().json_path.empty() ? std::string("(scene)") : e.largest().json_path,
                   fmt::format("the scene needs about {}, more than {}: make it smaller (fewer particles, a coarser "
                               "spacing or resolution){}",
                               e.describe(), limit, over_limit ? " or raise --max-memory" : ""));
}

void check_scene_work(const SceneDef& scene, const std::string& source, bool allow_huge_work) {
  if (allow_huge_work) return;
  const SolverDef& s = scene.solver;
  const bool tolerance = !scene.fluids.empty() && s.density_tolerance > 0.0f;
  const double iterations = double(s.substeps) * std::max(s.iterations, tolerance ? s.max_iterations : 0);
  const double particles = double(estimate_scene_memory(scene).particles);
  const std::string what = fmt::format("substeps {} x iterations {}{}", s.substeps, s.iterations,
                                       tolerance ? fmt::format(" (up to max_iterations {})", s.max_iterations) : "");
  if (iterations > kMaxIterationsPerFrame)
    throw SceneError(source, "solver.substeps",
                     fmt::format("{} = {:.3g} solver iterations per frame, more than the bound of {:.0e}: lower them, "
                                 "or pass --allow-huge-work to run it anyway",
                                 what, iterations, kMaxIterationsPerFrame));
  if (iterations * particles > kMaxParticleIterationsPerFrame)
    throw SceneError(source, "solver.substeps",
                     fmt::format("{} x {:.0f} particles = {:.3g} particle-iterations per frame, more than the bound of "
                                 "{:.0e} (hours per frame): lower them, or pass --allow-huge-work to run it anyway",
                                 what, particles, iterations * particles, kMaxParticleIterationsPerFrame));
}

}  // namespace seiche
