// The two ends of an XPBD substep (Macklin et al. 2016, "small steps" Macklin et al. 2019):
//   predict:  v += dt g   (free particles, w > 0),   p = x + dt v
//   update:   v = (p - x) / dt,                       x = p
//   damping:  v *= exp(-c dt)  (free particles; an optional velocity pass, c in 1/s)
// A pinned particle (w = 0) feels no gravity and keeps its velocity, so it stays put or moves
// at constant velocity (a kinematic particle).
#pragma once

#include "seiche/kernels/particle_view.hpp"

namespace seiche::kernels {

void predict_positions(const ParticleView& p, float dt, const float gravity[3]);
void update_velocities(const ParticleView& p, float dt);
/// v *= factor for free particles (factor = exp(-damping dt), computed by the caller).
void damp_velocities(const ParticleView& p, float factor);

}  // namespace seiche::kernels
