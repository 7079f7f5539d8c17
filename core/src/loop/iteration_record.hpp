// The iteration record: the predicted positions of one substep's iterations in the layout a pass
// works on. The store's columns px, py, pz are the positions' owner; the record is the packed
// layout of the passes that gather (kernels/packed_positions.hpp: (px, py, pz, w) records over
// one index range). Each pass declares its layout (Pass::layout in family.hpp), and before it
// runs, Simulation brings that layout up to date: it packs when the columns were written last
// and unpacks when the records were. So consecutive packed passes (distance, cloth stretch,
// cloth bending) share one pack, and no family keeps a copy of the positions in sync by hand.
//
// The range is the union of the ranges the families' packed passes gather (Family::packed_range),
// set when the families are built and again after every reorder; the records are allocated
// only when its size changes.
#pragma once

#include "seiche/kernels/packed_positions.hpp"
#include "seiche/kernels/particle_view.hpp"

namespace seiche {

/// The layout a pass reads and writes the predicted positions in.
enum class Layout {
  Columns,  ///< the store's px, py, pz (and every other column)
  Packed,   ///< the iteration record's (px, py, pz, w) records; the pass writes only positions
};

class IterationRecord {
 public:
  /// The store indices the records cover. Only while the columns are current (the records'
  /// content is dropped): Simulation makes them so before it reorders the store.
  void reset(kernels::IndexRange range);
  kernels::IndexRange range() const { return packed_.range(); }

  /// Before a pass that works on `layout`: packs the records from p (columns written last) or
  /// unpacks them into p (records written last); nothing when `layout` is already current. The
  /// pass is then taken to write `layout`.
  void prepare(Layout layout, const kernels::ParticleView& p);
  /// Which layout holds the newest positions (the one the last pass wrote).
  Layout current() const { return current_; }

  /// The records, for a packed pass (current after prepare(Layout::Packed, ...)).
  const kernels::PackedPositions& packed() const { return packed_; }

 private:
  kernels::PackedPositions packed_;
  Layout current_ = Layout::Columns;
};

}  // namespace seiche
