// The particle store: one structure-of-arrays for all particles of all materials.
//
// State columns (always present, kept across substeps, moved by reorder()):
//   x y z      position at the start of the substep (m)
//   px py pz   predicted position, the unknowns of the constraint solve (m)
//   vx vy vz   velocity (m/s)
//   w          inverse mass (1/kg); 0 = pinned
//   phase      material (low 8 bits) and object/group index (high 24 bits)
//   id         creation index: the stable order of every export
// Optional scratch columns (allocated only when a pass needs them, recomputed every substep,
// so reorder() leaves them alone): density, lambda (fluid), omega x/y/z (vorticity).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "seiche/aligned_column.hpp"
#include "seiche/kernels/particle_view.hpp"
#include "seiche/kernels/phase.hpp"

namespace seiche {

using FloatColumn = AlignedColumn<float>;

class ParticleStore {
 public:
  std::size_t size() const { return size_; }
  /// Resizes every allocated column; new particles are zero (w = 0: pinned until set).
  void resize(std::size_t n);

  FloatColumn x, y, z;
  FloatColumn px, py, pz;
  FloatColumn vx, vy, vz;
  FloatColumn w;
  AlignedColumn<std::uint32_t> phase;
  AlignedColumn<std::int32_t> id;

  // Optional scratch columns.
  FloatColumn density, lambda;
  FloatColumn omega_x, omega_y, omega_z;
  void enable_fluid_columns();
  void enable_vorticity_columns();

  /// Moves every state column so that new index k holds old index order[k]. `order` must be a
  /// permutation of [0, size()). Every index held outside the store must be remapped by the
  /// caller with inverse_permutation(order) (Simulation::reorder does both).
  void reorder(std::span<const std::uint32_t> order);

  /// Store index of every id: index_of_id()[id[i]] == i. Ids are creation indices, a
  /// permutation of [0, size()); exports and checkpoints use this to go back to id order.
  std::vector<std::uint32_t> index_of_id() const;

  /// Bytes held by all columns (the reorder spares included).
  std::size_t bytes() const;

 private:
  template <class F>
  void for_each_state_column(F&& f);
  std::size_t size_ = 0;
  bool fluid_columns_ = false, vorticity_columns_ = false;
  // reorder() gathers a column into the spare of its type and swaps the two buffers, so the
  // spares hold the old order afterwards (their contents mean nothing between calls).
  FloatColumn spare_float_;
  AlignedColumn<std::uint32_t> spare_uint_;
  AlignedColumn<std::int32_t> spare_int_;
  template <class T>
  AlignedColumn<T>& spare_column();
};

/// What kernels see of the store: its columns' pointers now (a reorder swaps the buffers, so a
/// view is made where a pass runs, not kept).
kernels::ParticleView particle_view(ParticleStore& store);

/// new_index[old] for a sorted[k] = old[order[k]] permutation.
std::vector<std::uint32_t> inverse_permutation(std::span<const std::uint32_t> order);

}  // namespace seiche
