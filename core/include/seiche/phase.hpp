// The phase word of a particle: its material in the low 8 bits and its object (group) index in
// the high 24 bits. Host code only (the neighbor grid, the particle contacts, the exporters):
// kernels know no materials, they read per-particle columns such as the collision radius.
#pragma once

#include <cstdint>

namespace seiche {

enum class Material : std::uint8_t {
  Free = 0,   ///< a raw particle: constraints and colliders only
  Fluid = 1,  ///< Position Based Fluids
  Cloth = 2,  ///< a cloth's vertex; the group is the cloth's index in the scene
  Shape = 3,  ///< a shape-matched particle; the group is the shape's index in the scene
};

constexpr std::uint32_t make_phase(Material m, std::uint32_t group = 0) {
  return std::uint32_t(m) | (group << 8);
}
constexpr Material phase_material(std::uint32_t phase) { return Material(phase & 0xffu); }

}  // namespace seiche
