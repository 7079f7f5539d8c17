// How much memory a scene needs, estimated from its definition before anything large is
// allocated, and the bounds a run checks before it starts:
//   memory  the estimate must fit in the machine's available memory (MemAvailable, and a cgroup
//           limit where one is set) and in --max-memory when given; else exit 2 with both numbers
//   work    substeps x iterations per frame <= kMaxIterationsPerFrame and that times the particle
//           count <= kMaxParticleIterationsPerFrame; else exit 2 unless --allow-huge-work
//
// The estimate, per item of the scene (the figures are bounds or were measured; see
// docs/design.md, "Memory"):
//   particle store   every particle: the store's columns (ParticleStore: 13 built-in, the fluid's
//                    2 and vorticity's 3 scratch columns) and the 3 reorder spares, 4 bytes
//                    each, padded like AlignedColumn; plus a frame's export buffer
//                    (kExportBytesPerParticle, the PLY's 28 bytes rounded up, and
//                    kVtpExportBytesPerParticle, the .vtp's 36, for the formats the scene writes)
//   fluid            neighbor lists at a bound of twice the rest lattice's neighbor count,
//                    2 x 4/3 pi (kernel_radius / spacing)^3, 4 bytes each, plus the grid's 13 bytes
//                    per particle and its cell table (at most 2^24 cells, 4 bytes each)
//   cloth            kClothBytesPerVertex and kClothBytesPerTriangle (the mesh as read and as
//                    simulated, topology, constraints, colors, forests, output), plus
//                    kSelfContactBytesPerVertex with self_collision: measured on 512^2 and 1024^2
//                    sheets, which they bound from above by about 10 %
//   shapes           20 bytes per cluster member (index, rest offset, mass share), one per particle;
//                    48 per member of region clusters, (2 + 1/h)^3 per particle at half-width h
//   mesh colliders   the signed distance field, 8 bytes per sample (at most 2^26 samples)
//   mesh bodies      the body's signed distance field (a voxel of 1/64 of its largest extent, a
//                    band of 4 voxels), 8 bytes per sample
//   fluid coupling   where the fluid meets bodies or shapes (families/fluid_body/): per body, its
//                    boundary sites (fluid_body::boundary_site_bound) at kBoundaryBytesPerSite
//                    and its grid's cells of h over the solid's width per axis
//                    (fluid_body::boundary_grid_cell_bound) at kBoundaryBytesPerCell; per shape particle kShapeBoundaryBytesPerParticle and
//                    its fluid pairs at the fluid's neighbor bound (2 x 4/3 pi kernel_radius^3)
//                    at kFluidShapeBytesPerPair; per fluid particle kCouplingBytesPerFluidParticle
//                    (and kFluidShapeBytesPerFluidParticle with shapes)
//   process          kProcessBytes (code, libraries, thread pools)
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "seiche/scene.hpp"

namespace seiche {

inline constexpr std::uint64_t kProcessBytes = 40ull << 20;
inline constexpr std::uint64_t kExportBytesPerParticle = 32;
inline constexpr std::uint64_t kVtpExportBytesPerParticle = 36;
inline constexpr std::uint64_t kClothBytesPerVertex = 550;
inline constexpr std::uint64_t kClothBytesPerTriangle = 300;
inline constexpr std::uint64_t kSelfContactBytesPerVertex = 900;
/// A body's boundary site: its body-frame position (24) and volume (8), the sampled copy before
/// the grid sort (24) and the sort's cursor (4).
inline constexpr std::uint64_t kBoundaryBytesPerSite = 60;
/// A cell of a body's boundary grid: its start and the sort's cursor.
inline constexpr std::uint64_t kBoundaryBytesPerCell = 8;
/// Per fluid particle with coupling: the boundary's (g_b, rho_b) (16) and the kept p_i (24), the
/// error probe's rho_b (8) and its row (16).
inline constexpr std::uint64_t kCouplingBytesPerFluidParticle = 64;
/// Per fluid particle with shapes: the fluid-major pairs' start and the sort's cursor.
inline constexpr std::uint64_t kFluidShapeBytesPerFluidParticle = 8;
/// Per shape particle: its volume psi_b (8), its index and its pairs' start (8).
inline constexpr std::uint64_t kShapeBoundaryBytesPerParticle = 16;
/// Per fluid-shape pair: fluid and shape indices (8), psi (8), gradient (24), fluid-major entry (4).
inline constexpr std::uint64_t kFluidShapeBytesPerPair = 44;
/// Solver iterations (substeps x iterations, or max_iterations where density_tolerance lets a
/// substep run that many) per frame: past this, float32 rounding noise dominates long before, and
/// each iteration's fixed cost alone takes minutes per frame.
inline constexpr double kMaxIterationsPerFrame = 1e5;
/// Particle-iterations per frame: about 2.5 hours of a 2-core machine per frame at ~90 ns each.
inline constexpr double kMaxParticleIterationsPerFrame = 1e11;

struct MemoryEstimate {
  struct Item {
    std::string json_path;  ///< what the scene says that costs it: "fluids[0].spacing"
    std::string what;       ///< "fluid: 50k particles, neighbor lists"
    std::uint64_t bytes = 0;
  };
  std::size_t particles = 0;
  std::uint64_t particle_store = 0;  ///< the ParticleStore's bytes() once every column is enabled
  std::vector<Item> items;           ///< the store first, then each object of the scene
  std::uint64_t total() const;
  /// The largest item (the store when the scene has nothing else).
  const Item& largest() const;
  /// "2.1 GiB (particle store 1.2 GiB; cloths[0]: 0.9 GiB ...)", the three largest items.
  std::string describe() const;
};

/// The particles `scene` creates: fluid and shape lattices, raw particles, cloth vertices (a
/// sheet's grid; an OBJ cloth's once loaded, else 0).
std::size_t scene_particle_count(const SceneDef& scene);

/// The estimate of `scene`'s memory. OBJ meshes count once they are loaded (SceneDef's
/// loaded_mesh): before, only their particles' store is left out.
MemoryEstimate estimate_scene_memory(const SceneDef& scene);

/// Bytes this process can still allocate without swapping: /proc/meminfo's MemAvailable, less
/// where a cgroup (v2) memory.max leaves less; nullopt when neither can be read.
std::optional<std::uint64_t> available_memory();

/// "512M", "2G", "1.5GiB", "1000000" (bytes): a size with an optional K, M, G or T (powers of
/// 1024) and an optional "B"/"iB"; nullopt when not such a size or not positive.
std::optional<std::uint64_t> parse_memory_size(std::string_view text);
/// "1.5 GiB", "300 MiB", "12 KiB", "100 B".
std::string format_memory_size(std::uint64_t bytes);

/// Throws SceneError (naming `source` and the largest item's JSON path) when the estimate is over
/// the available memory or `max_memory` (when given): the message gives the estimate, its largest
/// items and the limit.
void check_scene_memory(const SceneDef& scene, const std::string& source,
                        std::optional<std::uint64_t> max_memory);

/// Throws SceneError (naming `source` and solver.substeps) when the scene's work per frame is
/// past kMaxIterationsPerFrame or kMaxParticleIterationsPerFrame, unless `allow_huge_work`.
void check_scene_work(const SceneDef& scene, const std::string& source, bool allow_huge_work);

}  // namespace seiche
