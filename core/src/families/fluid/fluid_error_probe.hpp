// The fluid's density error on the final positions of a frame, measured without touching the
// simulation.
//
// The substep's neighbor lists were built on its predicted positions, before the constraint
// iterations moved the particles, so the frame's error needs lists of its own over the final
// positions. Building them with the simulation's neighbor stage would sort the store into the
// cell order of those positions: measuring would change the particle order, with it the order
// of every later neighbor sum, and so the later bits (a run with a report would differ from one
// without). The probe therefore owns everything it writes: a grid and neighbor lists over a copy
// of the positions (every particle's, in the grid's order: the fluid first, in cell order), the
// packed positions and density and lambda buffers. It only reads the store.
//
// The copy is sorted by a stable counting sort of the store's current order, the very order
// the simulation's own neighbor stage would have produced: the density of every particle, and
// so the reported error, has the same bits as if the store had been sorted.
#pragma once

#include <vector>

#include "fluid_solver.hpp"
#include "neighborhood.hpp"
#include "seiche/aligned_column.hpp"
#include "seiche/frame_metrics.hpp"
#include "seiche/kernels/pbf_density.hpp"
#include "seiche/particle_store.hpp"

namespace seiche {

class FluidErrorProbe {
 public:
  /// `params`: the fluid's (FluidSolver::params()); `spec` and `radius`: the simulation's grid
  /// and query radius.
  FluidErrorProbe(const kernels::PbfParams& params, const neighbor::GridSpec& spec, float radius);

  /// Mean and max of max(rho / rho0 - 1, 0) over the fluid particles of `store` at their
  /// positions x, y, z.
  FluidError measure(const ParticleStore& store);

 private:
  kernels::PbfParams params_;
  Neighborhood scratch_;                 // grid and lists over the sorted copy
  AlignedColumn<float> x_, y_, z_;       // every particle's position, in the grid's order
  std::vector<kernels::Float4> packed_;  // (x, y, z, -) for the density kernel
  AlignedColumn<float> density_, lambda_;
};

}  // namespace seiche
