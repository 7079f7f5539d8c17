#include "distance_family.hpp"

namespace seiche {

DistanceFamily::DistanceFamily(const SceneDef& scene, ParticleStore& store) : store_(store) {
  std::vector<std::uint32_t> ci, cj;
  std::vector<float> rest, compliance;
  for (const DistanceConstraintDef& d : scene.distance_constraints) {
    ci.push_back(std::uint32_t(d.i));
    cj.push_back(std::uint32_t(d.j));
    rest.push_back(d.rest_length);
    compliance.push_back(d.compliance);
  }
  solver_ = std::make_unique<DistanceSolver>(ci, cj, rest, compliance, particle_view(store),
                                             scene.solver.distance_forests);
}

void DistanceFamily::add_passes(std::vector<Pass>& passes) {
  passes.push_back({"distance", Stage::BeginSubstep, pass_order::kDistanceReset, false,
                    [this](const StepContext&) { solver_->begin_substep(); }});
  // Two passes under one name: the forests on the columns, then the colored constraints on the
  // iteration record.
  if (solver_->has_forests())
    passes.push_back({"distance", Stage::Iterate, pass_order::kDistanceForests, true,
                      [this](const StepContext& c) { solver_->solve_forests(particle_view(store_), c.dt); }});
  passes.push_back({"distance", Stage::Iterate, pass_order::kDistance, true,
                    [this](const StepContext& c) { solver_->solve(*c.packed, c.dt); }, Layout::Packed});
}

void DistanceFamily::measure(FrameMetrics& m) {
  const DistanceConstraintError e = solver_->measure(particle_view(store_));
  m.errors.push_back({"distance_error", "distance", ErrorUnit::Ratio, e.mean, e.max});
}

namespace {
constexpr const char* kMultipliers = "distance.multipliers";
}

void DistanceFamily::save_state(CheckpointChunks& chunks) const { chunks.put_values(kMultipliers, solver_->multipliers()); }

void DistanceFamily::restore_state(const CheckpointChunks& chunks) {
  std::vector<float> saved(solver_->multipliers().size());
  chunks.get_values(kMultipliers, std::span<float>(saved));
  solver_->restore_multipliers(saved);
}

}  // namespace seiche
