#include "cloth_family.hpp"

namespace seiche {

void ClothFamily::add_passes(std::vector<Pass>& passes) {
  passes.push_back({"cloth", Stage::BeginSubstep, pass_order::kClothReset, false,
                    [this](const StepContext&) { solver_->begin_substep(); }});
  // Stretch in two passes under one name: the forests on the columns, then the colored edges on
  // the iteration record, which bending goes on with (one pack for both, done by the loop).
  if (solver_->has_stretch_forests())
    passes.push_back({"cloth stretch", Stage::Iterate, pass_order::kClothStretchForests, true,
                      [this](const StepContext& c) { solver_->solve_stretch_forests(particle_view(store_), c.dt); }});
  passes.push_back({"cloth stretch", Stage::Iterate, pass_order::kClothStretch, true,
                    [this](const StepContext& c) { solver_->solve_stretch(*c.packed, c.dt, c.iteration); },
                    Layout::Packed});
  if (solver_->has_bending())
    passes.push_back({"cloth bending", Stage::Iterate, pass_order::kClothBending, true,
                      [this](const StepContext& c) { solver_->solve_bending(*c.packed, c.dt, c.iteration); },
                      Layout::Packed});
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
