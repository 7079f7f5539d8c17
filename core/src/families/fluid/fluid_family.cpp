#include "fluid_family.hpp"

#include <algorithm>
#include <cmath>

#include "families/lattice.hpp"

namespace seiche {

std::size_t FluidFamily::particle_count(const SceneDef& scene) {
  std::size_t count = 0;
  for (const FluidDef& f : scene.fluids) count += lattice_size(f.box, f.spacing);
  return count;
}

FluidFamily::FluidFamily(const SceneDef& scene, ParticleStore& store, std::size_t first, Reorder reorder)
    : scene_(scene), store_(store), reorder_(std::move(reorder)) {
  density_tolerance_ = scene.solver.density_tolerance;
  neighborhood_ = std::make_unique<Neighborhood>();
  // All blocks share the first block's material (the scene loader checks that they agree).
  solver_ = std::make_unique<FluidSolver>(scene.fluids[0], scene.solver, scene.domain, store, *neighborhood_);
  neighborhood_->radius = solver_->kernel_radius();
  std::size_t k = first;
  for (std::size_t b = 0; b < scene.fluids.size(); ++b) {
    const FluidDef& f = scene.fluids[b];
    for_each_lattice_site(f.box, f.spacing, [&](float x, float y, float z) {
      store.x[k] = x, store.y[k] = y, store.z[k] = z;
      store.vx[k] = f.velocity[0], store.vy[k] = f.velocity[1], store.vz[k] = f.velocity[2];
      store.w[k] = 1.0f / solver_->particle_mass();
      store.phase[k] = make_phase(Material::Fluid, std::uint32_t(b));
      store.radius[k] = solver_->particle_radius();
      ++k;
    });
  }
  // The grid covers the domain (grown by one cell); particles outside clamp to border cells.
  const float h = neighborhood_->radius;
  float lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = scene.domain.min[a] - h, hi[a] = scene.domain.max[a] + h;
  const std::size_t fluid_count = k - first;
  neighborhood_->spec = neighbor::make_grid_spec(lo, hi, h, std::max<std::size_t>(4 * fluid_count, 1 << 16));
  probe_ = std::make_unique<FluidErrorProbe>(solver_->params(), neighborhood_->spec, h);
}

void FluidFamily::add_passes(std::vector<Pass>& passes) {
  passes.push_back({"neighbors", Stage::Neighbors, pass_order::kFluidNeighbors, true,
                    [this](const StepContext&) { find_neighbors(); }});
  passes.push_back({"fluid density", Stage::Iterate, pass_order::kFluidDensity, true, [this](const StepContext& c) {
                      // The error is needed from the last fixed iteration on.
                      solver_->solve_density(density_tolerance_ > 0.0f && c.iteration + 1 >= scene_.solver.iterations);
                    }});
  if (solver_->has_vorticity())
    passes.push_back({"vorticity", Stage::Velocity, pass_order::kVorticity, true,
                      [this](const StepContext& c) { solver_->apply_vorticity_confinement(c.dt); }});
  if (solver_->has_viscosity())
    passes.push_back({"viscosity", Stage::Velocity, pass_order::kViscosity, true,
                      [this](const StepContext&) { solver_->apply_viscosity(); }});
}

bool FluidFamily::wants_iteration() const {
  return density_tolerance_ > 0.0f && solver_->predicted_density_error() > density_tolerance_;
}

void FluidFamily::measure(FrameMetrics& m) {
  const FluidError e = probe_->measure(store_);
  m.errors.push_back({"fluid_density_error", "fluid density", ErrorUnit::Ratio, e.mean, e.max});
}

// The grid on the predicted positions, the store reordered into its order (every index held
// elsewhere remapped), then the lists on the sorted positions.
void FluidFamily::find_neighbors() {
  Neighborhood& nb = *neighborhood_;
  const std::size_t n = store_.size();
  nb.build_grid(store_.px.data(), store_.py.data(), store_.pz.data(), store_.phase.data(), n);
  reorder_(nb.grid.order());
  neighbor::build_neighbor_list(nb.grid, store_.px.data(), store_.py.data(), store_.pz.data(), n, nb.radius,
                                nb.list);
}

}  // namespace seiche
