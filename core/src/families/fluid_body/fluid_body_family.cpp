// Two-way coupling of rigid bodies and fluid (the formulas are in fluid_body_family.hpp).
#include "fluid_body_family.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "families/fluid/fluid_ball_query.hpp"
#include "families/rigid/body_correction.hpp"
#include "seiche/kernels/blocked_reduce.hpp"
#include "seiche/kernels/sph_kernels.hpp"
#include "seiche/phase.hpp"

namespace seiche {

using fluid_body::BodyBoundary;
using rigid::RigidBody;
using rigid::Vec3d;

namespace {

// A block of particles' impulses on the bodies: per body, the impulse (kg m) and its moment about
// the centre (kg m^2), world frame, 6 doubles. Dense over the bodies while a block runs (one per
// thread, reused block after block), kept sparse between blocks: the bodies the block touched,
// ascending. A dense vector per block would hold blocks x bodies x 6 doubles (1000 blocks of a
// 4M-particle pool and 4096 bodies: 190 MB) and add them all up serially.
class BlockImpulses {
 public:
  explicit BlockImpulses(std::size_t bodies) : sums_(6 * bodies, 0.0), touched_(bodies, 0) {}

  void add(std::size_t body, Vec3d p, Vec3d moment) {
    if (!touched_[body]) touched_[body] = 1, order_.push_back(std::uint32_t(body));
    double* s = &sums_[6 * body];
    s[0] += p.x, s[1] += p.y, s[2] += p.z, s[3] += moment.x, s[4] += moment.y, s[5] += moment.z;
  }

  /// The block's sums of the bodies it touched, ascending body (6 doubles each).
  struct Sparse {
    std::vector<std::uint32_t> bodies;
    std::vector<double> sums;
  };
  /// Returns the block's sums and clears them for the thread's next block.
  Sparse take() {
    std::sort(order_.begin(), order_.end());
    Sparse out{order_, {}};
    out.sums.reserve(6 * order_.size());
    for (const std::uint32_t k : order_) {
      out.sums.insert(out.sums.end(), &sums_[6 * k], &sums_[6 * k] + 6);
      std::fill_n(&sums_[6 * k], 6, 0.0);
      touched_[k] = 0;
    }
    order_.clear();
    return out;
  }

 private:
  std::vector<double> sums_;
  std::vector<std::uint8_t> touched_;
  std::vector<std::uint32_t> order_;
};

// Sums per block of particles (kernels::kReduceBlock, in index order within a block), then the
// blocks in index order, body by body; moves each body once. Per body, the same additions in the
// same order as a dense sum over every block: the bits do not depend on the thread count.
template <class PerParticle>
void solve_and_move_bodies(std::size_t n, std::vector<RigidBody>& bodies, PerParticle&& per_particle) {
  const std::size_t block = kernels::kReduceBlock, blocks = (n + block - 1) / block;
  std::vector<BlockImpulses::Sparse> partial(blocks);
  tbb::enumerable_thread_specific<BlockImpulses> scratch([&] { return BlockImpulses(bodies.size()); });
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
    BlockImpulses& impulses = scratch.local();
    for (std::size_t i = b * block, end = std::min(n, (b + 1) * block); i < end; ++i) per_particle(i, impulses);
    partial[b] = impulses.take();
  });
  std::vector<double> total(6 * bodies.size(), 0.0);
  for (const BlockImpulses::Sparse& part : partial)
    for (std::size_t e = 0; e < part.bodies.size(); ++e)
      for (int c = 0; c < 6; ++c) total[6 * part.bodies[e] + c] += part.sums[6 * e + c];
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const double* s = &total[6 * k];
    rigid::apply_positional_impulse(bodies[k], {0.0, 0.0, 0.0}, {s[0], s[1], s[2]});
    rigid::apply_angular_impulse(bodies[k], {s[3], s[4], s[5]});
  }
}

}  // namespace

FluidBodyFamily::FluidBodyFamily(const SceneDef& scene, ParticleStore& store, FluidFamily& fluid, RigidFamily* rigid,
                                 std::int32_t first_shape_id)
    : store_(store), fluid_(fluid), rigid_(rigid) {
  particle_radius_ = fluid.solver().particle_radius();
  const double spacing = scene.fluids[0].spacing;
  const double h = fluid.solver().kernel_radius();
  for (std::size_t k = 0; k < scene.rigid_bodies.size(); ++k)
    boundaries_.push_back(
        fluid_body::sample_body_boundary(scene.rigid_bodies[k], rigid->body_mesh_fields().get(k), spacing, h));
  if (!scene.shapes.empty()) shapes_ = std::make_unique<fluid_body::ShapeBoundary>(scene, first_shape_id, h);
  fluid.set_boundary_density(
      [this](const FluidErrorProbe::Positions& at, double* density) { measured_boundary_density(at, density); });
}

