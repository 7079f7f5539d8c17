// IterationRecord (iteration_record.hpp): the layout last written, and one pack or unpack when
// a pass asks for the other.
#include "iteration_record.hpp"

namespace seiche {

void IterationRecord::reset(kernels::IndexRange range) {
  packed_.reset(range);
  current_ = Layout::Columns;
}

void IterationRecord::prepare(Layout layout, const kernels::ParticleView& p) {
  if (layout == current_) return;
  if (layout == Layout::Packed)
    packed_.pack(p);
  else
    packed_.unpack(p);
  current_ = layout;
}

}  // namespace seiche
