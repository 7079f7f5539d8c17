// The fluid material: Position Based Fluids over the fluid particles of the store, which the
// neighbor stage has sorted to the front ([0, neighborhood.count())). Owns the packed
// per-neighbor copies the kernels gather from and launches the kernels of kernels/.
#pragma once

#include <vector>

#include "neighborhood.hpp"
#include "seiche/frame_metrics.hpp"
#include "seiche/kernels/pbf_density.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

/// PBF's artificial pressure is a push per iteration, which as a force grows as 1/dt^2; Seiche
/// scales it by (dt / kTensileReferenceSubstep)^2, at most 1, so that `tensile_k` means the same
/// force at any substep shorter than the reference (the default 1/60 s frame in 8 substeps) and
/// never more than the paper's push at longer ones.
constexpr double kTensileReferenceSubstep = 1.0 / 480.0;
double tensile_substep_scale(const SolverDef& solver);

/// The fluid's density error: the run report's "fluid_density_error".
struct FluidError {
  double mean = 0.0;  ///< mean over fluid particles of max(rho / rho0 - 1, 0)
  double max = 0.0;   ///< max over fluid particles of the same
};

/// Mean and max of max(rho / rho0 - 1, 0) over density[0, n) (deterministic: blocked sums in
/// index order).
FluidError density_error(const float* density, std::size_t n, float rest_density);

class FluidSolver {
 public:
  /// The domain's walls lend density to the particles next to them (pbf_walls.hpp).
  FluidSolver(const FluidDef& material, const SolverDef& solver, const DomainDef& domain,
              ParticleStore& store, const Neighborhood& neighborhood);

  const kernels::PbfParams& params() const { return params_; }
  float kernel_radius() const { return params_.h; }
  float particle_mass() const { return params_.mass; }
  float particle_radius() const { return particle_radius_; }
  bool has_viscosity() const { return viscosity_ > 0.0f; }
  bool has_vorticity() const { return vorticity_ > 0.0f; }
  float viscosity() const { return viscosity_; }  ///< XSPH's c

  /// One Jacobi iteration of the density constraints on the predicted positions. With
  /// `measure_error`, also the mean density error of those positions before the correction
  /// (deterministic: blocked sums in index order), read by predicted_density_error().
  void solve_density(bool measure_error = false);
  double predicted_density_error() const { return predicted_error_; }
  /// The rigid bodies' boundary, per fluid particle (kernels::PbfParams::boundary), for the
  /// density passes from now on; null: none.
  void set_boundary(const kernels::Float4* boundary) { params_.boundary = boundary; }
  void apply_vorticity_confinement(float dt);
  void apply_viscosity();

 private:
  void pack_positions(const float* x, const float* y, const float* z);
  void pack_velocities_and_volumes();

  ParticleStore& store_;
  const Neighborhood& neighborhood_;
  kernels::PbfParams params_;
  float particle_radius_ = 0.0f;
  float viscosity_ = 0.0f, vorticity_ = 0.0f;
  // Per-pass scratch of the neighbor kernels, rebuilt from the store's columns at every call and
  // never written back: the store's px, py, pz own the positions (the iteration record is the
  // colored solves' layout, with the inverse mass in w; these gathers need lambda or volume).
  std::vector<kernels::Float4> pos_;  // (x, y, z, lambda or volume)
  std::vector<kernels::Float4> vel_;  // (vx, vy, vz, volume)
  std::vector<float> omega_norm_;
  double predicted_error_ = 0.0;
};

}  // namespace seiche