void FluidBodyFamily::add_passes(std::vector<Pass>& passes) {
  if (shapes_)
    passes.push_back({"fluid-shape pairs", Stage::Neighbors, pass_order::kFluidShapePairs, true,
                      [this](const StepContext&) { shapes_->find_pairs(store_, fluid_.neighborhood()); }});
  passes.push_back({"fluid-body boundary", Stage::Iterate, pass_order::kFluidBodyBoundary, true,
                    [this](const StepContext&) { gather_boundary(); }});
  passes.push_back({"fluid-body density", Stage::Iterate, pass_order::kFluidBodyDensity, true,
                    [this](const StepContext&) { solve_density(); }});
  if (fluid_.solver().has_viscosity())
    passes.push_back({"fluid-body viscosity", Stage::Velocity, pass_order::kFluidBodyViscosity, true,
                      [this](const StepContext&) { apply_viscosity(); }});
  if (rigid_ == nullptr) return;  // shapes only: their contacts with the fluid are particle contacts
  passes.push_back({"fluid-body separation", Stage::Iterate, pass_order::kFluidBodySeparation, true,
                    [this](const StepContext&) { separate(); }});
}

void FluidBodyFamily::build_grid(bool separation) {
  const std::vector<RigidBody>& bodies = this->bodies();
  centres_.resize(bodies.size());
  reaches_.resize(bodies.size());
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    centres_[k] = bodies[k].x;
    reaches_[k] = separation ? boundaries_[k].extent + particle_radius_ : boundaries_[k].reach;
  }
  grid_.build(centres_, reaches_);
}

template <class Visit>
void FluidBodyFamily::for_each_site(Vec3d p, Visit&& visit) const {
  const std::vector<RigidBody>& bodies = this->bodies();
  for (const std::uint32_t k : grid_.candidates(p)) {
    const RigidBody& b = bodies[k];
    const BodyBoundary& boundary = boundaries_[k];
    const Vec3d d = p - b.x;
    if (dot(d, d) >= boundary.reach * boundary.reach) continue;
    const Vec3d q = rotate_back(b.q, d);
    boundary.for_each_site_near(q, [&](std::uint32_t s) { visit(k, s, q - boundary.sites[s]); });
  }
}

void FluidBodyFamily::gather_boundary() {
  const kernels::PbfParams& prm = fluid_.solver().params();
  const kernels::SphKernel kernel(prm.h);
  const double rho0 = prm.rest_density;
  const std::size_t n = fluid_.neighborhood().count();
  boundary_.resize(n);
  kept_.resize(n);
  const float* px = store_.px.data();
  const float* py = store_.py.data();
  const float* pz = store_.pz.data();
  const std::vector<RigidBody>& bodies = this->bodies();
  build_grid(false);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const Vec3d p{px[i], py[i], pz[i]};
      kept_[i] = p;
      double density = 0.0;
      Vec3d gradient;  // world frame
      std::size_t body = bodies.size();
      Vec3d local;     // body frame, of `body`
      const auto flush = [&]() {
        if (body != bodies.size()) gradient += rotate(bodies[body].q, local);
      };
      for_each_site(p, [&](std::size_t k, std::uint32_t s, Vec3d r) {
        if (k != body) flush(), body = k, local = {};
        const float r2 = float(dot(r, r));
        const double psi = boundaries_[k].psi[s];
        density += rho0 * psi * double(kernel.poly6(r2));
        local += (psi * double(kernel.spiky_grad_over_r(r2))) * r;
      });
      flush();
      if (shapes_) {
        double g[3] = {gradient.x, gradient.y, gradient.z};
        shapes_->gather(store_, i, rho0, kernel, density, g);
        gradient = {g[0], g[1], g[2]};
      }
      boundary_[i] = {float(gradient.x), float(gradient.y), float(gradient.z), float(density)};
    }
  });
  fluid_.solver().set_boundary(boundary_.data());
}

