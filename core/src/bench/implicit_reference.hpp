// The implicit-Euler reference of a scene (implicit_euler.hpp): which scenes it can model, and
// its mechanical system taken from a freshly built simulation, so that the reference starts
// from exactly the particles, masses and constraints the XPBD runs start from.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "implicit_euler.hpp"
#include "seiche/scene.hpp"
#include "seiche/simulation.hpp"

namespace seiche {

/// Why the implicit-Euler reference cannot model this scene ("" when it can): it models raw
/// particles, distance constraints and cloths with isometric bending under gravity; not fluid,
/// colliders, contacts, tethers, dihedral bending or damping.
std::string implicit_reference_unsupported(const SceneDef& scene);

/// The system of `sim` as built (before its first step), particles in store order, and the id
/// of each store index (to write positions in id order).
struct ImplicitReferenceSystem {
  ImplicitEulerSystem system;
  std::vector<std::int32_t> id_of_index;
};
ImplicitReferenceSystem implicit_reference_system(const Simulation& sim);

}  // namespace seiche
