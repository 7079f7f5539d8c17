#include "motion_family.hpp"

#include <cmath>

#include "seiche/kernels/integrate.hpp"

namespace seiche {

void MotionFamily::add_passes(std::vector<Pass>& passes) {
  passes.push_back({"predict", Stage::Predict, pass_order::kPredict, true, [this](const StepContext& c) {
                      kernels::predict_positions(particle_view(store_), c.dt, solver_.gravity.data());
                    }});
  passes.push_back({"update", Stage::Update, pass_order::kUpdate, true, [this](const StepContext& c) {
                      kernels::update_velocities(particle_view(store_), c.dt);
                    }});
  if (solver_.damping > 0.0f)
    passes.push_back({"damping", Stage::Velocity, pass_order::kDamping, true, [this](const StepContext& c) {
                        kernels::damp_velocities(particle_view(store_), std::exp(-solver_.damping * c.dt));
                      }});
}

}  // namespace seiche
