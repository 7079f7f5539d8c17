// The stability suite's cases and its judge (stability.hpp). Each case is a scene written as
// JSON (checked by the scene loader like any file), sized by the suite size: the full size for
// `seiche bench --stability`, a reduced one (fewer particles, the same simulated time) for CI.
#include "seiche/stability.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ostream.h>

#include "run/progress.hpp"
#include "seiche/scene_loader.hpp"
#include "seiche/simulation.hpp"
#include "seiche/thread_count.hpp"

namespace seiche {

namespace {

constexpr double kEnergyTolerance = 0.01;  // of the start value
constexpr double kDensityErrorBound = 0.1;  // fluid: mean max(rho / rho0 - 1, 0)
constexpr double kStrainBound = 1.0;        // distance constraints and cloth edges: mean |C| / l0

SceneDef scene_of(const std::string& name, const std::string& json) {
  return load_scene_text(json, "<stability case " + name + ">");
}

// A pinned particle, n - 1 light links of 1 g, then a 1 kg weight, released horizontally; zero
// compliance; the default solver settings. (At one substep and one iteration per 1/24 s frame
// Gauss-Seidel cannot hold the weight: the chain stretches until the floor stops it.)
StabilityCase chain_mass_ratio(bool full) {
  const int n = full ? 100 : 20;
  const float link = 0.05f;
  std::string particles, constraints;
  for (int k = 0; k < n; ++k) {
    const double mass = k == 0 ? 0.0 : k == n - 1 ? 1.0 : 1e-3;
    particles += fmt::format("{}{{\"x\": [{}, 0, 0], \"mass\": {}}}", k ? ", " : "", link * k, mass);
    if (k) constraints += fmt::format("{}{{\"i\": {}, \"j\": {}}}", k > 1 ? ", " : "", k - 1, k);
  }
  const float reach = link * n + 0.5f;
  StabilityCase c;
  c.name = "chain_mass_ratio";
  c.description = fmt::format("chain of {} particles, links of 1 g and a 1 kg weight (1:1000), zero compliance, "
                              "default solver settings",
                              n);
  c.scene = scene_of(c.name, fmt::format(R"({{
      "domain": {{ "min": [{0}, {0}, -1], "max": [{1}, 1, 1] }},
      "particles": [{2}], "distance_constraints": [{3}] }})",
                                         -reach, reach, particles, constraints));
  c.duration = 10.0;
  return c;
}

// A sheet pinned at two corners, inextensible, one substep and one iteration per 1/24 s frame.
StabilityCase stiff_cloth(bool full) {
  const int n = full ? 64 : 16;
  StabilityCase c;
  c.name = "stiff_cloth_24fps";
  c.description = fmt::format("{0}x{0} sheet pinned at two corners, zero stretch compliance, 1 substep x 1 "
                              "iteration per 1/24 s frame",
                              n);
  c.scene = scene_of(c.name, fmt::format(R"({{
      "solver": {{ "frame_dt": 0.0416667, "substeps": 1, "iterations": 1 }},
      "domain": {{ "min": [-1, -0.5, -1.5], "max": [2, 2.5, 1.5] }},
      "cloths": [ {{ "sheet": {{ "origin": [0, 1.8, 0], "size": [1, 1], "resolution": [{0}, {0}] }},
                     "stretch_compliance": 0, "pins": [0, {1}] }} ] }})",
                                         n, n - 1));
  c.duration = 10.0;
  return c;
}

// A cube of fluid whose bottom starts 20 of its heights above the floor.
StabilityCase fluid_drop(bool full) {
  const int n = full ? 24 : 10;
  const float s = 0.02f, h = n * s, width = 5 * h;
  StabilityCase c;
  c.name = "fluid_drop_20x";
  c.description = fmt::format("{0}^3 fluid block dropped from 20x its height ({1:.1f} m; impact at {2:.0f} m/s)", n,
                              20 * h, std::sqrt(2 * 9.81 * 20 * h));
  c.scene = scene_of(c.name, fmt::format(R"({{
      "domain": {{ "min": [0, 0, 0], "max": [{0}, {1}, {0}] }},
      "fluids": [ {{ "box": {{ "min": [{2}, {3}, {2}], "max": [{4}, {5}, {4}] }}, "spacing": {6} }} ] }})",
                                         width, 21.5 * h, 2 * h, 20 * h, 3 * h, 21 * h, s));
  c.duration = 3.0;
  return c;
}

