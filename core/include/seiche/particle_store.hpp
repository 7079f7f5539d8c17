// The particle store: one structure-of-arrays for all particles of all materials, described by
// one column table. Every column is declared once, with its name, element type and kind:
//   State     kept across substeps: moved by reorder(), written to checkpoints
//   Constant  set at creation from the scene: moved by reorder(), rebuilt (not checkpointed)
//   Scratch   recomputed every substep where a pass needs it: allocated only once enabled,
//             neither moved nor checkpointed
// The built-in columns are the named members below; a family adds its own with add_column()
// (rest offsets, frames, ...) without editing the store. resize(), reorder(), bytes(),
// checkpoints and Simulation::restore_state go through the table.
//
// Built-in columns:
//   x y z      State     position at the start of the substep (m)
//   px py pz   State     predicted position, the unknowns of the constraint solve (m)
//   vx vy vz   State     velocity (m/s)
//   w          State     inverse mass (1/kg); 0 = pinned
//   phase      State     material (low 8 bits) and object/group index (high 24 bits), phase.hpp
//   id         State     creation index: the stable order of every export
//   radius     Constant  collision radius (m): what the colliders keep between a particle's
//                        centre and their surface
//   density lambda            Scratch (fluid)
//   omega_x omega_y omega_z   Scratch (vorticity)
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "seiche/aligned_column.hpp"
#include "seiche/kernels/particle_view.hpp"
#include "seiche/phase.hpp"

namespace seiche {

using FloatColumn = AlignedColumn<float>;

enum class ColumnKind : std::uint8_t { State, Constant, Scratch };

/// The element type of a column; the values are those checkpoints write.
enum class ColumnType : std::uint8_t { F32 = 0, U32 = 1, I32 = 2 };
const char* column_type_name(ColumnType type);

/// One column of the store's table.
struct StoreColumn {
  using Data = std::variant<AlignedColumn<float>, AlignedColumn<std::uint32_t>, AlignedColumn<std::int32_t>>;
  std::string name;
  ColumnKind kind = ColumnKind::State;
  bool enabled = true;  ///< sized with the store (a Scratch column once a pass enabled it)
  Data data;

  ColumnType type() const { return ColumnType(data.index()); }
  /// Every element type is 4 bytes.
  static constexpr std::size_t kElementBytes = 4;
  /// The values as bytes (kElementBytes per particle).
  const char* raw() const;
  char* raw();
};

class ParticleStore {
 public:
  ParticleStore();
  // Copies and moves carry the whole table; the named members refer to this store's own.
  ParticleStore(const ParticleStore& other);
  ParticleStore(ParticleStore&& other) noexcept;
  ParticleStore& operator=(const ParticleStore& other);
  ParticleStore& operator=(ParticleStore&& other) noexcept;

  std::size_t size() const { return size_; }
  /// Resizes every enabled column; new particles are zero (w = 0: pinned until set).
  void resize(std::size_t n);
  /// Room for n particles in every enabled column, and in those enabled or added later: the
  /// families' resize() calls, one per family, then allocate each column once (std::vector
  /// would grow it up to twice its final size).
  void reserve(std::size_t n);

  /// Adds a column of element type T (float, std::uint32_t or std::int32_t), sized with the
  /// store and zero; the reference stays valid for the store's life. Throws
  /// std::invalid_argument when the name is taken.
  template <class T>
  AlignedColumn<T>& add_column(std::string name, ColumnKind kind);

  /// The table, in declaration order (the built-ins first).
  const std::deque<StoreColumn>& columns() const { return columns_; }
  /// The column called `name`, or null.
  const StoreColumn* find(std::string_view name) const;
  StoreColumn* find(std::string_view name);

 private:
  // The table comes first: the named members below are declared into it, in this order.
  std::deque<StoreColumn> columns_;
  std::size_t size_ = 0;
  std::size_t reserved_ = 0;  ///< reserve()'s count (not carried by copies)
  /// The named column `name` of this table, appended when this store is being built (copies and
  /// moves find the one they carried).
  template <class T>
  AlignedColumn<T>& declare(const char* name, ColumnKind kind, bool enabled = true);

 public:
  FloatColumn& x = declare<float>("x", ColumnKind::State);
  FloatColumn& y = declare<float>("y", ColumnKind::State);
  FloatColumn& z = declare<float>("z", ColumnKind::State);
  FloatColumn& px = declare<float>("px", ColumnKind::State);
  FloatColumn& py = declare<float>("py", ColumnKind::State);
  FloatColumn& pz = declare<float>("pz", ColumnKind::State);
  FloatColumn& vx = declare<float>("vx", ColumnKind::State);
  FloatColumn& vy = declare<float>("vy", ColumnKind::State);
  FloatColumn& vz = declare<float>("vz", ColumnKind::State);
  FloatColumn& w = declare<float>("w", ColumnKind::State);
  AlignedColumn<std::uint32_t>& phase = declare<std::uint32_t>("phase", ColumnKind::State);
  AlignedColumn<std::int32_t>& id = declare<std::int32_t>("id", ColumnKind::State);
  FloatColumn& radius = declare<float>("radius", ColumnKind::Constant);

  // Scratch columns, allocated by the enable calls of the passes that need them.
  FloatColumn& density = declare<float>("density", ColumnKind::Scratch, false);
  FloatColumn& lambda = declare<float>("lambda", ColumnKind::Scratch, false);
  FloatColumn& omega_x = declare<float>("omega_x", ColumnKind::Scratch, false);
  FloatColumn& omega_y = declare<float>("omega_y", ColumnKind::Scratch, false);
  FloatColumn& omega_z = declare<float>("omega_z", ColumnKind::Scratch, false);
  void enable_fluid_columns();
  void enable_vorticity_columns();

  /// Moves every State and Constant column so that new index k holds old index order[k].
  /// `order` must be a permutation of [0, size()). Every index held outside the store must be
  /// remapped by the caller with inverse_permutation(order) (Simulation::reorder does both).
  void reorder(std::span<const std::uint32_t> order);

  /// Store index of every id: index_of_id()[id[i]] == i. Ids are creation indices, a
  /// permutation of [0, size()); exports and checkpoints use this to go back to id order.
  std::vector<std::uint32_t> index_of_id() const;

  /// Bytes held by all columns (the reorder spares included).
  std::size_t bytes() const;

 private:
  void enable(FloatColumn& column);
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
