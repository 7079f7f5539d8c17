// The "particles" and "distance_constraints" sections: key tables, readers, and the rules across
// sections (a particle inside the domain, a constraint's indices within "particles").
#include "distance_reader.hpp"

#include <utility>

#include <fmt/format.h>

#include "scene/shared_keys.hpp"

namespace seiche::detail {

namespace {

// kg: 1 / mass must be a finite float. A float: the documented bound, read as a float like the
// mass, is itself valid (1e-12 as a float is 9.9999998e-13, below the double 1e-12).
constexpr float kMinMass = 1e-12f;
constexpr double kMaxCompliance = 1e8;  // m/N: 1 mN stretches the pair 100 km: no constraint left

const KeyTable<ParticleDef>& particle_keys() {
  using K = Key<ParticleDef>;
  static const KeyTable<ParticleDef> keys{
      K("x", &ParticleDef::x).required().unit("m").valid_note("inside the domain (bounds included)").doc("position"),
      K("v", &ParticleDef::v).unit("m/s").doc("velocity"),
      K("mass", &ParticleDef::mass, Range::at_least(0))
          .unit("kg")
          .valid_note("and not in (0, 1e-12)")
          .doc("mass; 0 pins the particle"),
  };
  return keys;
}

void read_particle(JsonReader r, SceneDef& scene) {
  ParticleDef p = read_object(r, particle_keys());
  if (p.mass != 0.0f && p.mass < kMinMass)
    r.fail_at("mass", fmt::format("must be 0 (pinned) or at least {} kg, got {}", kMinMass, p.mass));
  scene.particles.push_back(p);
}

void check_particles(SceneDef& scene, const std::string& file) {
  for (std::size_t k = 0; k < scene.particles.size(); ++k) {
    const Vec3& x = scene.particles[k].x;
    if (!inside(x, scene.domain))
      fail(file, element_path("particles", k) + ".x",
           fmt::format("{} is outside the domain {}", format_vec(x), format_domain(scene.domain)));
  }
}

const KeyTable<DistanceConstraintDef>& distance_constraint_keys() {
  using K = Key<DistanceConstraintDef>;
  static const KeyTable<DistanceConstraintDef> keys{
      K("i", &DistanceConstraintDef::i)
          .required()
          .valid_note("0 … len(`particles`) − 1")
          .doc("first particle, an index into `particles` (file order)"),
      K("j", &DistanceConstraintDef::j)
          .required()
          .valid_note("0 … len(`particles`) − 1, ≠ `i`")
          .doc("second particle"),
      K("rest_length", &DistanceConstraintDef::rest_length, Range::at_least(0))
          .unit("m")
          .default_text("absent: the initial distance between i and j")
          .doc("target length"),
      K("compliance", &DistanceConstraintDef::compliance, Range::closed(0, kMaxCompliance))
          .unit("m/N")
          .doc("inverse stiffness; 0 = infinitely stiff"),
  };
  return keys;
}

void read_distance_constraint(JsonReader r, SceneDef& scene) {
  // An absent rest_length stays -1: the initial distance.
  scene.distance_constraints.push_back(read_object(r, distance_constraint_keys()));
}

void check_distance_constraints(SceneDef& scene, const std::string& file) {
  const auto n = static_cast<long long>(scene.particles.size());
  const std::string valid = n == 0 ? "\"particles\" is empty" : fmt::format("valid: 0..{}", n - 1);
  for (std::size_t k = 0; k < scene.distance_constraints.size(); ++k) {
    const DistanceConstraintDef& c = scene.distance_constraints[k];
    const std::string path = element_path("distance_constraints", k);
    for (const auto& [key, index] : {std::pair{".i", c.i}, std::pair{".j", c.j}}) {
      if (index < 0 || index >= n)
        fail(file, path + key, fmt::format("particle index {} is out of range ({})", index, valid));
    }
    if (c.i == c.j)
      fail(file, path + ".j", fmt::format("equals i ({}); a constraint needs two different particles", c.i));
  }
}

}  // namespace

SceneSection particles_section() {
  return {"particles", true, "raw particles", read_particle, check_particles,
          [] { return std::vector<KeyTableDoc>{{"particles", key_docs(particle_keys())}}; }};
}

SceneSection distance_constraints_section() {
  return {"distance_constraints", true, "distance constraints between raw particles", read_distance_constraint,
          check_distance_constraints,
          [] { return std::vector<KeyTableDoc>{{"distance_constraints", key_docs(distance_constraint_keys())}}; }};
}

}  // namespace seiche::detail