// Two fluid columns flying at each other at 25 m/s each.
StabilityCase colliding_columns(bool full) {
  const int n = full ? 16 : 8;
  const float s = 0.02f, w = n * s;
  StabilityCase c;
  c.name = "columns_50ms";
  c.description = fmt::format("two {0}x{1}x{0} fluid columns colliding at 50 m/s", n, 2 * n);
  c.scene = scene_of(c.name, fmt::format(R"({{
      "domain": {{ "min": [0, 0, 0], "max": [{0}, {1}, {2}] }},
      "fluids": [ {{ "box": {{ "min": [{3}, 0, {3}], "max": [{4}, {5}, {6}] }}, "spacing": {7}, "velocity": [25, 0, 0] }},
                  {{ "box": {{ "min": [{8}, 0, {3}], "max": [{9}, {5}, {6}] }}, "spacing": {7}, "velocity": [-25, 0, 0] }} ] }})",
                                         12 * w, 6 * w, 3 * w, w, 2 * w, 2 * w, 2 * w, s, 10 * w, 11 * w));
  c.duration = 1.0;
  return c;
}

// Every particle of a kind starts on top of others: two fluid blocks filling the same box, a
// chain whose particles all start at one point, and a sheet whose free vertices all start at
// one point.
StabilityCase coincident(bool full) {
  const int n = full ? 16 : 8, sheet = full ? 32 : 12;
  const float s = 0.02f, w = n * s;
  std::string particles, constraints;
  for (int k = 0; k < 20; ++k) {
    particles += fmt::format("{}{{\"x\": [0.2, 0.8, 0.2], \"mass\": {}}}", k ? ", " : "", k == 0 ? 0.0 : 0.01);
    if (k) constraints += fmt::format("{}{{\"i\": {}, \"j\": {}, \"rest_length\": 0.02}}", k > 1 ? ", " : "", k - 1, k);
  }
  StabilityCase c;
  c.name = "coincident";
  c.description = fmt::format("two {0}^3 fluid blocks in the same box, a 20-particle chain at one point, a {1}x{1} "
                              "sheet collapsed to one point (self-collision on)",
                              n, sheet);
  c.scene = scene_of(c.name, fmt::format(R"({{
      "domain": {{ "min": [0, 0, 0], "max": [1.5, 1.5, 1.5] }},
      "fluids": [ {{ "box": {{ "min": [0.6, 0, 0.6], "max": [{0}, {1}, {0}] }}, "spacing": {2} }},
                  {{ "box": {{ "min": [0.6, 0, 0.6], "max": [{0}, {1}, {0}] }}, "spacing": {2} }} ],
      "particles": [{3}], "distance_constraints": [{4}],
      "cloths": [ {{ "sheet": {{ "origin": [0.1, 1.2, 0.1], "size": [0.4, 0.4], "resolution": [{5}, {5}] }},
                     "pins": [0], "self_collision": true }} ] }})",
                                         0.6f + w, w, s, particles, constraints, sheet));
  // The sheet's free vertices collapse to the point its first corner is pinned at.
  c.prepare = [](Simulation& sim) {
    ParticleStore state = sim.particles();
    const std::size_t first_cloth = sim.particles().size() - sim.scene().cloths[0].sheet->resolution[0] *
                                                                 sim.scene().cloths[0].sheet->resolution[1];
    for (std::size_t i = 0; i < state.size(); ++i) {
      if (std::size_t(state.id[i]) < first_cloth || state.w[i] <= 0.0f) continue;
      state.x[i] = state.px[i] = 0.1f;
      state.y[i] = state.py[i] = 1.2f;
      state.z[i] = state.pz[i] = 0.1f;
    }
    sim.restore_state(state, 0);
  };
  c.energy_start_frame = 1;
  c.duration = 5.0;
  return c;
}

// Particles far outside the domain: a chain placed a million metres away (a scene built in
// code; the loader rejects such a file) and a fluid block fired into a wall at 300 m/s, so that
// every substep predicts positions far past it.
StabilityCase far_outside(bool full) {
  const int n = full ? 16 : 8;
  const float s = 0.02f, w = n * s;
  StabilityCase c;
  c.name = "far_outside";
  c.description = fmt::format("a 10-particle chain placed 1e6 m outside the domain; a {0}^3 fluid block fired into "
                              "a wall at 300 m/s",
                              n);
  std::string particles, constraints;
  for (int k = 0; k < 10; ++k) {
    particles += fmt::format("{}{{\"x\": [0.05, {}, 0.05]}}", k ? ", " : "", 0.4 - 0.03 * k);
    if (k) constraints += fmt::format("{}{{\"i\": {}, \"j\": {}, \"rest_length\": 0.03}}", k > 1 ? ", " : "", k - 1, k);
  }
  c.scene = scene_of(c.name, fmt::format(R"({{
      "domain": {{ "min": [0, 0, 0], "max": [{0}, {1}, {1}] }},
      "particles": [{2}], "distance_constraints": [{3}],
      "fluids": [ {{ "box": {{ "min": [{4}, 0, {4}], "max": [{5}, {6}, {5}] }}, "spacing": {7}, "velocity": [300, 0, 0] }} ] }})",
                                         6 * w, 3 * w, particles, constraints, w, 2 * w, w, s));
  const float far[3][3] = {{1e6f, 1e6f, 1e6f}, {-1e6f, 0.5f, -1e6f}, {0.5f, -1e6f, 0.5f}};
  for (int k = 0; k < 10; ++k)
    for (int a = 0; a < 3; ++a) c.scene.particles[k].x[a] = far[k % 3][a] + 0.03f * k * (a == 1);
  c.duration = 2.0;
  return c;
}