void FluidBodyFamily::measured_boundary_density(const FluidErrorProbe::Positions& at, double* density) {
  const kernels::PbfParams& prm = fluid_.solver().params();
  const kernels::SphKernel kernel(prm.h);
  const double rho0 = prm.rest_density;
  if (rigid_ != nullptr) {
    build_grid(false);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, at.fluid, 4096), [&](const auto& range) {
      for (std::size_t k = range.begin(); k != range.end(); ++k) {
        double sum = 0.0;
        for_each_site(Vec3d{at.x[k], at.y[k], at.z[k]}, [&](std::size_t body, std::uint32_t s, Vec3d r) {
          sum += rho0 * boundaries_[body].psi[s] * double(kernel.poly6(float(dot(r, r))));
        });
        density[k] += sum;
      }
    });
  }
  if (!shapes_) return;
  // Shape particle by shape particle in the probe's order (serial: each adds to its fluid neighbours).
  for (std::size_t k = at.fluid; k < at.order.size(); ++k) {
    const std::uint32_t i = at.order[k];
    if (phase_material(store_.phase[i]) != Material::Shape) continue;
    const float xb = at.x[k], yb = at.y[k], zb = at.z[k];
    if (!std::isfinite(xb) || !std::isfinite(yb) || !std::isfinite(zb)) continue;
    const double psi = shapes_->volume(store_.id[i]);
    for_each_fluid_particle_within(at.grid, at.x, at.y, at.z, xb, yb, zb, float(prm.h), [&](std::uint32_t j) {
      const float rx = at.x[j] - xb, ry = at.y[j] - yb, rz = at.z[j] - zb;
      density[j] += rho0 * psi * double(kernel.poly6(rx * rx + ry * ry + rz * rz));
    });
  }
}

void FluidBodyFamily::solve_density() {
  const kernels::PbfParams& prm = fluid_.solver().params();
  const kernels::SphKernel kernel(prm.h);
  const double mass = prm.mass;
  if (shapes_) shapes_->solve(store_, fluid_.neighborhood().count(), mass);
  if (rigid_ == nullptr) return;
  std::vector<RigidBody>& bodies = rigid_->bodies();
  float* px = store_.px.data();
  float* py = store_.py.data();
  float* pz = store_.pz.data();
  const float* lambda = store_.lambda.data();
  build_grid(false);
  solve_and_move_bodies(fluid_.neighborhood().count(), bodies, [&](std::size_t i, BlockImpulses& impulses) {
    if (!(boundary_[i].w > 0.0f) || !(lambda[i] < 0.0f)) return;
    const double lambda_i = lambda[i];
    // Per body, the body-frame sums of lambda_i psi_b grad W and of their moments about the centre.
    Vec3d dp;
    std::size_t body = bodies.size();
    Vec3d shift, moment;
    const auto flush = [&]() {
      if (body == bodies.size()) return;
      const RigidBody& b = bodies[body];
      const Vec3d world_shift = rotate(b.q, shift);
      dp += world_shift;
      impulses.add(body, -mass * world_shift, rotate(b.q, -mass * moment));
    };
    for_each_site(kept_[i], [&](std::size_t k, std::uint32_t s, Vec3d r) {
      if (k != body) flush(), body = k, shift = {}, moment = {};
      const double g = double(kernel.spiky_grad_over_r(float(dot(r, r))));
      const Vec3d step = (lambda_i * boundaries_[k].psi[s] * g) * r;
      shift += step;
      moment += cross(boundaries_[k].sites[s], step);
    });
    flush();
    px[i] += float(dp.x), py[i] += float(dp.y), pz[i] += float(dp.z);
  });
}

