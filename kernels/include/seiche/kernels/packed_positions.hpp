// The particles a colored constraint solve works on, packed as (px, py, pz, w) records: a
// constraint's particle is then one 16-byte load and one 16-byte store (gathering and scattering
// three SoA columns costs twice as much). Only the index range [lo, hi] the constraints use is
// packed, as a store may hold much more than the cloths.
//
// Who solves several families on the same particles keeps one PackedPositions for all of them
// (the simulation's iteration record, core/src/loop/iteration_record.hpp: raw distance
// constraints, cloth stretch and bending): the range is computed when the constraints are built
// (index_range) and again when the store is reordered, the records are allocated once, and the
// positions are packed once before the first family and unpacked once after the last.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <span>

#include "seiche/kernels/particle_view.hpp"

namespace seiche::kernels {

/// Particle indices [lo, hi], both included; empty when lo > hi.
struct IndexRange {
  std::uint32_t lo = 1, hi = 0;
  bool empty() const { return lo > hi; }
  std::size_t size() const { return empty() ? 0 : std::size_t(hi - lo) + 1; }
};

/// The smallest range holding every index of the columns (empty if all are empty).
IndexRange index_range(std::initializer_list<std::span<const std::uint32_t>> columns);

class PackedPositions {
 public:
  /// Records for the particles of `range` (allocated only when the size changes); their content
  /// is undefined until pack.
  void reset(IndexRange range);
  /// px, py, pz, w of the range into the records (parallel).
  void pack(const ParticleView& p);
  /// The records' positions back to px, py, pz (parallel); w is never changed by a solve.
  void unpack(const ParticleView& p) const;

  IndexRange range() const { return range_; }
  /// by_index()[i] is particle i's record, for i in range(): the records shifted by lo, so that
  /// constraints address them by store index (no subtraction per lane). Formed through an integer
  /// (implementation-defined, not undefined, on the flat address spaces we target) and only
  /// dereferenced inside the range.
  Float4* by_index() const { return by_index_; }

 private:
  std::unique_ptr<Float4[]> records_;
  std::size_t capacity_ = 0;
  Float4* by_index_ = nullptr;
  IndexRange range_;
};

}  // namespace seiche::kernels