// A small block of coarse fluid collapsing at default settings: 6^3 particles at spacing 0.05 m
// (full: 8^3), so that nearly every particle is within a kernel radius of the free surface. The
// paper's artificial pressure still pushes at the rest spacing, and there the unilateral density
// constraint has nothing to hold it: it lifted the block (+21 % energy by frame 6).
StabilityCase coarse_block(bool full) {
  const int n = full ? 8 : 6;
  const float s = 0.05f, w = n * s, lo = 0.5f - 0.5f * w;
  StabilityCase c;
  c.name = "fluid_coarse_block";
  c.description = fmt::format("{0}^3 fluid block at spacing {1} m ({2:.2f} m cube) collapsing in a 1 m box, "
                              "default settings",
                              n, s, w);
  c.scene = scene_of(c.name, fmt::format(R"({{
      "domain": {{ "min": [0, 0, 0], "max": [1, 1, 1] }},
      "fluids": [ {{ "box": {{ "min": [{0}, 0, {0}], "max": [{1}, {2}, {1}] }}, "spacing": {3} }} ] }})",
                                         lo, lo + w, w, s));
  c.duration = 2.0;
  return c;
}

// The default dam break with every substep 10 times longer than it should be.
StabilityCase large_time_step(bool full) {
  const float s = full ? 0.027f : 0.05f;
  StabilityCase c;
  c.name = "time_step_10x";
  c.description = fmt::format("dam break (spacing {} m) at frame_dt 1/6 s: every substep 10x too long", s);
  c.scene = load_scene_text(default_scene_json(), "<stability case time_step_10x>",
                            std::vector<std::string>{"solver.frame_dt=0.166667", fmt::format("fluids.0.spacing={}", s)});
  c.duration = 5.0;
  return c;
}

// A sheet hit by a sphere at 30 m/s, seen from the sphere: the sheet flies at 30 m/s into a fixed
// sphere (the same collision; colliders do not move yet).
StabilityCase fast_sphere(bool full) {
  const int n = full ? 64 : 24;
  StabilityCase c;
  c.name = "cloth_fast_sphere";
  c.description = fmt::format("{0}x{0} sheet and a sphere meeting at 30 m/s (the sheet moves; self-collision on)", n);
  c.scene = scene_of(c.name, fmt::format(R"({{
      "domain": {{ "min": [-2, -2, -2], "max": [2, 2, 12] }},
      "cloths": [ {{ "sheet": {{ "origin": [-0.5, -0.5, 0], "size": [1, 1], "resolution": [{0}, {0}], "plane": "xy" }},
                     "velocity": [0, 0, 30], "self_collision": true }} ],
      "colliders": [ {{ "sphere": {{ "center": [0, 0, 2], "radius": 0.25 }}, "friction": 0.3 }} ] }})",
                                         n));
  c.duration = 1.0;
  return c;
}

double mechanical_energy(const FrameMetrics& m) { return m.kinetic_energy + m.potential_energy; }

struct FamilyError {
  std::string family;
  double error = 0.0, bound = 0.0;
};

// The family of the scene whose last-frame mean error is nearest its bound (or past it).
FamilyError worst_final_error(const FrameMetrics& m) {
  FamilyError worst;
  auto consider = [&](const char* family, double mean, double bound) {
    if (worst.family.empty() || !(mean / bound <= worst.error / worst.bound)) worst = {family, mean, bound};
  };
  // The rows the suite judges, and their bounds on the mean (the bending error is not judged).
  static constexpr std::pair<const char*, double> kBounds[] = {
      {"fluid_density_error", kDensityErrorBound}, {"distance_error", kStrainBound}, {"cloth_strain", kStrainBound}};
  for (const ErrorRow& e : m.errors)
    for (const auto& [key, bound] : kBounds)
      if (e.key == key) consider(e.label.c_str(), e.mean, bound);
  return worst;
}

}  // namespace

std::vector<StabilityCase> stability_cases(SuiteSize size) {
  const bool full = size == SuiteSize::Full;
  return {chain_mass_ratio(full), stiff_cloth(full),       fluid_drop(full),      colliding_columns(full),
          coincident(full),       far_outside(full),       large_time_step(full), fast_sphere(full),
          coarse_block(full)};
}

