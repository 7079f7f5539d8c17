#include "seiche/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <tbb/parallel_for.h>

#include "blocked_reduce.hpp"
#include "cloth_solver.hpp"
#include "mesh_sdf.hpp"
#include "particle_contact_stage.hpp"
#include "distance_solver.hpp"
#include "fluid_error_probe.hpp"
#include "fluid_solver.hpp"
#include "neighborhood.hpp"
#include "seiche/kernels/collisions.hpp"
#include "seiche/kernels/integrate.hpp"
#include "seiche/kernels/particle_view.hpp"

namespace seiche {

namespace {

// Lattice points of a fluid block: (i + 0.5) spacing from box.min along each axis.
std::array<std::size_t, 3> lattice_counts(const FluidDef& f) {
  std::array<std::size_t, 3> n{};
  for (int a = 0; a < 3; ++a) {
    const double extent = double(f.box.max[a]) - f.box.min[a];
    n[a] = std::size_t(std::max(0.0, std::floor(extent / f.spacing + 1e-4)));
  }
  return n;
}

// Mesh colliders: the field's samples are a 64th of the mesh's largest side unless the scene
// says otherwise, over the mesh's box grown by 4 samples.
std::unique_ptr<MeshSdf> build_collider_sdf(const ColliderDef& c, std::size_t index) {
  const std::string path = "colliders[" + std::to_string(index) + "].mesh";
  const ClothMesh mesh = read_obj_mesh(c.mesh.file, c.mesh, path);
  float voxel = c.voxel_size;
  if (voxel <= 0.0f) {
    float extent = 0.0f;
    for (int a = 0; a < 3; ++a) {
      float lo = INFINITY, hi = -INFINITY;
      for (const Vec3& x : mesh.positions) lo = std::min(lo, x[a]), hi = std::max(hi, x[a]);
      extent = std::max(extent, hi - lo);
    }
    voxel = std::max(extent / 64.0f, 1e-6f);
  }
  auto sdf = std::make_unique<MeshSdf>();
  build_mesh_sdf(mesh, voxel, 4.0f * voxel, c.mesh.file, path + ".file", *sdf);
  return sdf;
}

kernels::CollisionShape to_shape(const ColliderDef& c, const MeshSdf* sdf) {
  kernels::CollisionShape s;
  s.friction = c.friction;
  switch (c.shape) {
    case ColliderDef::Shape::Plane:
      s.kind = kernels::CollisionShape::Kind::Plane;
      std::copy(c.point.begin(), c.point.end(), s.a);
      std::copy(c.normal.begin(), c.normal.end(), s.b);
      break;
    case ColliderDef::Shape::Box:
      s.kind = kernels::CollisionShape::Kind::Box;
      std::copy(c.box.min.begin(), c.box.min.end(), s.a);
      std::copy(c.box.max.begin(), c.box.max.end(), s.b);
      break;
    case ColliderDef::Shape::Sphere:
      s.kind = kernels::CollisionShape::Kind::Sphere;
      std::copy(c.center.begin(), c.center.end(), s.a);
      s.radius = c.radius;
      break;
    case ColliderDef::Shape::Capsule:
      s.kind = kernels::CollisionShape::Kind::Capsule;
      std::copy(c.end_a.begin(), c.end_a.end(), s.a);
      std::copy(c.end_b.begin(), c.end_b.end(), s.b);
      s.radius = c.radius;
      break;
    case ColliderDef::Shape::Mesh:
      s.kind = kernels::CollisionShape::Kind::Sdf;
      s.sdf = &sdf->grid;
      break;
  }
  return s;
}

}  // namespace

Simulation::Simulation(const SceneDef& scene) : scene_(scene) {
  create_particles();
  move_into_domain();
  create_distance_constraints();
  create_colliders();
  assemble_pipeline();
}

// Raw particles first (their index is the scene's index), then the fluid blocks' lattices, then
// the cloths' vertices.
void Simulation::create_particles() {
  std::size_t fluid_count = 0;
  for (const FluidDef& f : scene_.fluids) {
    const auto n = lattice_counts(f);
    fluid_count += n[0] * n[1] * n[2];
  }
  const std::size_t raw_count = scene_.particles.size();
  if (!scene_.cloths.empty()) cloth_ = std::make_unique<ClothSolver>(scene_);
  const std::size_t cloth_count = cloth_ ? cloth_->vertex_count() : 0;
  store_.resize(raw_count + fluid_count + cloth_count);
  for (std::size_t k = 0; k < raw_count; ++k) {
    const ParticleDef& p = scene_.particles[k];
    store_.x[k] = p.x[0], store_.y[k] = p.x[1], store_.z[k] = p.x[2];
    store_.vx[k] = p.v[0], store_.vy[k] = p.v[1], store_.vz[k] = p.v[2];
    store_.w[k] = p.mass > 0.0f ? 1.0f / p.mass : 0.0f;
    store_.phase[k] = make_phase(Material::Free);
  }
  if (!scene_.fluids.empty()) {
    neighborhood_ = std::make_unique<Neighborhood>();
    fluid_ = std::make_unique<FluidSolver>(scene_.fluids[0], scene_.solver, scene_.domain, store_,
                                           *neighborhood_);
    neighborhood_->radius = fluid_->kernel_radius();
    std::size_t k = raw_count;
    for (std::size_t b = 0; b < scene_.fluids.size(); ++b) {
      const FluidDef& f = scene_.fluids[b];
      const auto n = lattice_counts(f);
      for (std::size_t iz = 0; iz < n[2]; ++iz)
        for (std::size_t iy = 0; iy < n[1]; ++iy)
          for (std::size_t ix = 0; ix < n[0]; ++ix, ++k) {
            store_.x[k] = f.box.min[0] + (float(ix) + 0.5f) * f.spacing;
            store_.y[k] = f.box.min[1] + (float(iy) + 0.5f) * f.spacing;
            store_.z[k] = f.box.min[2] + (float(iz) + 0.5f) * f.spacing;
            store_.vx[k] = f.velocity[0], store_.vy[k] = f.velocity[1], store_.vz[k] = f.velocity[2];
            store_.w[k] = 1.0f / fluid_->particle_mass();
            store_.phase[k] = make_phase(Material::Fluid, std::uint32_t(b));
          }
    }
    // The grid covers the domain (grown by one cell); particles outside clamp to border cells.
    const float h = neighborhood_->radius;
    float lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = scene_.domain.min[a] - h, hi[a] = scene_.domain.max[a] + h;
    neighborhood_->spec = neighbor::make_grid_spec(lo, hi, h, std::max<std::size_t>(4 * fluid_count, 1 << 16));
    fluid_probe_ = std::make_unique<FluidErrorProbe>(fluid_->params(), neighborhood_->spec, h);
  }
  for (std::size_t k = 0; k < store_.size(); ++k) {
    store_.id[k] = std::int32_t(k);
    store_.px[k] = store_.x[k], store_.py[k] = store_.y[k], store_.pz[k] = store_.z[k];
  }
  if (cloth_) {
    const std::size_t first = raw_count + fluid_count;
    cloth_->create(store_, first, view());
    for (std::size_t k = first; k < store_.size(); ++k)
      store_.px[k] = store_.x[k], store_.py[k] = store_.y[k], store_.pz[k] = store_.z[k];
    index_remappers_.push_back([this](std::span<const std::uint32_t> m) { cloth_->remap(m); });
    if (ParticleContactStage::needed(scene_))
      contacts_ = std::make_unique<ParticleContactStage>(*cloth_, scene_.domain,
                                                         fluid_ ? fluid_->particle_radius() : 0.0f);
  }
}

// A particle created outside the domain would be projected onto its wall by the first substep,
// and the velocity update would turn that jump into a speed of jump / dt: so it starts there.
void Simulation::move_into_domain() {
  const Vec3 &lo = scene_.domain.min, &hi = scene_.domain.max;
  for (std::size_t k = 0; k < store_.size(); ++k) {
    float* x[3] = {&store_.x[k], &store_.y[k], &store_.z[k]};
    bool moved = false;
    for (int a = 0; a < 3; ++a) {
      const float inside = std::clamp(*x[a], lo[a], hi[a]);  // NaN stays NaN (and is reported)
      if (std::isnan(*x[a]) || inside == *x[a]) continue;
      *x[a] = inside;
      moved = true;
    }
    if (!moved) continue;
    ++moved_into_domain_;
    store_.px[k] = store_.x[k], store_.py[k] = store_.y[k], store_.pz[k] = store_.z[k];
  }
}

void Simulation::create_distance_constraints() {
  if (!scene_.distance_constraints.empty()) {
    std::vector<std::uint32_t> ci, cj;
    std::vector<float> rest, compliance;
    for (const DistanceConstraintDef& d : scene_.distance_constraints) {
      ci.push_back(std::uint32_t(d.i));
      cj.push_back(std::uint32_t(d.j));
      rest.push_back(d.rest_length);
      compliance.push_back(d.compliance);
    }
    distance_ = std::make_unique<DistanceSolver>(ci, cj, rest, compliance, view());
    index_remappers_.push_back([this](std::span<const std::uint32_t> m) { distance_->remap(m); });
  }
}

// The domain always, plus the scene's colliders.
void Simulation::create_colliders() {
  collision_params_ = std::make_unique<kernels::CollisionParams>();
  for (int a = 0; a < 3; ++a) {
    collision_params_->domain_min[a] = scene_.domain.min[a];
    collision_params_->domain_max[a] = scene_.domain.max[a];
  }
  collision_params_->domain_friction = scene_.domain.friction;
  collision_params_->fluid_radius = fluid_ ? fluid_->particle_radius() : 0.0f;
  if (cloth_) collision_params_->cloth_radius = cloth_->collision_radius().data();
  for (std::size_t k = 0; k < scene_.colliders.size(); ++k) {
    const ColliderDef& c = scene_.colliders[k];
    if (c.shape == ColliderDef::Shape::Mesh) mesh_sdfs_.push_back(build_collider_sdf(c, k));
    colliders_.push_back(to_shape(c, c.shape == ColliderDef::Shape::Mesh ? mesh_sdfs_.back().get() : nullptr));
  }
}

// Only what this scene needs: a pass whose material or coefficient is absent is not built.
void Simulation::assemble_pipeline() {
  const SolverDef& solver = scene_.solver;
  density_tolerance_ = fluid_ ? solver.density_tolerance : 0.0f;
  iteration_cap_ = density_tolerance_ > 0.0f ? std::max(solver.iterations, solver.max_iterations) : solver.iterations;
  if (distance_) {
    begin_substep_passes_.push_back({"distance", [this](const StepContext&) { distance_->begin_substep(); }});
  }
  if (cloth_) {
    begin_substep_passes_.push_back({"cloth", [this](const StepContext&) { cloth_->begin_substep(); }});
  }
  if (fluid_) {
    constraint_passes_.push_back({"fluid density", [this](const StepContext& c) {
                                    // The error is needed from the last fixed iteration on.
                                    fluid_->solve_density(density_tolerance_ > 0.0f &&
                                                          c.iteration + 1 >= scene_.solver.iterations);
                                  }});
  }
  if (distance_) {
    constraint_passes_.push_back({"distance", [this](const StepContext& c) { distance_->solve(view(), c.dt); }});
  }
  if (cloth_) {
    // Bending must directly follow stretch: the stretch pass leaves the positions packed for it,
    // and px, py, pz are stale until bending unpacks them (ClothSolver::solve_stretch).
    constraint_passes_.push_back({"cloth stretch", [this](const StepContext& c) {
                                    cloth_->solve_stretch(view(), c.dt, c.iteration);
                                  }});
    if (cloth_->has_bending())
      constraint_passes_.push_back({"cloth bending", [this](const StepContext& c) {
                                      cloth_->solve_bending(view(), c.dt, c.iteration);
                                    }});
    if (cloth_->has_tethers())
      constraint_passes_.push_back({"tethers", [this](const StepContext&) { cloth_->solve_tethers(view()); }});
  }
  if (contacts_) {
    constraint_passes_.push_back({"particle contacts", [this](const StepContext&) { contacts_->solve(view()); }});
  }
  constraint_passes_.push_back({"collisions", [this](const StepContext&) {
                                  kernels::solve_collisions(view(), *collision_params_, colliders_);
                                }});
  if (scene_.solver.damping > 0.0f) {
    velocity_passes_.push_back({"damping", [this](const StepContext& c) {
                                  kernels::damp_velocities(view(), std::exp(-scene_.solver.damping * c.dt));
                                }});
  }
  if (fluid_ && fluid_->has_vorticity()) {
    velocity_passes_.push_back({"vorticity", [this](const StepContext& c) { fluid_->apply_vorticity_confinement(c.dt); }});
  }
  if (fluid_ && fluid_->has_viscosity()) {
    velocity_passes_.push_back({"viscosity", [this](const StepContext&) { fluid_->apply_viscosity(); }});
  }
}

Simulation::~Simulation() = default;

kernels::ParticleView Simulation::view() {
  kernels::ParticleView v;
  v.n = store_.size();
  v.x = store_.x.data(), v.y = store_.y.data(), v.z = store_.z.data();
  v.px = store_.px.data(), v.py = store_.py.data(), v.pz = store_.pz.data();
  v.vx = store_.vx.data(), v.vy = store_.vy.data(), v.vz = store_.vz.data();
  v.w = store_.w.data();
  v.phase = store_.phase.data();
  return v;
}

std::vector<std::string> Simulation::pipeline() const {
  std::vector<std::string> names{"predict"};
  if (neighborhood_) names.push_back("neighbors");
  if (contacts_) names.push_back("contact pairs");
  for (const Pass& p : constraint_passes_) names.push_back(p.name);
  names.push_back("update");
  for (const Pass& p : velocity_passes_) names.push_back(p.name);
  return names;
}

FrameMetrics Simulation::step_frame(FrameMeasure measure_frame) {
  timer_.begin_frame();
  StepContext ctx;
  ctx.dt = float(scene_.solver.frame_dt / scene_.solver.substeps);
  long iterations = 0;
  int iterations_max = 0;
  for (ctx.substep = 0; ctx.substep < scene_.solver.substeps; ++ctx.substep) {
    substep(ctx);
    iterations += ctx.iteration;
    iterations_max = std::max(iterations_max, ctx.iteration);
  }
  ++frame_;
  time_ = frame_ * scene_.solver.frame_dt;
  FrameMetrics m;
  if (measure_frame == FrameMeasure::Full) {
    timer_.time("metrics", [&] { m = measure(); });
  } else {
    m.frame = frame_;
    m.time = time_;
    m.particles = store_.size();
  }
  m.iterations_mean = double(iterations) / scene_.solver.substeps;
  m.iterations_max = iterations_max;
  return m;
}

void Simulation::substep(StepContext& ctx) {
  const float* g = scene_.solver.gravity.data();
  timer_.time("predict", [&] { kernels::predict_positions(view(), ctx.dt, g); });
  if (neighborhood_) timer_.time("neighbors", [&] { find_neighbors(); });
  if (contacts_) timer_.time("contact pairs", [&] { contacts_->find_candidates(store_, neighborhood_.get()); });
  for (const Pass& p : begin_substep_passes_) p.run(ctx);
  // `iterations` of every constraint pass, then more while the fluid is too compressed (see
  // SolverDef::density_tolerance); ctx.iteration ends as the number run.
  for (ctx.iteration = 0; ctx.iteration < iteration_cap_;) {
    for (const Pass& p : constraint_passes_) timer_.time(p.name, [&] { p.run(ctx); });
    ++ctx.iteration;
    if (ctx.iteration >= scene_.solver.iterations && !fluid_needs_iteration()) break;
  }
  timer_.time("update", [&] { kernels::update_velocities(view(), ctx.dt); });
  for (const Pass& p : velocity_passes_) timer_.time(p.name, [&] { p.run(ctx); });
}

bool Simulation::fluid_needs_iteration() const {
  return density_tolerance_ > 0.0f && fluid_->predicted_density_error() > density_tolerance_;
}

void Simulation::find_neighbors() {
  Neighborhood& nb = *neighborhood_;
  const std::size_t n = store_.size();
  nb.build_grid(store_.px.data(), store_.py.data(), store_.pz.data(), store_.phase.data(), n);
  reorder(nb.grid.order());
  neighbor::build_neighbor_list(nb.grid, store_.px.data(), store_.py.data(), store_.pz.data(),
                                n, nb.radius, nb.list);
}

void Simulation::reorder(std::span<const std::uint32_t> order) {
  store_.reorder(order);
  if (index_remappers_.empty()) return;
  const std::vector<std::uint32_t> new_index = inverse_permutation(order);
  for (auto& remap : index_remappers_) remap(new_index);
}

void Simulation::restore_state(const ParticleStore& saved, int frames_done) {
  const std::size_t n = store_.size();
  if (saved.size() != n)
    throw std::invalid_argument("Simulation::restore_state: the saved state has another particle count");
  // order[k] = the current index of the particle that the saved state holds at k.
  const std::vector<std::uint32_t> index_of_id = store_.index_of_id();
  std::vector<std::uint32_t> order(n);
  for (std::size_t k = 0; k < n; ++k) order[k] = index_of_id[std::size_t(saved.id[k])];
  reorder(order);
  auto copy = [n](auto& to, const auto& from) { std::copy(from.data(), from.data() + n, to.data()); };
  copy(store_.x, saved.x), copy(store_.y, saved.y), copy(store_.z, saved.z);
  copy(store_.px, saved.px), copy(store_.py, saved.py), copy(store_.pz, saved.pz);
  copy(store_.vx, saved.vx), copy(store_.vy, saved.vy), copy(store_.vz, saved.vz);
  copy(store_.w, saved.w), copy(store_.phase, saved.phase), copy(store_.id, saved.id);
  frame_ = frames_done;
  time_ = frame_ * scene_.solver.frame_dt;
}

std::span<const float> Simulation::cloth_stretch_multipliers() const {
  return cloth_ ? cloth_->stretch_multipliers() : std::span<const float>();
}

void Simulation::restore_cloth_stretch_multipliers(std::span<const float> saved) {
  if (cloth_) cloth_->restore_stretch_multipliers(saved);
}

FrameMetrics Simulation::state_metrics() const {
  FrameMetrics m;
  m.frame = frame_;
  m.time = time_;
  m.particles = store_.size();
  struct Health {
    double kinetic = 0.0, potential = 0.0, max_speed2 = 0.0;
    std::size_t non_finite = 0, outside = 0;
  };
  const Vec3& g = scene_.solver.gravity;
  const Vec3 &lo = scene_.domain.min, &hi = scene_.domain.max;
  const Health h = blocked_reduce(
      store_.size(), Health{},
      [&](std::size_t b, std::size_t e) {
        Health part;
        for (std::size_t i = b; i < e; ++i) {
          const float values[6] = {store_.x[i], store_.y[i], store_.z[i],
                                   store_.vx[i], store_.vy[i], store_.vz[i]};
          for (float v : values) part.non_finite += std::isfinite(v) ? 0 : 1;
          const double v2 = double(store_.vx[i]) * store_.vx[i] + double(store_.vy[i]) * store_.vy[i] +
                            double(store_.vz[i]) * store_.vz[i];
          if (store_.w[i] > 0.0f) {
            part.kinetic += 0.5 * v2 / store_.w[i];
            const double height = -(double(g[0]) * (store_.x[i] - lo[0]) + double(g[1]) * (store_.y[i] - lo[1]) +
                                    double(g[2]) * (store_.z[i] - lo[2]));
            part.potential += height / store_.w[i];
          }
          part.max_speed2 = std::max(part.max_speed2, v2);
          const bool inside = store_.x[i] >= lo[0] && store_.x[i] <= hi[0] && store_.y[i] >= lo[1] &&
                              store_.y[i] <= hi[1] && store_.z[i] >= lo[2] && store_.z[i] <= hi[2];
          part.outside += inside ? 0 : 1;
        }
        return part;
      },
      [](Health& acc, const Health& p) {
        acc.kinetic += p.kinetic;
        acc.potential += p.potential;
        acc.outside += p.outside;
        acc.max_speed2 = std::max(acc.max_speed2, p.max_speed2);
        acc.non_finite += p.non_finite;
      });
  m.kinetic_energy = h.kinetic;
  m.potential_energy = h.potential;
  m.outside_domain = h.outside;
  m.max_speed = std::sqrt(h.max_speed2);
  m.non_finite = h.non_finite;
  return m;
}

FrameMetrics Simulation::measure() {
  FrameMetrics m = state_metrics();
  // The last substep's neighbor lists were built on its predicted positions; particles have
  // moved since, and stale lists could only miss pairs (under-report). The probe builds lists of
  // its own on the final positions, on a copy: the simulation's neighbor stage would reorder the
  // store, and with it the bits of every later frame.
  if (fluid_) m.fluid = fluid_probe_->measure(store_);
  if (distance_) m.distance = distance_->measure(view());
  if (cloth_) m.cloth = cloth_->measure(view());
  return m;
}

}  // namespace seiche
