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
//
// Where the scene couples the fluid with rigid bodies or shapes (families/fluid_body/), their
// boundary particles lend density to the fluid particles near them in the constraint
//   rho_i = sum_j m W(|x_i - x_j|) + walls + rho_b,i
// and the error is of that same rho_i: the coupling hands the probe a BoundaryDensity that
// computes rho_b,i at the measured positions (kernels::PbfParams::boundary then carries it into
// the density kernel). Without coupling there is none and rho_i has no boundary term.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <utility>
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
  /// The positions the probe measures at: every particle's, in its grid's order (its fluid
  /// particles first, [0, fluid), in cell order), and each one's store index.
  struct Positions {
    const neighbor::CellGrid& grid;        ///< over the fluid particles [0, fluid)
    const float* x;                        ///< copy index k: store index order[k]
    const float* y;
    const float* z;
    std::span<const std::uint32_t> order;  ///< copy index -> store index
    std::size_t fluid;
  };
  /// Writes rho_b,k (kg/m^3) of each fluid particle k < at.fluid to density[k].
  using BoundaryDensity = std::function<void(const Positions& at, double* density)>;

  /// `params`: the fluid's (FluidSolver::params()); `spec` and `radius`: the simulation's grid
  /// and query radius.
  FluidErrorProbe(const kernels::PbfParams& params, const neighbor::GridSpec& spec, float radius);

  /// Mean and max of max(rho / rho0 - 1, 0) over the fluid particles of `store` at their
  /// positions x, y, z.
  FluidError measure(const ParticleStore& store);
  /// From now on, the density measured adds `boundary`'s (null: none, the default).
  void set_boundary_density(BoundaryDensity boundary) { boundary_ = std::move(boundary); }

 private:
  kernels::PbfParams params_;
  Neighborhood scratch_;                 // grid and lists over the sorted copy
  AlignedColumn<float> x_, y_, z_;       // every particle's position, in the grid's order
  std::vector<kernels::Float4> packed_;  // (x, y, z, -) for the density kernel
  AlignedColumn<float> density_, lambda_;
  BoundaryDensity boundary_;
  std::vector<double> boundary_density_;     // rho_b per fluid particle, in the copy's order
  std::vector<kernels::Float4> boundary_rows_;  // (0, 0, 0, rho_b): kernels::PbfParams::boundary
};

}  // namespace seiche
