// Particle contacts of cloth and shapes (particle_contact_stage.hpp): candidate pairs found once
// per substep on the predicted positions (after the fluid's neighbor stage, whose grid it reads
// for cloth-fluid pairs), the contacts solved every iteration. Present when a cloth collides with
// itself, with another cloth or with fluid, or shapes meet shapes or cloth
// (ParticleContactStage::needed).
#pragma once

#include <memory>

#include "loop/family.hpp"
#include "families/fluid/neighborhood.hpp"
#include "particle_contact_stage.hpp"
#include "seiche/particle_store.hpp"

namespace seiche {

class ContactFamily final : public Family {
 public:
  /// `cloth`: the scene's cloths, or null without cloth; `fluid`: the fluid's neighbor stage, or
  /// null without fluid; `fluid_radius`: its particles' collision radius (0 without fluid).
  ContactFamily(const ClothSolver* cloth, const SceneDef& scene, ParticleStore& store, const Neighborhood* fluid,
                float fluid_radius)
      : store_(store), fluid_(fluid), stage_(std::make_unique<ParticleContactStage>(cloth, scene, fluid_radius)) {}

  void add_passes(std::vector<Pass>& passes) override;

 private:
  ParticleStore& store_;
  const Neighborhood* fluid_;
  std::unique_ptr<ParticleContactStage> stage_;
};

}  // namespace seiche
