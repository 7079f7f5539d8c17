#include "fluid_solver.hpp"

#include <algorithm>
#include <stdexcept>

#include <tbb/parallel_for.h>

#include "seiche/kernels/blocked_reduce.hpp"
#include "seiche/kernels/pbf_walls.hpp"
#include "seiche/kernels/vorticity_confinement.hpp"
#include "seiche/kernels/xsph_viscosity.hpp"

namespace seiche {

FluidSolver::FluidSolver(const FluidDef& material, const SolverDef& solver,
                         const DomainDef& domain, ParticleStore& store,
                         const Neighborhood& neighborhood)
    : store_(store), neighborhood_(neighborhood) {
  const float s = material.spacing;
  params_.h = material.kernel_radius * s;
  params_.rest_density = material.rest_density;
  // The mass that makes the initial lattice exactly rest density (about rest_density s^3).
  params_.mass = float(material.rest_density / kernels::lattice_kernel_sum(s, params_.h));
  const double full_denominator = kernels::lattice_lambda_denominator(s, params_.h);
  if (!(full_denominator > 0.0))  // the loader keeps kernel_radius >= 1.5, where it is > 0
    throw std::invalid_argument("fluid: kernel_radius gives the density constraint no gradient");
  params_.epsilon = float(solver.relaxation * full_denominator);
  params_.lambda_scale = float(1.0 / full_denominator);
  params_.tensile_k = solver.tensile_k * tensile_substep_scale(solver);
  params_.tensile_n = solver.tensile_n;
  params_.tensile_dq = solver.tensile_dq;
  params_.tensile_rest_distance = s;  // s_corr pushes no pair apart beyond the rest spacing
  params_.walls = true;
  params_.wall_scale = float(kernels::lattice_wall_share(s, params_.h) /
                             kernels::wall_density_fraction(0.5f * s, params_.h));
  for (int a = 0; a < 3; ++a) params_.wall_min[a] = domain.min[a], params_.wall_max[a] = domain.max[a];
  particle_radius_ = 0.5f * s;
  viscosity_ = material.viscosity;
  vorticity_ = material.vorticity;
  store_.enable_fluid_columns();
  if (has_vorticity()) store_.enable_vorticity_columns();
}

double tensile_substep_scale(const SolverDef& solver) {
  const double dt = solver.frame_dt / solver.substeps;
  return std::min(1.0, (dt / kTensileReferenceSubstep) * (dt / kTensileReferenceSubstep));
}

void FluidSolver::pack_positions(const float* x, const float* y, const float* z) {
  const std::size_t n = neighborhood_.count();
  pos_.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) pos_[i] = {x[i], y[i], z[i], 0.0f};
  });
}

void FluidSolver::pack_velocities_and_volumes() {
  const std::size_t n = neighborhood_.count();
  vel_.resize(n);
  const float mass = params_.mass;
  const float* rho = store_.density.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i)
      vel_[i] = {store_.vx[i], store_.vy[i], store_.vz[i], mass / rho[i]};  // rho >= m W(0) > 0
  });
}

void FluidSolver::solve_density(bool measure_error) {
  const std::size_t n = neighborhood_.count();
  pack_positions(store_.px.data(), store_.py.data(), store_.pz.data());
  kernels::pbf_density_lambda(pos_.data(), neighborhood_.span(), n, params_,
                              store_.density.data(), store_.lambda.data());
  if (measure_error)
    predicted_error_ = density_error(store_.density.data(), n, params_.rest_density).mean;
  const float* lambda = store_.lambda.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) pos_[i].w = lambda[i];
  });
  kernels::pbf_apply_correction(pos_.data(), neighborhood_.span(), n, params_, store_.px.data(),
                                store_.py.data(), store_.pz.data());
}

void FluidSolver::apply_vorticity_confinement(float dt) {
  const std::size_t n = neighborhood_.count();
  pack_positions(store_.x.data(), store_.y.data(), store_.z.data());
  pack_velocities_and_volumes();
  kernels::compute_vorticity(pos_.data(), vel_.data(), neighborhood_.span(), n, params_.h,
                             store_.omega_x.data(), store_.omega_y.data(), store_.omega_z.data());
  omega_norm_.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const float wx = store_.omega_x[i], wy = store_.omega_y[i], wz = store_.omega_z[i];
      omega_norm_[i] = std::sqrt(wx * wx + wy * wy + wz * wz);
      pos_[i].w = vel_[i].w;  // volume
    }
  });
  kernels::apply_vorticity_confinement(pos_.data(), omega_norm_.data(), store_.omega_x.data(),
                                       store_.omega_y.data(), store_.omega_z.data(),
                                       neighborhood_.span(), n, params_.h, vorticity_, dt,
                                       store_.vx.data(), store_.vy.data(), store_.vz.data());
}

void FluidSolver::apply_viscosity() {
  const std::size_t n = neighborhood_.count();
  pack_positions(store_.x.data(), store_.y.data(), store_.z.data());
  pack_velocities_and_volumes();
  kernels::xsph_viscosity(pos_.data(), vel_.data(), neighborhood_.span(), n, params_.h,
                          viscosity_, store_.vx.data(), store_.vy.data(), store_.vz.data());
}

FluidError density_error(const float* rho, std::size_t n, float rest_density) {
  FluidError e;
  if (n == 0) return e;
  const float inv_rest = 1.0f / rest_density;
  const FluidError sum = kernels::blocked_reduce(
      n, FluidError{},
      [&](std::size_t b, std::size_t end) {
        FluidError part;
        for (std::size_t i = b; i < end; ++i) {
          const double err = std::max(double(rho[i] * inv_rest) - 1.0, 0.0);
          part.mean += err;
          part.max = std::max(part.max, err);
        }
        return part;
      },
      [](FluidError& acc, const FluidError& part) {
        acc.mean += part.mean;
        acc.max = std::max(acc.max, part.max);
      });
  e.mean = sum.mean / double(n);
  e.max = sum.max;
  return e;
}

}  // namespace seiche
