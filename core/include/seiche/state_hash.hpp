// A fingerprint of the simulated state, for the determinism tests (golden values), the bench and
// bug reports: two runs with the same hash have the same positions and velocities, bit for bit.
//
// Definition (so that anyone can recompute it): 64-bit FNV-1a (offset basis
// 0xcbf29ce484222325, prime 0x100000001b3) over the bytes of x, y, z, vx, vy, vz of every
// particle, particles in id order (id 0 first, whatever the store's order), each value's IEEE
// 754 binary32 bit pattern as 4 bytes, least significant byte first. So the hash does not depend
// on the machine's byte order nor on the store's particle order, and -0.0 and +0.0 (or two NaNs
// with different payloads) hash differently: it compares bits, not values.
//
// The rigid bodies (their own double-precision state, not particles) have a hash of their own,
// body_state_hash: the same FNV-1a, continued from the offset basis over every body in scene
// order, its position, orientation [w, x, y, z], velocity and angular velocity, each value's IEEE
// 754 binary64 bit pattern as 8 bytes, least significant byte first.
#pragma once

#include <cstdint>
#include <span>

#include "seiche/frame_exporter.hpp"
#include "seiche/particle_store.hpp"

namespace seiche {

/// The hash of the store's positions and velocities (see above). Ids must be a permutation of
/// [0, size()), as the simulation keeps them.
std::uint64_t state_hash(const ParticleStore& store);

/// The hash of the rigid bodies' state (see above; Simulation::body_poses gives them).
std::uint64_t body_state_hash(std::span<const BodyPose> bodies);

}  // namespace seiche
