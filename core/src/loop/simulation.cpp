#include "seiche/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "families/cloth/cloth_family.hpp"
#include "families/distance/distance_family.hpp"
#include "families/fluid/fluid_family.hpp"
#include "families/rigid/rigid_family.hpp"
#include "family.hpp"
#include "family_registry.hpp"
#include "iteration_record.hpp"
#include "seiche/kernels/blocked_reduce.hpp"
#include "seiche/memory_estimate.hpp"

namespace seiche {

Simulation::Simulation(const SceneDef& scene)
    : scene_(scene), record_(std::make_unique<IterationRecord>()) {
  create_families();
  assemble_pipeline();
  reset_record_range();
}

Simulation::~Simulation() = default;

// The families of the scene's sections, built by the registry's rows (family_registry.hpp):
// the particle-creating rows, the move into the domain, then the rows over existing particles.
void Simulation::create_families() {
  FamilyBuild build(scene_, store_, families_, [this](std::span<const std::uint32_t> order) { reorder(order); });
  auto run_rows = [&](FamilyRow::Phase phase) {
    for (const FamilyRow& row : family_rows()) {
      if (row.phase != phase) continue;
      const std::size_t first = store_.size();
      row.build(build);
      for (std::size_t k = first; k < store_.size(); ++k)  // the new particles start at rest
        store_.px[k] = store_.x[k], store_.py[k] = store_.y[k], store_.pz[k] = store_.z[k];
    }
  };
  store_.reserve(scene_particle_count(scene_));  // one allocation per column, not one per family
  run_rows(FamilyRow::Phase::Particles);
  move_into_domain();
  run_rows(FamilyRow::Phase::OnParticles);
  fluid_ = build.find<FluidFamily>();
  distance_ = build.find<DistanceFamily>();
  cloth_ = build.find<ClothFamily>();
  rigid_ = build.find<RigidFamily>();
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

// Every family's passes, sorted by stage and then by order key (stable: equal keys keep the
// families' order), and the iteration cap.
void Simulation::assemble_pipeline() {
  for (const auto& f : families_) f->add_passes(passes_);
  std::stable_sort(passes_.begin(), passes_.end(), [](const Pass& a, const Pass& b) {
    return a.stage != b.stage ? a.stage < b.stage : a.order < b.order;
  });
  stage_begin_.assign(kStageCount + 1, passes_.size());
  for (std::size_t k = passes_.size(); k-- > 0;) stage_begin_[std::size_t(passes_[k].stage)] = k;
  for (int s = kStageCount - 1; s >= 0; --s)  // a stage without passes begins where the next does
    stage_begin_[s] = std::min(stage_begin_[s], stage_begin_[s + 1]);
  const bool votes = std::any_of(families_.begin(), families_.end(),
                                 [](const auto& f) { return f->votes_on_iterations(); });
  const SolverDef& solver = scene_.solver;
  iteration_cap_ = votes ? std::max(solver.iterations, solver.max_iterations) : solver.iterations;
}

const ClothSolver* Simulation::cloth() const { return cloth_ ? &cloth_->solver() : nullptr; }
const DistanceSolver* Simulation::distance() const { return distance_ ? &distance_->solver() : nullptr; }

std::vector<BodyPose> Simulation::body_poses() const {
  return rigid_ ? rigid_->poses() : std::vector<BodyPose>{};
}

std::vector<std::string> Simulation::pipeline() const {
  // A family's work split over consecutive passes by layout under one name (cloth stretch: the
  // forests on the columns, the colored edges on the record) is timed and listed once.
  std::vector<std::string> names;
  for (const Pass& p : passes_)
    if (p.reported && (names.empty() || names.back() != p.name)) names.push_back(p.name);
  return names;
}

FrameMetrics Simulation::step_frame(FrameMeasure measure_frame) {
  timer_.begin_frame();
  StepContext ctx;
  ctx.packed = &record_->packed();
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

void Simulation::run_stage(int stage, const StepContext& ctx) {
  for (std::size_t k = stage_begin_[stage]; k < stage_begin_[stage + 1]; ++k) {
    const Pass& p = passes_[k];
    // Its layout up to date first (a pack or an unpack when the other was written last), timed
    // as part of the pass.
    const auto run = [&] {
      record_->prepare(p.layout, particle_view(store_));
      p.run(ctx);
    };
    if (p.reported) timer_.time(p.name, run);
    else run();
  }
}

void Simulation::substep(StepContext& ctx) {
  run_stage(int(Stage::Predict), ctx);
  run_stage(int(Stage::Neighbors), ctx);
  run_stage(int(Stage::BeginSubstep), ctx);
  // `iterations` of every constraint pass, then more while a family votes for them (the fluid's
  // SolverDef::density_tolerance), up to the cap; ctx.iteration ends as the number run.
  for (ctx.iteration = 0; ctx.iteration < iteration_cap_;) {
    run_stage(int(Stage::Iterate), ctx);
    ++ctx.iteration;
    if (ctx.iteration >= scene_.solver.iterations && !a_family_wants_iteration()) break;
  }
  record_->prepare(Layout::Columns, particle_view(store_));  // update and the frame read the columns
  run_stage(int(Stage::Update), ctx);
  run_stage(int(Stage::Velocity), ctx);
}

bool Simulation::a_family_wants_iteration() const {
  return std::any_of(families_.begin(), families_.end(), [](const auto& f) { return f->wants_iteration(); });
}

void Simulation::reorder(std::span<const std::uint32_t> order) {
  record_->prepare(Layout::Columns, particle_view(store_));
  store_.reorder(order);
  const std::vector<std::uint32_t> new_index = inverse_permutation(order);
  for (const auto& f : families_) f->remap(new_index);
  reset_record_range();
}

void Simulation::reset_record_range() {
  kernels::IndexRange all;
  for (const auto& f : families_) {
    const kernels::IndexRange r = f->packed_range();
    if (r.empty()) continue;
    all = all.empty() ? r : kernels::IndexRange{std::min(all.lo, r.lo), std::max(all.hi, r.hi)};
  }
  record_->reset(all);
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
  for (const StoreColumn& to : store_.columns()) {
    if (to.kind != ColumnKind::State) continue;
    const StoreColumn* from = saved.find(to.name);
    if (from == nullptr || from->type() != to.type())
      throw std::invalid_argument("Simulation::restore_state: the saved state has no column " + to.name);
    if (n > 0)  // a scene of rigid bodies only has no particles, and its columns no buffers
      std::memcpy(store_.find(to.name)->raw(), from->raw(), n * StoreColumn::kElementBytes);
  }
  frame_ = frames_done;
  time_ = frame_ * scene_.solver.frame_dt;
}

CheckpointChunks Simulation::family_state() const {
  CheckpointChunks chunks;
  for (const auto& f : families_) f->save_state(chunks);
  return chunks;
}

void Simulation::restore_family_state(const CheckpointChunks& chunks) {
  for (const auto& f : families_) f->restore_state(chunks);
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
  const Health h = kernels::blocked_reduce(
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
  for (const auto& f : families_) f->measure(m);
  return m;
}

}  // namespace seiche
