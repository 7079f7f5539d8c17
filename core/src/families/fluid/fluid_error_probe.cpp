#include "fluid_error_probe.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "fluid_solver.hpp"

namespace seiche {

FluidErrorProbe::FluidErrorProbe(const kernels::PbfParams& params, const neighbor::GridSpec& spec,
                                 float radius)
    : params_(params) {
  scratch_.spec = spec;
  scratch_.radius = radius;
}

FluidError FluidErrorProbe::measure(const ParticleStore& store) {
  const std::size_t n = store.size();
  Neighborhood& nb = scratch_;
  nb.build_grid(store.x.data(), store.y.data(), store.z.data(), store.phase.data(), n);
  // order() puts the fluid first, [0, count()); the lists want every particle's sorted position.
  const std::size_t fluid = nb.count();
  if (fluid == 0) return {};
  const std::span<const std::uint32_t> order = nb.grid.order();
  x_.resize(n), y_.resize(n), z_.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192), [&](const auto& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      const std::uint32_t i = order[k];
      x_[k] = store.x[i], y_[k] = store.y[i], z_[k] = store.z[i];
    }
  });
  neighbor::build_neighbor_list(nb.grid, x_.data(), y_.data(), z_.data(), n, nb.radius, nb.list);
  packed_.resize(fluid);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, fluid, 8192), [&](const auto& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) packed_[k] = {x_[k], y_[k], z_[k], 0.0f};
  });
  density_.resize(fluid), lambda_.resize(fluid);
  if (boundary_) {  // the constraint's rho_i: its gradient part is not needed for the density
    boundary_density_.assign(fluid, 0.0);
    boundary_(Positions{nb.grid, x_.data(), y_.data(), z_.data(), order, fluid}, boundary_density_.data());
    boundary_rows_.resize(fluid);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, fluid, 8192), [&](const auto& r) {
      for (std::size_t k = r.begin(); k != r.end(); ++k)
        boundary_rows_[k] = {0.0f, 0.0f, 0.0f, float(boundary_density_[k])};
    });
    params_.boundary = boundary_rows_.data();
  }
  kernels::pbf_density_lambda(packed_.data(), nb.span(), fluid, params_, density_.data(),
                              lambda_.data());
  return density_error(density_.data(), fluid, params_.rest_density);
}

}  // namespace seiche
