#include "contact_family.hpp"

namespace seiche {

void ContactFamily::add_passes(std::vector<Pass>& passes) {
  passes.push_back({"contact pairs", Stage::Neighbors, pass_order::kContactPairs, true,
                    [this](const StepContext&) { stage_->find_candidates(store_, fluid_); }});
  passes.push_back({"particle contacts", Stage::Iterate, pass_order::kParticleContacts, true,
                    [this](const StepContext&) { stage_->solve(particle_view(store_)); }});
}

}  // namespace seiche
