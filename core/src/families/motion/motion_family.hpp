// The motion every particle has: the prediction at the start of a substep, the velocity update
// at its end, and velocity damping where the scene asks for it (kernels/integrate.hpp).
#pragma once

#include "loop/family.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

class MotionFamily final : public Family {
 public:
  MotionFamily(ParticleStore& store, const SolverDef& solver) : store_(store), solver_(solver) {}
  void add_passes(std::vector<Pass>& passes) override;

 private:
  ParticleStore& store_;
  const SolverDef& solver_;
};

}  // namespace seiche
