// The fluid: Position Based Fluids over the particles of the scene's fluid blocks (fluid_solver.hpp
// has the solver, kernels/pbf_density.hpp the math).
//
// Passes: the neighbor stage (grid on the predicted positions, the store reordered into its cell
// order, neighbor lists), the density constraint every iteration, and vorticity confinement and
// XSPH viscosity where the material has them. It votes for iterations past the fixed count while
// the fluid is more than solver.density_tolerance compressed, and measures the density error of
// the final positions with a probe that only reads the store (fluid_error_probe.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <utility>

#include "loop/family.hpp"
#include "fluid_error_probe.hpp"
#include "fluid_solver.hpp"
#include "neighborhood.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

class FluidFamily final : public Family {
 public:
  /// Reorders the store (new k = old order[k]) and remaps every index held elsewhere.
  using Reorder = std::function<void(std::span<const std::uint32_t> order)>;

  /// Particles of all the scene's fluid blocks.
  static std::size_t particle_count(const SceneDef& scene);

  /// The store must already hold room for the fluid's particles at [first, first +
  /// particle_count(scene)); the constructor writes them (positions on the blocks' lattices,
  /// velocities, inverse masses, phases).
  FluidFamily(const SceneDef& scene, ParticleStore& store, std::size_t first, Reorder reorder);

  const FluidSolver& solver() const { return *solver_; }
  FluidSolver& solver() { return *solver_; }
  const Neighborhood& neighborhood() const { return *neighborhood_; }

  void add_passes(std::vector<Pass>& passes) override;
  bool votes_on_iterations() const override { return density_tolerance_ > 0.0f; }
  bool wants_iteration() const override;
  void measure(FrameMetrics& m) override;
  /// The boundary (bodies, shapes) whose density the measured error includes, as the density
  /// constraint does (fluid_error_probe.hpp); set by the coupling, none without.
  void set_boundary_density(FluidErrorProbe::BoundaryDensity boundary) {
    probe_->set_boundary_density(std::move(boundary));
  }

 private:
  void find_neighbors();

  const SceneDef& scene_;
  ParticleStore& store_;
  Reorder reorder_;
  float density_tolerance_ = 0.0f;
  std::unique_ptr<Neighborhood> neighborhood_;  // the solver keeps a reference: never moved
  std::unique_ptr<FluidSolver> solver_;
  std::unique_ptr<FluidErrorProbe> probe_;
};

}  // namespace seiche