namespace {

// One case, already on its threads (run_stability_case).
StabilityResult run_case(const StabilityCase& c, std::ostream* progress_out) {
  StabilityResult r;
  r.name = c.name;
  r.description = c.description;
  const auto start = std::chrono::steady_clock::now();
  Simulation sim(c.scene);
  if (c.prepare) c.prepare(sim);
  r.particles = sim.particles().size();
  r.moved_into_domain = sim.moved_into_domain();
  const int frames = std::max(1, int(std::lround(c.duration / c.scene.solver.frame_dt)));
  if (c.energy_start_frame == 0) r.energy_start = mechanical_energy(sim.state_metrics());
  r.energy_max = -std::numeric_limits<double>::infinity();
  Progress progress(progress_out, frames);
  FrameMetrics last;
  for (int f = 1; f <= frames; ++f) {
    last = sim.step_frame();
    progress.frame_done(f, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), f, c.name);
    r.frames = f;
    r.non_finite = std::max(r.non_finite, last.non_finite);
    r.outside_domain = std::max(r.outside_domain, last.outside_domain);
    r.max_speed = std::max(r.max_speed, last.max_speed);
    if (last.non_finite > 0) break;  // nothing after this can be judged
    const double e = mechanical_energy(last);
    if (f == c.energy_start_frame) r.energy_start = e;
    else if (f > c.energy_start_frame) r.energy_max = std::max(r.energy_max, e);
  }
  progress.end_line();
  r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.lost = r.particles - std::min(r.particles, last.particles);
  const FamilyError worst = worst_final_error(last);
  r.error_family = worst.family, r.final_error = worst.error, r.error_bound = worst.bound;

  const double allowed = r.energy_start + kEnergyTolerance * std::abs(r.energy_start);
  if (r.non_finite > 0) r.failure = fmt::format("{} non-finite values in frame {}", r.non_finite, r.frames);
  else if (r.lost > 0) r.failure = fmt::format("{} particles lost", r.lost);
  else if (r.outside_domain > 0) r.failure = fmt::format("{} particles outside the domain", r.outside_domain);
  else if (r.energy_max > allowed)
    r.failure = fmt::format("energy grew to {:.4g} J from {:.4g} J", r.energy_max, r.energy_start);
  else if (!r.error_family.empty() && !(r.final_error < r.error_bound))
    r.failure = fmt::format("{} error {:.3g} in the last frame (bound {:.3g})", r.error_family, r.final_error,
                            r.error_bound);
  r.passed = r.failure.empty();
  return r;
}

}  // namespace

StabilityResult run_stability_case(const StabilityCase& c, int threads,
                                   std::ostream* progress_out) {
  return run_with_threads(resolve_thread_count(threads), [&] { return run_case(c, progress_out); });
}

std::string stability_csv(const std::vector<StabilityResult>& results) {
  std::string csv =
      "case,result,frames,particles,wall_s,non_finite,outside_domain,lost,moved_into_domain,energy_start_j,"
      "energy_max_j,max_speed,error_family,final_error,error_bound,failure\n";
  for (const StabilityResult& r : results)
    csv += fmt::format("{},{},{},{},{:.3f},{},{},{},{},{:.6g},{:.6g},{:.6g},{},{:.6g},{:.6g},\"{}\"\n", r.name,
                       r.passed ? "PASS" : "FAIL", r.frames, r.particles, r.wall_seconds, r.non_finite,
                       r.outside_domain, r.lost, r.moved_into_domain, r.energy_start, r.energy_max, r.max_speed,
                       r.error_family, r.final_error, r.error_bound, r.failure);
  return csv;
}

void print_stability_table(std::ostream& out, const std::vector<StabilityResult>& results) {
  fmt::print(out, "\n{:<19} {:>6} {:>9} {:>7} {:>12} {:>12} {:>9}  {:<24} {}\n", "case", "result", "particles",
             "wall s", "energy start", "energy max", "max v", "last frame's mean error", "");
  int passed = 0;
  for (const StabilityResult& r : results) {
    passed += r.passed;
    const std::string error =
        r.error_family.empty() ? "-" : fmt::format("{:.3g}% {} (< {:g}%)", 100.0 * r.final_error, r.error_family,
                                                   100.0 * r.error_bound);
    fmt::print(out, "{:<19} {:>6} {:>9} {:>7.1f} {:>10.4g} J {:>10.4g} J {:>5.3g} m/s  {:<24} {}\n", r.name,
               r.passed ? "PASS" : "FAIL", r.particles, r.wall_seconds, r.energy_start, r.energy_max, r.max_speed,
               error, r.passed ? r.description : r.failure);
  }
  fmt::print(out, "\n{} of {} cases pass\n", passed, results.size());
}

}  // namespace seiche