void FluidBodyFamily::apply_viscosity() {
  const kernels::PbfParams& prm = fluid_.solver().params();
  const kernels::SphKernel kernel(prm.h);
  const double c = fluid_.solver().viscosity();
  const std::size_t n = fluid_.neighborhood().count();
  const std::vector<RigidBody>& bodies = this->bodies();
  const float* x = store_.x.data();
  const float* y = store_.y.data();
  const float* z = store_.z.data();
  float* vx = store_.vx.data();
  float* vy = store_.vy.data();
  float* vz = store_.vz.data();
  // The pair's weight psi_b W(|x_i - x_b|), the same bits from either side.
  const auto shape_weight = [&](std::uint32_t i, std::uint32_t b, double psi) {
    const float rx = x[i] - x[b], ry = y[i] - y[b], rz = z[i] - z[b];
    return psi * double(kernel.poly6(rx * rx + ry * ry + rz * rz));
  };
  // The shape particles' reaction, from the velocities before this pass, so that each pair keeps
  // its momentum (m dv_i + m_b dv_b = 0): dv_b = -w_b m c sum_{pairs of b} psi_b W (v_b - v_i).
  if (shapes_) {
    const double scale = -double(prm.mass) * c;
    shape_dv_.resize(shapes_->shape_count());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, shapes_->shape_count(), 64), [&](const auto& range) {
      for (std::size_t g = range.begin(); g != range.end(); ++g) {
        const std::uint32_t b = shapes_->shape_particle(g);
        const Vec3d vb{vx[b], vy[b], vz[b]};
        Vec3d push;
        shapes_->for_each_pair_of_shape(g, [&](std::uint32_t i, double psi) {
          const double w = shape_weight(i, b, psi);
          if (w > 0.0) push += w * (vb - Vec3d{vx[i], vy[i], vz[i]});
        });
        shape_dv_[g] = (scale * double(store_.w[b])) * push;
      }
    });
  }
  build_grid(false);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const Vec3d p{x[i], y[i], z[i]}, v{vx[i], vy[i], vz[i]};
      Vec3d pull;  // sum_b psi_b (v_b - v_i) W
      bool near = false;
      for_each_site(p, [&](std::size_t k, std::uint32_t s, Vec3d r) {
        const double w = boundaries_[k].psi[s] * double(kernel.poly6(float(dot(r, r))));
        if (!(w > 0.0)) return;
        const RigidBody& b = bodies[k];
        const Vec3d site_velocity = b.v + cross(b.omega, rotate(b.q, boundaries_[k].sites[s]));
        pull += w * (site_velocity - v);
        near = true;
      });
      if (shapes_)
        shapes_->for_each_pair_of(i, [&](std::uint32_t b, double psi) {
          const double w = shape_weight(std::uint32_t(i), b, psi);
          if (!(w > 0.0)) return;
          pull += w * (Vec3d{vx[b], vy[b], vz[b]} - v);
          near = true;
        });
      if (!near) continue;
      const Vec3d after = v + c * pull;
      vx[i] = float(after.x), vy[i] = float(after.y), vz[i] = float(after.z);
    }
  });
  if (!shapes_) return;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, shapes_->shape_count(), 256), [&](const auto& range) {
    for (std::size_t g = range.begin(); g != range.end(); ++g) {
      const std::uint32_t b = shapes_->shape_particle(g);
      vx[b] += float(shape_dv_[g].x), vy[b] += float(shape_dv_[g].y), vz[b] += float(shape_dv_[g].z);
    }
  });
}

void FluidBodyFamily::separate() {
  const double inverse_mass = 1.0 / double(fluid_.solver().particle_mass());
  std::vector<RigidBody>& bodies = rigid_->bodies();
  float* px = store_.px.data();
  float* py = store_.py.data();
  float* pz = store_.pz.data();
  build_grid(true);
  solve_and_move_bodies(fluid_.neighborhood().count(), bodies, [&](std::size_t i, BlockImpulses& impulses) {
    Vec3d p{px[i], py[i], pz[i]};
    bool moved = false;
    // The bodies in ascending order, each tested at p as the earlier contacts left it: after a
    // contact p has moved, so the candidates after k are looked up again at the new p.
    for (std::uint32_t next = 0;;) {
      const std::span<const std::uint32_t> candidates = grid_.candidates(p);
      const auto found = std::lower_bound(candidates.begin(), candidates.end(), next);
      if (found == candidates.end()) break;
      const std::uint32_t k = *found;
      next = k + 1;
      const RigidBody& b = bodies[k];
      const double reach = boundaries_[k].extent + particle_radius_;
      const Vec3d r = p - b.x;
      if (dot(r, r) >= reach * reach) continue;
      rigid::SurfacePenetration contact;
      if (!rigid::penetration(boundaries_[k].solid, rotate_back(b.q, r), particle_radius_, contact)) continue;
      const Vec3d n = rotate(b.q, contact.normal);
      const double denominator = inverse_mass + rigid::positional_inverse_mass(b, r, n);
      const double dlambda = contact.depth / denominator;  // denominator >= 1/m > 0
      p += (dlambda * inverse_mass) * n;
      impulses.add(k, -dlambda * n, cross(r, -dlambda * n));
      moved = true;
    }
    if (moved) px[i] = float(p.x), py[i] = float(p.y), pz[i] = float(p.z);
  });
}

}  // namespace seiche
