// The "solver", "domain" and "output" sections: their key tables and readers. Rules that are
// not a range of one key (a substep not too short, min < max) are checked after the table.
#include "core_sections.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "shared_keys.hpp"

namespace seiche::detail {

namespace {

constexpr double kMaxStepsPerFrame = 10000;  // substeps and iterations: more is a typo
constexpr double kMinSubstep = 1e-6;         // s: below this, float time steps underflow
constexpr double kMaxFrameDt = 10;           // s: frames are 1/24-1/60 s; 10 s is a unit mistake
constexpr double kMaxTensileK = 1;           // k = 1: s_corr already as strong as a 100 % compression

const KeyTable<SolverDef>& solver_keys() {
  using K = Key<SolverDef>;
  static const KeyTable<SolverDef> keys{
      K("frame_dt", &SolverDef::frame_dt, Range::left_open(0, kMaxFrameDt))
          .unit("s")
          .default_text("`1/60` (0.016666…)")
          .valid_note("and `frame_dt / substeps` ≥ 1e-6")
          .doc("time per output frame"),
      K("substeps", &SolverDef::substeps, Range::closed(1, kMaxStepsPerFrame)).doc("XPBD substeps per frame"),
      K("iterations", &SolverDef::iterations, Range::closed(1, kMaxStepsPerFrame))
          .doc("constraint iterations per substep (the least; see `density_tolerance`)"),
      K("density_tolerance", &SolverDef::density_tolerance, Range::half_open(0, 1))
          .doc("the fluid's mean density error the iterations aim for: after `iterations`, a substep "
               "iterates on while the mean of max(ρ/ρ0 − 1, 0) over the fluid, measured at the start of "
               "its last iteration, is above it (1 % by default: ordinary scenes never need more, impacts "
               "and long substeps do); 0 = exactly `iterations`. Scenes without fluid ignore it"),
      K("max_iterations", &SolverDef::max_iterations, Range::closed(1, kMaxStepsPerFrame))
          .doc("the most iterations a substep runs for `density_tolerance` (never fewer than "
               "`iterations`)"),
      K("gravity", &SolverDef::gravity).unit("m/s²").doc("gravitational acceleration"),
      K("relaxation", &SolverDef::relaxation, Range::at_least(0))
          .doc("PBF constraint-force mixing ε, relative to the λ denominator of a particle with a full "
               "rest neighborhood; larger is softer and more stable (below about 0.3 a single iteration "
               "per substep overshoots and gains energy; tall fluid columns need 2 iterations even at "
               "0.3)"),
      K("damping", &SolverDef::damping, Range::at_least(0))
          .unit("1/s")
          .doc("velocity damping c: v ← v·exp(−c·dt) every substep (free particles); 0 = off, no pass"),
      K("tensile_k", &SolverDef::tensile_k, Range::closed(0, kMaxTensileK))
          .doc("artificial pressure s_corr = −k max(uⁿ − u_sⁿ, 0) / (1 − u_sⁿ) / D0 with u = W(r) / "
               "W(dq·h) and u_s its value at the rest spacing (PBF eq. 13 shifted to 0 at the rest "
               "spacing: it pushes apart only pairs closer than that, never a free surface outward; D0 "
               "as for `relaxation`, so k is the compression this repulsion is worth at r = dq·h), given for a "
               "substep of 1/480 s (the default 1/60 s frame in 8 substeps) and scaled by (dt·480)², at "
               "most 1, so that it is the same force at any shorter substep; 0 turns it off. Half the "
               "paper's 0.1, which made colliding fluid gain energy at 1/480 s (docs/design.md)"),
      K("tensile_n", &SolverDef::tensile_n, Range::closed(1, 8)).doc("the exponent n of s_corr"),
      K("tensile_dq", &SolverDef::tensile_dq, Range::open(0, 1))
          .doc("dq of s_corr as a fraction of the kernel radius h; from dq·h ≥ the fluid spacing on "
               "(dq ≥ 1 / `kernel_radius`) there is no artificial pressure"),
      K("distance_forests", &SolverDef::distance_forests, Range::closed(0, 3))
          .default_text("1 on pieces without loops")
          .doc("spanning forests of the raw `distance_constraints` solved exactly (linear time) every "
               "iteration, before their Gauss-Seidel sweep, as the cloth's `stretch_forests`: grown from "
               "the pinned particles (mass 0), they carry the load to the pins whatever the mass ratios "
               "along the way (a 20-particle chain released from a pin with its last particle 1000 times "
               "heavier: max stretch 245 % → below 0.001 % over 10 s at the default settings). Absent: one "
               "forest over the connected pieces without loops (chains, trees), none over a piece with a "
               "loop, which keeps Gauss-Seidel alone: on a loop a forest leaves the closing edges to "
               "Gauss-Seidel, and at high mass ratios the two fight (a ring with a 1:1000 particle: energy "
               "gains, once a blow-up; docs/design.md). A number n: n forests over every piece, loops "
               "included, each over the constraints the previous left. 0 = Gauss-Seidel only. A tree of "
               "one constraint (a lone pair) is left to Gauss-Seidel, which solves it exactly. The step is the "
               "cloth's and, like it, not energy-safe where a substep is long for the tension: at 2 substeps "
               "or fewer per 1/60 s, or 1 iteration at 1:1000, or 1:10⁴ at the defaults, a whipping chain can "
               "gain energy where Gauss-Seidel alone stretches it several times; set 0 there or add substeps "
               "(docs/design.md). "
               "Checkpoints hold the multipliers the forests read, so a resumed bake is byte-identical. "
               "Scenes without distance constraints ignore it"),
      K("joint_trees", &SolverDef::joint_trees)
          .doc("the joints but distance joints (ball, hinge, fixed, slider, universal) that form trees "
               "over the rigid bodies (chains, ragdolls; a joint that "
               "closes a loop, through the world too, is left out) solved exactly along the trees every "
               "iteration, before the other joints' Gauss-Seidel sweep: a tree carries its load to the "
               "world in one step, whatever the mass ratios along it (over 5-10 s at the default settings, "
               "max joint drift with Gauss-Seidel alone → with the trees: scenes/rigid_chain.json, 20 links "
               "with the last 1000 times heavier, 367 % → 1.5e-10 % of a link; 100 equal links 56 % → "
               "0.002 %; the same 20 links on hinges 142 % → 1.5e-10 %, their axes aligned within "
               "1e-15 rad; on universal joints 125 % → 1.5e-10 %). With geometric stiffness from the previous substep's multipliers, which the "
               "checkpoints hold; it gains no energy on that chain from 1 substep of 1 iteration per frame "
               "up (docs/design.md). A tree of ball, hinge and fixed joints whose bodies carry little "
               "load for their inertia (pendulums, lightly loaded articulations) and on which no "
               "Gauss-Seidel correction acts takes its step along the joints' directions at the start of "
               "the substep (SHAKE), which keeps its energy: a double pendulum of 0.5 m boxes within "
               "0.07 % over 10 s at the defaults, where the end-of-step directions lose 9.8 %; heavily "
               "loaded trees (high mass ratios, long chains) keep the end-of-step directions, which never "
               "gain energy. A hinge's or slider's limits and motor are corrected by Gauss-Seidel after "
               "the trees (a hinge's limit through its anchor: an inelastic stop); a loop's closing joint "
               "and the distance joints stay with Gauss-Seidel. `false`: every joint Gauss-Seidel. "
               "Scenes with only distance joints ignore it"),
  };
  return keys;
}

void read_solver(JsonReader r, SceneDef& scene) {
  SolverDef s = read_object(r, solver_keys());
  if (s.frame_dt / s.substeps < kMinSubstep)
    r.fail_at("frame_dt", fmt::format("gives substeps of {} s (frame_dt / substeps); the smallest is {} s",
                                      s.frame_dt / s.substeps, kMinSubstep));
  scene.solver = s;
}

const KeyTable<DomainDef>& domain_keys() {
  using K = Key<DomainDef>;
  static const KeyTable<DomainDef> keys{
      K("min", &DomainDef::min).unit("m").valid_note("< `max` on every axis").doc("lower corner"),
      K("max", &DomainDef::max).unit("m").valid_note("> `min` on every axis").doc("upper corner"),
      K("friction", &DomainDef::friction, Range::at_least(0))
          .doc("Coulomb friction coefficient of the walls"),
  };
  return keys;
}

void read_domain(JsonReader r, SceneDef& scene) {
  DomainDef d = read_object(r, domain_keys());
  for (int a = 0; a < 3; ++a) {
    if (!(d.min[a] < d.max[a]))
      r.fail_here(fmt::format("min must be < max on every axis, but along {} min = {} and max = {}", kAxis[a],
                              d.min[a], d.max[a]));
  }
  scene.domain = d;
}

const KeyTable<OutputDef>& output_keys() {
  using K = Key<OutputDef>;
  static const KeyTable<OutputDef> keys{
      K("frames", &OutputDef::frames, Range::at_least(1)).doc("number of frames to simulate"),
      K("checkpoint_every", &OutputDef::checkpoint_every, Range::at_least(1))
          .doc("bake: frames between checkpoints of the simulation state (`seiche bake --resume`)"),
      K("particles", &OutputDef::particles)
          .doc("bake: the particle files of `particle_formats` per frame; `false` writes none (`seiche run` "
               "writes them always)"),
      nested<OutputDef>("particle_formats", "array of strings")
          .default_text("`[\"ply\"]`")
          .valid_note("one or both of `\"ply\"`, `\"vtp\"`, each at most once")
          .doc("the formats of the particle files, each in id order with position, velocity and id: "
               "`\"ply\"` `particles.%04d.ply` (binary PLY: Blender, Houdini); `\"vtp\"` "
               "`particles.%04d.vtp` (VTK XML PolyData) and `particles.pvd`, the series of the .vtp "
               "frames with their times, which ParaView opens as one time series with `velocity` and "
               "`id` point arrays"),
      nested<OutputDef>("vdb", "array of strings")
          .default_text("`[\"surface\", \"density\"]`")
          .valid_note("each of `\"surface\"`, `\"density\"`, `\"points\"`, `\"v\"`, at most once")
          .doc("bake: the grids of `<name>.%04d.vdb`; `[]` writes no .vdb files"),
      K("mesh", &OutputDef::mesh).doc("bake: `<name>.%04d.obj`, the fluid surface as a triangle mesh"),
      K("body_meshes", &OutputDef::body_meshes)
          .doc("`<body name>.%04d.obj` per rigid body: its surface in the world (a mesh body's triangles; a "
               "generated mesh for a box, sphere or capsule), next to `bodies.%04d.jsonl`"),
      K("voxel_size", &OutputDef::voxel_size, Range::at_least(0))
          .unit("m")
          .default_text("`0` (automatic)")
          .doc("voxel size of the grids; 0 = half the fluid spacing"),
      K("anisotropic", &OutputDef::anisotropic)
          .doc("anisotropic surface (Yu & Turk 2013): flat sheets and sharp edges instead of blobby "
               "spheres"),
      K("half_float", &OutputDef::half_float)
          .doc("store float grids as 16-bit halves (half the file size)"),
      K("compression", &OutputDef::compression)
          .choices({"blosc", "zip", "none"})
          .doc("compression of the .vdb files"),
  };
  return keys;
}

bool lists(const std::vector<std::string>& names, std::string_view name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

void read_output(JsonReader r, SceneDef& scene) {
  OutputDef o;
  read_keys(r, output_keys(), o);
  std::vector<std::string> grids{"surface", "density"};
  r.read_string_set("vdb", grids, {"surface", "density", "points", "v"});
  std::vector<std::string> formats{"ply"};
  r.read_string_set("particle_formats", formats, {"ply", "vtp"});
  if (formats.empty())
    r.fail_at("particle_formats", "lists no format: give \"ply\", \"vtp\" or both (a bake writes no "
                                  "particle files with output.particles = false)");
  r.finish();
  o.vdb_surface = lists(grids, "surface");
  o.vdb_density = lists(grids, "density");
  o.vdb_points = lists(grids, "points");
  o.vdb_velocity = lists(grids, "v");
  o.particles_ply = lists(formats, "ply");
  o.particles_vtp = lists(formats, "vtp");
  scene.output = o;
}

}  // namespace

SceneSection solver_section() {
  return {"solver", false, "time stepping and the solvers' numerical settings", read_solver, nullptr,
          [] { return std::vector<KeyTableDoc>{{"solver", key_docs(solver_keys())}}; }};
}

SceneSection domain_section() {
  return {"domain", false, "the box that holds every particle", read_domain, nullptr,
          [] { return std::vector<KeyTableDoc>{{"domain", key_docs(domain_keys())}}; }};
}

SceneSection output_section() {
  return {"output", false, "what a run or a bake writes", read_output, nullptr,
          [] { return std::vector<KeyTableDoc>{{"output", key_docs(output_keys())}}; }};
}

}  // namespace seiche::detail
