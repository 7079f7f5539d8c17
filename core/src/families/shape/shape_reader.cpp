// The "shapes" section: the key tables of a shape-matched body (its material, and one per body
// shape: box, sphere, mesh), its reader, and the rules across sections (a shape holds particles,
// not too many, and lies inside the domain). A mesh shape's OBJ is read and voxelized here, once,
// so that a broken or open mesh is reported before anything runs, and its sites are kept in the
// definition for the family.
#include "shape_reader.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "families/cloth/cloth_mesh.hpp"
#include "families/lattice.hpp"
#include "families/shape/shape_sites.hpp"
#include "scene/shared_keys.hpp"

namespace seiche::detail {

namespace {

// One particle per body is the least; past a million the body's clusters make every iteration
// slow (and one cluster is matched by one thread).
constexpr std::size_t kMaxParticlesPerShape = 1'000'000;
// The lattice a sphere or a mesh is sampled on before its inside is kept (its bounding box at
// the spacing): 4 times the particle bound, so a body that fills a quarter of its box or more can
// have the most particles. Building that field takes the loader about a second; the mesh
// colliders' bound (2^26) let a scaled-up mesh shape keep the loader busy for minutes (found by
// the scene fuzzer).
constexpr double kMaxLatticeSamples = 4.0 * double(kMaxParticlesPerShape);
// The lightest particle a shape may have: the raw particles' bound ("particles[k].mass"), so
// that the inverse mass stays a normal float.
constexpr double kMinParticleMass = 1e-12;
// Densest solid (osmium, 22.6 t/m^3) with room to spare; above, density * spacing^3 is a typo.
constexpr double kMaxDensity = 1e5;
// Region clusters wider than this many cells are one cluster in all but name (and cost).
constexpr int kMaxClusterHalfWidth = 64;

using K = Key<ShapeDef>;

const KeyTable<ShapeDef>& shape_keys() {
  static const KeyTable<ShapeDef> keys{
      nested<ShapeDef>("box", "object")
          .default_text("–")
          .valid_note("see below")
          .doc("a box, filled with particles as a fluid block is"),
      nested<ShapeDef>("sphere", "object")
          .default_text("–")
          .valid_note("see below")
          .doc("a ball: particles at `center + i * spacing` (i integer) within `radius`"),
      nested<ShapeDef>("mesh", "object")
          .default_text("–")
          .valid_note("see below")
          .doc("a closed OBJ mesh, voxelized at the spacing: particles at the lattice points inside it"),
      K("spacing", &ShapeDef::spacing, Range::above(0))
          .unit("m")
          .doc("particle spacing; each particle's collision radius is half of it"),
      K("density", &ShapeDef::density, Range::left_open(0, kMaxDensity))
          .unit("kg/m³")
          .doc("each particle weighs `density * spacing³`"),
      K("stiffness", &ShapeDef::stiffness, Range::left_open(0, 1))
          .doc("1 keeps the shape rigid; less pulls each particle that part of the way to its goal every "
               "iteration (soft)"),
      K("stiffness_per_substep", &ShapeDef::stiffness_per_substep)
          .doc("`true`: `stiffness` is the part of a deviation a lone cluster loses in one substep, whatever "
               "`solver.iterations` (each iteration pulls `1 − (1 − stiffness)^(1 / iterations)`); `false`: per "
               "iteration"),
      K("linear_blend", &ShapeDef::linear_blend, Range::closed(0, 1))
          .doc("β of the goal `β A + (1 − β) R`: 0 is the rigid goal, more lets the body shear and stretch "
               "(A: the best linear map, volume kept)"),
      K("yield", &ShapeDef::yield, Range::at_least(0))
          .doc("plastic: the strain `‖S − I‖` above which the rest shape flows (with `creep` > 0)"),
      K("creep", &ShapeDef::creep, Range::at_least(0))
          .unit("1/s")
          .doc("plastic: how fast the rest shape takes the strain past `yield`; 0 is elastic"),
      K("max_plastic_strain", &ShapeDef::max_plastic_strain, Range::above(0))
          .doc("plastic: the bound on the rest shape's total change `‖Sp − I‖`"),
      K("cluster_half_width", &ShapeDef::cluster_half_width, Range::closed(0, kMaxClusterHalfWidth))
          .unit("cells")
          .doc("0: the body is one cluster; k: overlapping clusters, cubes of half-width k lattice cells "
               "centred every k cells, each particle moved to the mean of its clusters' goals"),
      K("velocity", &ShapeDef::velocity).unit("m/s").doc("initial velocity of every particle"),
  };
  return keys;
}

const KeyTable<ShapeDef>& sphere_keys() {
  static const KeyTable<ShapeDef> keys{
      K("center", &ShapeDef::center).unit("m").doc("centre (a particle sits there)"),
      K("radius", &ShapeDef::radius, Range::above(0)).required().unit("m").doc("radius"),
  };
  return keys;
}

void read_shape(JsonReader r, SceneDef& scene) {
  ShapeDef s;
  read_keys(r, shape_keys(), s);
  auto box = r.optional_object("box");
  auto sphere = r.optional_object("sphere");
  auto mesh = r.optional_object("mesh");
  r.finish();
  const int bodies = int(box.has_value()) + int(sphere.has_value()) + int(mesh.has_value());
  if (bodies != 1)
    r.fail_here(bodies == 0 ? "needs a body: one of \"box\", \"sphere\", \"mesh\""
                            : "has more than one of \"box\", \"sphere\", \"mesh\"; a shape has exactly one");
  if (box) {
    s.kind = ShapeDef::Kind::Box;
    s.box = read_box(*box);
  } else if (sphere) {
    s.kind = ShapeDef::Kind::Sphere;
    read_keys(*sphere, sphere_keys(), s);
    sphere->finish();
  } else {
    s.kind = ShapeDef::Kind::Mesh;
    s.mesh = read_mesh_placement(*mesh);
  }
  scene.shapes.push_back(s);
}

// A sphere's or a mesh's lattice before its inside is kept: bounded, so that a tiny spacing is
// refused at once instead of being sampled for hours.
void check_lattice(double samples, const std::string& file, const std::string& path, float spacing) {
  if (samples > kMaxLatticeSamples)
    fail(file, path + ".spacing",
         fmt::format("{} m is too small for this body: its lattice would have {:.0f} points; the limit is {:.0f}",
                     spacing, samples, kMaxLatticeSamples));
}

// Mesh paths become absolute (a resumed bake may run elsewhere); the OBJ is read and voxelized.
void load_mesh_sites(ShapeDef& s, const std::string& file, const std::string& path, const std::string& base_dir) {
  s.mesh.file = resolve_mesh_path(s.mesh.file, base_dir);
  check_mesh_file(s.mesh.file, file, path + ".mesh.file");
  const ClothMesh mesh = read_obj_mesh(s.mesh.file, s.mesh, path + ".mesh");
  check_lattice(mesh_lattice_samples(mesh, s.spacing), file, path, s.spacing);
  s.loaded_sites = std::make_shared<const ShapeSites>(voxelize_mesh(mesh, s.spacing, s.mesh.file, path + ".mesh"));
}

void check_shapes(SceneDef& scene, const std::string& file) {
  for (std::size_t k = 0; k < scene.shapes.size(); ++k) {
    ShapeDef& s = scene.shapes[k];
    const std::string path = element_path("shapes", k);
    const double mass = double(s.density) * s.spacing * s.spacing * s.spacing;
    if (mass < kMinParticleMass)
      fail(file, path + ".density",
           fmt::format("gives particles of {:.3g} kg (density * spacing^3); the lightest allowed is {:g} kg", mass,
                       kMinParticleMass));
    std::string body_path = path + ".box";
    if (s.kind == ShapeDef::Kind::Box) {
      const auto n = lattice_counts(s.box, s.spacing);
      for (int a = 0; a < 3; ++a)
        if (n[a] < 1)
          fail(file, body_path, fmt::format("holds no particles: along {} it is thinner than one spacing ({} m)",
                                            kAxis[a], s.spacing));
    } else if (s.kind == ShapeDef::Kind::Sphere) {
      body_path = path + ".sphere";
      check_lattice(std::pow(2.0 * std::floor(double(s.radius) / s.spacing) + 1.0, 3.0), file, path, s.spacing);
    } else {
      body_path = path + ".mesh";
      load_mesh_sites(s, file, path, scene.base_dir);
      if (s.loaded_sites->size() == 0)
        fail(file, body_path, fmt::format("holds no particles: no lattice point at spacing {} m lies inside it",
                                          s.spacing));
    }
    const double count = s.kind == ShapeDef::Kind::Box ? double(lattice_size(s.box, s.spacing))
                                                       : double(shape_site_count(s));
    if (count > double(kMaxParticlesPerShape))
      fail(file, body_path, fmt::format("would hold {:.0f} particles at spacing {} m; the limit is {} per shape",
                                        count, s.spacing, kMaxParticlesPerShape));
    Vec3 lo, hi;
    if (s.kind == ShapeDef::Kind::Box) {
      lo = s.box.min, hi = s.box.max;
    } else if (s.kind == ShapeDef::Kind::Sphere) {
      for (int a = 0; a < 3; ++a) lo[a] = s.center[a] - s.radius, hi[a] = s.center[a] + s.radius;
    } else {
      lo = hi = s.loaded_sites->position.front();
      for (const Vec3& x : s.loaded_sites->position)
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], x[a]), hi[a] = std::max(hi[a], x[a]);
    }
    if (!inside(lo, scene.domain) || !inside(hi, scene.domain))
      fail(file, body_path,
           fmt::format("{}..{} reaches outside the domain {}", format_vec(lo), format_vec(hi),
                       format_domain(scene.domain)));
  }
}

std::vector<KeyTableDoc> shape_docs() {
  std::vector<KeyDoc> bodies;
  append_prefixed(bodies, "box", key_docs(box_keys()));
  append_prefixed(bodies, "sphere", key_docs(sphere_keys()));
  append_prefixed(bodies, "mesh", key_docs(mesh_placement_keys()));
  return {{"shapes", key_docs(shape_keys())}, {"shape_bodies", std::move(bodies)}};
}

}  // namespace

SceneSection shapes_section() {
  return {"shapes", true, "bodies of particles kept in shape by shape matching (rigid, soft, plastic)", read_shape,
          check_shapes, shape_docs};
}

}  // namespace seiche::detail
