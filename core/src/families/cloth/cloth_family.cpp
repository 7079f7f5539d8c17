#include "cloth_family.hpp"

namespace seiche {

void ClothFamily::add_passes(std::vector<Pass>& passes) {
  passes.push_back({"cloth", Stage::BeginSubstep, pass_order::kClothReset, false,
                    [this](const StepContext&) { solver_->begin_substep(); }});
  passes.push_back({"cloth stretch", Stage::Iterate, pass_order::kClothStretch, true, [this](const StepContext& c) {
                      solver_->solve_stretch(particle_view(store_), c.dt, c.iteration);
                    }});
  // Bending directly follows stretch (pass_order): the stretch pass leaves the positions packed
  // for it, and px, py, pz are stale until bending unpacks them (ClothSolver::solve_stretch).
  if (solver_->has_bending())
    passes.push_back({"cloth bending", Stage::Iterate, pass_order::kClothBending, true, [this](const StepContext& c) {
                        solver_->solve_bending(particle_view(store_), c.dt, c.iteration);
                      }});
  if (solver_->has_tethers())
    passes.push_back({"tethers", Stage::Iterate, pass_order::kTethers, true,
                      [this](const StepContext&) { solver_->solve_tethers(particle_view(store_)); }});
}

void ClothFamily::measure(FrameMetrics& m) {
  const ClothError e = solver_->measure(particle_view(store_));
  m.errors.push_back({"cloth_strain", "cloth strain", ErrorUnit::Ratio, e.strain_mean, e.strain_max});
  m.errors.push_back({"cloth_bending_error", "cloth bending", ErrorUnit::Radians, e.bending_mean, e.bending_max});
}

namespace {
constexpr const char* kStretchMultipliers = "cloth.stretch_multipliers";
}

void ClothFamily::save_state(CheckpointChunks& chunks) const {
  chunks.put_values(kStretchMultipliers, solver_->stretch_multipliers());
}

void ClothFamily::restore_state(const CheckpointChunks& chunks) {
  std::vector<float> saved(solver_->stretch_multipliers().size());
  chunks.get_values(kStretchMultipliers, std::span<float>(saved));
  solver_->restore_stretch_multipliers(saved);
}

}  // namespace seiche
