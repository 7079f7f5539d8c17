// `seiche bench --stability`: a fixed set of stiff and extreme scenes, each run for a fixed
// simulated time and judged PASS or FAIL:
//   finite     no NaN or inf in any position or velocity, in any frame
//   contained  no particle lost, none outside the domain, in any frame
//   energy     the mechanical energy E = kinetic + gravitational never exceeds its value at the
//              start (so kinetic energy never exceeds its start plus the work gravity did) by
//              more than 1 % of the start value
//   bounded    in the last frame, the fluid's mean density error is below 10 % and the mean
//              relative error of distance constraints and cloth edges below 100 % (bounded, not
//              accurate: how accurate a setting is, the sweep measures)
// The same cases run as tests at a reduced size (fewer particles, the same time).
#pragma once

#include <cstddef>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "seiche/scene.hpp"

namespace seiche {

class Simulation;

enum class SuiteSize { Full, Reduced };

struct StabilityCase {
  std::string name;         ///< e.g. "chain_mass_ratio"
  std::string description;  ///< what the scene does, in a sentence
  SceneDef scene;
  double duration = 1.0;    ///< simulated seconds
  /// Changes the freshly built simulation's state before the first frame (e.g. collapses a
  /// cloth to one point); empty = none.
  std::function<void(Simulation&)> prepare;
  /// The frame whose energy is the start value: 0 = the initial state; 1 = after the first
  /// frame, for a start that violates its constraints (their release is not energy made by
  /// the solver, and E counts no elastic energy).
  int energy_start_frame = 0;
};

/// The suite, in order: chain with a 1:1000 mass ratio, zero-compliance cloth at one substep
/// per 1/24 s frame, a fluid block dropped from 20x its height, two fluid columns colliding at
/// 50 m/s, particles starting coincident, particles far outside the domain, a time step 10x
/// too large, a cloth hit by a fast sphere.
std::vector<StabilityCase> stability_cases(SuiteSize size);

struct StabilityResult {
  std::string name, description;
  bool passed = false;
  std::string failure;           ///< the first criterion that failed, in words ("" on PASS)
  int frames = 0;                ///< frames run
  std::size_t particles = 0;
  double wall_seconds = 0.0;
  std::size_t non_finite = 0;      ///< the most non-finite values in a frame
  std::size_t outside_domain = 0;  ///< the most particles outside the domain in a frame
  std::size_t lost = 0;            ///< particles missing at the end
  std::size_t moved_into_domain = 0;  ///< particles created outside the domain and moved in
  double energy_start = 0.0;       ///< J
  double energy_max = 0.0;         ///< J, the largest E after the start frame
  double max_speed = 0.0;          ///< m/s, the largest in any frame
  std::string error_family;        ///< the family nearest its bound in the last frame ("" if none)
  double final_error = 0.0;        ///< its mean error in the last frame
  double error_bound = 0.0;        ///< and its bound
};

/// Runs one case (with `threads` worker threads, 0 = every core; progress lines to `progress`
/// unless null); never throws for a diverged simulation (that is a FAIL).
StabilityResult run_stability_case(const StabilityCase& c, int threads, std::ostream* progress = nullptr);

/// The results as CSV (a header line and one row per case) and as a table for the terminal.
std::string stability_csv(const std::vector<StabilityResult>& results);
void print_stability_table(std::ostream& out, const std::vector<StabilityResult>& results);

}  // namespace seiche
