// Particle-particle contacts (cloth self-collision, cloth-cloth, cloth-fluid and shapes; Macklin et al.
// 2014, "Unified particle physics", sec. 5 and 6.1): two particles closer than their contact
// distance r are pushed apart along n = (p_i - p_j) / |p_i - p_j|,
//   dp_i = w_i / (w_i + w_j) (r - |p_i - p_j|) n,
// then friction removes the relative tangential motion of the substep (as for shapes,
// collisions.hpp; static when it is below mu times the depth, else scaled to mu times it).
// Jacobi with averaging: every particle sums its own corrections from its partners (each pair
// is listed from both sides), divides by the count of active contacts, and all corrections are
// applied after all are computed. No atomics, no order dependence: bit-identical results with
// any thread count. Coincident particles (|p_i - p_j| < 1e-9 m) have no normal and are skipped.
#pragma once

#include <cstdint>
#include <vector>

#include "seiche/kernels/particle_view.hpp"

namespace seiche::kernels {

/// Contact candidates in CSR form: particle[g] has partners [start[g], start[g + 1]).
struct ParticleContacts {
  std::vector<std::uint32_t> particle;  ///< store indices of the particles with candidates
  std::vector<std::uint32_t> start;     ///< size particle.size() + 1
  std::vector<std::uint32_t> partner;   ///< per entry: store index of the other particle
  std::vector<float> distance;          ///< per entry: contact distance r (m)

  std::size_t size() const { return particle.size(); }
  void clear() { particle.clear(), start.assign(1, 0), partner.clear(), distance.clear(); }
};

/// One Jacobi iteration. `scratch` is resized to 3 * c.size() and holds the corrections.
void solve_particle_contacts(const ParticleView& p, const ParticleContacts& c, float friction,
                             std::vector<float>& scratch);

/// Contacts of particles against partners that must get their full reaction (fluid particles
/// against shape particles, whose corrections shape matching spreads over their clusters):
/// `first` lists each particle's partners (CSR, as above); `second` lists, per partner particle,
/// its entries in `first` (an index of the same pairs, in a fixed order).
struct SidedContacts {
  ParticleContacts first;
  std::vector<std::uint32_t> second;        ///< store indices of the partner particles
  std::vector<std::uint32_t> second_start;  ///< size second.size() + 1
  std::vector<std::uint32_t> second_entry;  ///< per entry: its index in first.partner

  void clear() { first.clear(), second.clear(), second_start.assign(1, 0), second_entry.clear(); }
};

/// One Jacobi iteration of momentum-keeping contacts, with friction as solve_particle_contacts
/// has it. For particle i and each partner j closer than r, out of a_i such contacts of i:
///   lambda = (r - d) / (w_i + w_j) / a_i,  n = (p_i - p_j) / d
///   u_t: the tangential part of the pair's relative motion of the substep, (p_i - x_i) - (p_j - x_j)
///   keep = 1 where |u_t| <= mu (r - d) (static), else mu (r - d) / |u_t|
///   impulse  P = lambda n - keep u_t / (w_i + w_j) / a_i
///   dp_i += w_i P,  dp_j -= w_j P
/// so m_i dp_i + m_j dp_j = 0 for every pair: i's corrections are averaged (a fluid particle
/// between two partners is not pushed twice), j gets the sum of its pairs' reactions. mu =
/// `friction` (0: none). Each sum runs over a list in a fixed order: the same bits on any thread
/// count. `scratch` holds the pairs' impulses and the corrections.
void solve_sided_contacts(const ParticleView& p, const SidedContacts& c, float friction, std::vector<float>& scratch);

}  // namespace seiche::kernels
