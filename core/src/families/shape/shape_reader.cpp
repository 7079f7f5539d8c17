// The "shapes" section: the key table of a shape-matched box, its reader, and the rules across
// sections (a shape holds particles, not too many for one cluster, and lies inside the domain).
#include "shape_reader.hpp"

#include <fmt/format.h>

#include "families/lattice.hpp"
#include "scene/shared_keys.hpp"

namespace seiche::detail {

namespace {

// One cluster is matched by one thread: past a million particles one shape would stall every
// iteration (large soft bodies are several overlapping clusters, a later family).
constexpr std::size_t kMaxParticlesPerShape = 1'000'000;
// The lightest particle a shape may have: the raw particles' bound ("particles[k].mass"), so
// that the inverse mass stays a normal float.
constexpr double kMinParticleMass = 1e-12;
// Densest solid (osmium, 22.6 t/m^3) with room to spare; above, density * spacing^3 is a typo.
constexpr double kMaxDensity = 1e5;

const KeyTable<ShapeDef>& shape_keys() {
  using K = Key<ShapeDef>;
  static const KeyTable<ShapeDef> keys{
      nested<ShapeDef>("box", "object")
          .required()
          .unit("m")
          .doc("the body: `{\"min\": vec3, \"max\": vec3}`, filled with particles as a fluid block is"),
      K("spacing", &ShapeDef::spacing, Range::above(0))
          .unit("m")
          .doc("particle spacing; each particle's collision radius is half of it"),
      K("density", &ShapeDef::density, Range::left_open(0, kMaxDensity))
          .unit("kg/m³")
          .doc("each particle weighs `density * spacing³`"),
      K("stiffness", &ShapeDef::stiffness, Range::left_open(0, 1))
          .doc("1 keeps the shape rigid; less pulls each particle that part of the way to its rigid goal "
               "every iteration (soft)"),
      K("velocity", &ShapeDef::velocity).unit("m/s").doc("initial velocity of every particle"),
  };
  return keys;
}

void read_shape(JsonReader r, SceneDef& scene) {
  ShapeDef s;
  read_keys(r, shape_keys(), s);  // "box" is required: asked for after the optional keys
  s.box = read_box(r.object("box"));
  r.finish();
  scene.shapes.push_back(s);
}

void check_shapes(SceneDef& scene, const std::string& file) {
  for (std::size_t k = 0; k < scene.shapes.size(); ++k) {
    const ShapeDef& s = scene.shapes[k];
    const std::string box_path = element_path("shapes", k) + ".box";
    const auto n = lattice_counts(s.box, s.spacing);
    for (int a = 0; a < 3; ++a)
      if (n[a] < 1)
        fail(file, box_path, fmt::format("holds no particles: along {} it is thinner than one spacing ({} m)",
                                         kAxis[a], s.spacing));
    const double count = double(n[0]) * double(n[1]) * double(n[2]);
    if (count > double(kMaxParticlesPerShape))
      fail(file, box_path, fmt::format("would hold {:.0f} particles at spacing {} m; the limit is {} per shape",
                                       count, s.spacing, kMaxParticlesPerShape));
    const double mass = double(s.density) * s.spacing * s.spacing * s.spacing;
    if (mass < kMinParticleMass)
      fail(file, element_path("shapes", k) + ".density",
           fmt::format("gives particles of {:.3g} kg (density * spacing^3); the lightest allowed is {:g} kg", mass,
                       kMinParticleMass));
    if (!inside(s.box.min, scene.domain) || !inside(s.box.max, scene.domain))
      fail(file, box_path, fmt::format("{}..{} reaches outside the domain {}", format_vec(s.box.min),
                                       format_vec(s.box.max), format_domain(scene.domain)));
  }
}

}  // namespace

SceneSection shapes_section() {
  return {"shapes", true, "boxes of particles kept in shape by shape matching (rigid or soft)", read_shape,
          check_shapes, [] { return std::vector<KeyTableDoc>{{"shapes", key_docs(shape_keys())}}; }};
}

}  // namespace seiche::detail
