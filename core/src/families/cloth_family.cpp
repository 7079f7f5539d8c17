#include "families/cloth_family.hpp"

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

}  // namespace seiche
