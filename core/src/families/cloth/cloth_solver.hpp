// The cloth material: every cloth of a scene (sheets and OBJ meshes) as particles of the store,
// with its constraints built once and solved every iteration:
//   stretch   XPBD distance constraints on the mesh edges (kernels/distance_constraint.hpp), each
//             iteration first on `stretch_forests` spanning forests of them, solved exactly in
//             linear time (kernels/distance_tree.hpp; the first grows from the pins), then
//             color by color
//   bending   dihedral-angle or isometric hinges, chosen per cloth
//   tethers   long-range attachments to the pinned vertices (optional, per cloth)
// Constraints of all cloths share one colored set per family (parallel Gauss-Seidel). The
// vertices of cloth c are the store particles with ids first_id(c) .. first_id(c) + vertices - 1
// in vertex order, created after the raw and the fluid particles.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "cloth_mesh.hpp"
#include "seiche/frame_metrics.hpp"
#include "seiche/kernels/distance_constraint.hpp"
#include "seiche/kernels/distance_tree.hpp"
#include "seiche/kernels/hinges.hpp"
#include "seiche/kernels/isometric_bending.hpp"
#include "seiche/kernels/packed_positions.hpp"
#include "seiche/kernels/particle_view.hpp"
#include "seiche/kernels/tethers.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

/// The cloths' errors: the run report's "cloth_strain" and "cloth_bending_error".
struct ClothError {
  double strain_mean = 0.0;   ///< mean |l - l0| / l0 over the stretch constraints (edges)
  double strain_max = 0.0;
  double bending_mean = 0.0;  ///< mean |theta - theta0| over the hinges (rad)
  double bending_max = 0.0;
};

/// A cloth's mesh as the scene defines it (a sheet or the OBJ), with its topology. `file` names
/// the scene file in errors. Warnings (degenerate faces) are in mesh.warnings.
struct ClothShape {
  ClothMesh mesh;
  ClothTopology topology;
};
ClothShape build_cloth_shape(const ClothDef& cloth, std::size_t index, const std::string& file);

class ClothSolver {
 public:
  /// Reads or generates every cloth's mesh (SceneError on bad input).
  explicit ClothSolver(const SceneDef& scene);
  ~ClothSolver();

  std::size_t vertex_count() const { return total_vertices_; }
  std::size_t cloth_count() const { return shapes_.size(); }
  const ClothShape& shape(std::size_t c) const { return shapes_[c]; }
  std::int32_t first_id(std::size_t c) const { return first_id_[c]; }

  /// Fills store particles [first, first + vertex_count()) with the cloths' vertices (positions,
  /// velocities, inverse masses, phases, collision radii: half the thickness; ids are set by the
  /// caller as creation indices) and builds the constraints on those rest positions.
  void create(ParticleStore& store, std::size_t first, const kernels::ParticleView& view);

  bool has_bending() const { return dihedral_.size() + isometric_.size() > 0; }
  bool has_dihedral_bending() const { return dihedral_.size() > 0; }
  bool has_tethers() const { return tethers_.groups() > 0; }
  /// Contact distance of cloth c's particles with each other (its thickness).
  float thickness(std::size_t c) const { return scene_cloths_[c].thickness; }
  bool self_collision(std::size_t c) const { return scene_cloths_[c].self_collision; }
  float friction(std::size_t c) const { return scene_cloths_[c].friction; }
  /// Whether vertices u and v of cloth c share a triangle (or are the same vertex).
  bool adjacent(std::size_t c, std::uint32_t u, std::uint32_t v) const;

  void begin_substep();
  bool has_stretch_forests() const { return !forests_.empty(); }
  /// One iteration of the stretch constraints (iteration counts from 0 in each substep), in two
  /// parts: first the forests, on the store's columns; then the colored edges, on the iteration
  /// record (core/src/loop/iteration_record.hpp: its range covers packed_range()).
  void solve_stretch_forests(const kernels::ParticleView& p, float dt);
  void solve_stretch(const kernels::PackedPositions& packed, float dt, int iteration);
  /// One iteration of the bending constraints, on the iteration record.
  void solve_bending(const kernels::PackedPositions& packed, float dt, int iteration);
  /// Every store index the colored constraints (stretch and bending) use.
  kernels::IndexRange packed_range() const;
  void solve_tethers(const kernels::ParticleView& p);
  void remap(std::span<const std::uint32_t> new_index);
  /// The stretch multipliers of the last substep when there are forests (their geometric
  /// stiffness reads them in the next substep), else empty; restored from a checkpoint.
  std::span<const float> stretch_multipliers() const;
  void restore_stretch_multipliers(std::span<const float> saved);

  /// The constraints as built (store indices), for the implicit-Euler reference of the bench.
  const kernels::DistanceConstraints& stretch() const { return stretch_; }
  const kernels::IsometricBending& isometric() const { return isometric_; }

  /// Strain and bending error at positions x.
  ClothError measure(const kernels::ParticleView& p) const;

 private:
  void build_tethers(std::size_t c, std::size_t first, std::span<const std::uint8_t> pinned);

  std::vector<ClothDef> scene_cloths_;
  std::vector<ClothShape> shapes_;
  std::vector<std::int32_t> first_id_;
  std::size_t total_vertices_ = 0;
  std::vector<float> radius_;

  kernels::DistanceConstraints stretch_;
  kernels::Hinges dihedral_;
  kernels::IsometricBending isometric_;
  kernels::Tethers tethers_;  // all cloths' tethers, appended cloth by cloth
  std::vector<kernels::DistanceForest> forests_;  // cloth stretch_forests (kernels/distance_tree.hpp)
  std::vector<float> tension_;  // stretch multipliers of the previous substep
};

}  // namespace seiche
