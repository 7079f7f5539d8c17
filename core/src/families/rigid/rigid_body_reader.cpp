// The "rigid_bodies" section: the key table of a rigid body, its reader, and the rules across
// keys and sections (the sizes its shape uses and no others, a name no other body has, a centre
// inside the domain, an orientation axis that is not zero). A mesh body's OBJ is read here, once,
// so that an open or degenerate mesh is reported before anything runs, and its mass properties
// and body-frame mesh are kept in the definition (body_mesh.hpp).
#include <fmt/format.h>

#include <cmath>
#include <memory>

#include "body_mesh.hpp"
#include "body_shape.hpp"
#include "families/fluid_body/body_boundary.hpp"
#include "rigid_reader.hpp"
#include "scene/output_name.hpp"
#include "scene/shared_keys.hpp"

namespace seiche::detail {

namespace {

// Densest solid (osmium, 22.6 t/m^3) with room to spare, as for shapes.
constexpr double kMaxDensity = 1e5;
// The most bodies a scene may hold: the body contacts keep a list of every pair of bodies and
// test it every substep (body_contacts.hpp), so memory and time grow with the square of the
// count: 4096 bodies are 8.4M pairs, 67 MB, and about 10 ms a substep of broad phase.
constexpr std::size_t kMaxRigidBodies = 4096;
// The lightest body: below, its inverse mass and inertia leave the range a joint solve can mix
// with ordinary bodies.
constexpr double kMinBodyMass = 1e-9;

const KeyTable<RigidBodyDef>& rigid_body_keys() {
  using K = Key<RigidBodyDef>;
  static const KeyTable<RigidBodyDef> keys{
      K("name", &RigidBodyDef::name)
          .required()
          .valid_note("1 to 64 ASCII letters, digits, `_`, `-`, `.`; not starting with `.` or `-`; not `world`; "
                      "unique ignoring case")
          .doc("names the body for joints, in `bodies.%04d.jsonl` and its `<name>.%04d.obj` (not a cloth's name, "
               "nor the scene's with a fluid)"),
      K("shape", &RigidBodyDef::shape)
          .choices({"box", "sphere", "capsule", "mesh"})
          .doc("a box (edges along the body's x, y, z), a sphere, a capsule (axis along the body's y), or a closed "
               "OBJ mesh (`mesh`)"),
      K("size", &RigidBodyDef::size)
          .unit("m")
          .valid_note("every component > 0; box only")
          .doc("box: its edge lengths along the body's x, y, z"),
      K("radius", &RigidBodyDef::radius, Range::above(0)).unit("m").doc("sphere and capsule only: the radius"),
      K("length", &RigidBodyDef::length, Range::above(0))
          .unit("m")
          .doc("capsule only: the length of its cylinder (the caps add a radius at each end)"),
      nested<RigidBodyDef>("mesh", "object")
          .default_text("–")
          .valid_note("see below; mesh only")
          .doc("the closed OBJ mesh of a `mesh` body: `file` and `scale`"),
      K("density", &RigidBodyDef::density, Range::left_open(0, kMaxDensity))
          .unit("kg/m³")
          .doc("mass and inertia tensor follow from it, the shape and the size (closed forms; a mesh's volume "
               "integrals)"),
      K("position", &RigidBodyDef::position)
          .required()
          .unit("m")
          .valid_note("inside the domain")
          .doc("the centre of mass at the start (a mesh's centre of mass is put there)"),
      K("axis", &RigidBodyDef::axis)
          .valid_note("not zero when `angle` is not 0")
          .doc("orientation at the start: the body is turned by `angle` about this axis (world frame) from its rest "
               "pose (a mesh: as in its file, turned about its centre of mass)"),
      K("angle", &RigidBodyDef::angle).unit("degrees").doc("orientation at the start: the angle about `axis`"),
      K("velocity", &RigidBodyDef::velocity).unit("m/s").doc("initial velocity of the centre of mass"),
      K("angular_velocity", &RigidBodyDef::angular_velocity)
          .unit("rad/s")
          .doc("initial angular velocity, world frame"),
      K("fixed", &RigidBodyDef::fixed).doc("the body never moves (infinite mass): an anchor for joints"),
      K("friction", &RigidBodyDef::friction, Range::at_least(0))
          .doc("static Coulomb friction of its contacts with the domain's walls, the colliders and the other "
               "bodies: sqrt(this x the surface's or the other body's `friction`) is the coefficient; with cloth "
               "sqrt(this x the cloth's `friction`), with shape particles this"),
      K("dynamic_friction", &RigidBodyDef::dynamic_friction, Range::at_least(0))
          .doc("sliding friction of those contacts, mixed the same way with the surface's `friction` (another "
               "body's `dynamic_friction`)"),
      K("restitution", &RigidBodyDef::restitution, Range::closed(0, 1))
          .doc("the share of its normal speed a bounce keeps (0: no bounce; none below 2 g h, the "
               "speed a substep of gravity gives); between two bodies the larger of their two"),
  };
  return keys;
}

// A mesh body's "mesh": the OBJ and its scale. No "translate": `position` places the body.
const KeyTable<ClothMeshDef>& body_mesh_keys() {
  using M = Key<ClothMeshDef>;
  static const KeyTable<ClothMeshDef> keys{
      M("file", &ClothMeshDef::file)
          .required()
          .valid_note("a closed OBJ file, wound outward")
          .doc("relative paths are relative to the scene file's folder"),
      M("scale", &ClothMeshDef::scale, Range::above(0)).doc("the factor of x_file"),
  };
  return keys;
}

// A size key the body's shape does not use is an error, not silently ignored.
void reject_unused_size_keys(JsonReader& r, const RigidBodyDef& b) {
  const BodyShape shape = body_shape_of(b.shape);
  const bool uses_size = shape == BodyShape::Box;
  const bool uses_radius = shape == BodyShape::Sphere || shape == BodyShape::Capsule;
  const bool uses_length = shape == BodyShape::Capsule;
  const auto reject = [&](const char* key, bool used) {
    if (!used && r.has(key)) r.fail_at(key, fmt::format("a {} has no \"{}\"", b.shape, key));
  };
  const bool uses_mesh = shape == BodyShape::Mesh;
  reject("size", uses_size);
  reject("mesh", uses_mesh);
  reject("radius", uses_radius);
  reject("length", uses_length);
}

void read_rigid_body(JsonReader r, SceneDef& scene) {
  RigidBodyDef b;
  read_keys(r, rigid_body_keys(), b);
  auto mesh = r.optional_object("mesh");
  reject_unused_size_keys(r, b);
  if (body_shape_of(b.shape) == BodyShape::Mesh) {
    if (!mesh) r.fail_at("shape", "is \"mesh\" but the body has no \"mesh\" object (its OBJ file)");
    b.mesh = read_object(*mesh, body_mesh_keys());
    if (b.mesh.file.empty()) mesh->fail_at("file", "must not be empty");
  }
  if (const std::string problem = output_name_problem(b.name); !problem.empty()) r.fail_at("name", problem);
  if (output_name_key(b.name) == "world")
    r.fail_at("name", "\"world\" is what a joint's body_a names the world by; give the body another name");
  if (body_shape_of(b.shape) == BodyShape::Box)
    for (int a = 0; a < 3; ++a)
      if (!(b.size[a] > 0.0f))
        r.fail_at("size", fmt::format("{} is not a size: every edge must be longer than 0 m ({} is {})",
                                      format_vec(b.size), kAxis[a], b.size[a]));
  const Vec3& axis = b.axis;
  if (b.angle != 0.0f && !(std::hypot(double(axis[0]), double(axis[1]), double(axis[2])) > 0.0))
    r.fail_at("axis", fmt::format("is zero, so the {} degree turn has no axis", b.angle));
  r.finish();
  scene.rigid_bodies.push_back(b);
}

// With output.body_meshes a body writes <name>.%04d.obj: not a name whose .obj files another
// output writes (the fluid's, named after the scene; a cloth's), compared ignoring case.
void check_body_obj_name(const SceneDef& scene, const RigidBodyDef& b, const std::string& file,
                         const std::string& path) {
  if (!scene.output.body_meshes) return;
  const std::string key = output_name_key(b.name);
  std::string owner;
  if (!scene.fluids.empty() && key == output_name_key(scene.name))
    owner = fmt::format("name (\"{}\", the scene's name, which names the fluid's files)", scene.name);
  for (std::size_t c = 0; c < scene.cloths.size() && owner.empty(); ++c)
    if (key == output_name_key(scene.cloths[c].name))
      owner = fmt::format("{}.name (\"{}\")", element_path("cloths", c), scene.cloths[c].name);
  if (!owner.empty())
    fail(file, path + ".name",
         fmt::format("\"{}\" writes the same files ({}.%04d.obj) as {} (output names are compared ignoring case: "
                     "case-folding file systems); give the body another name, or set output.body_meshes to false",
                     b.name, b.name, owner));
}

void check_rigid_bodies(SceneDef& scene, const std::string& file) {
  if (scene.rigid_bodies.size() > kMaxRigidBodies)
    fail(file, "rigid_bodies",
         fmt::format("{} bodies; at most {} (the contacts between bodies test every pair each substep)",
                     scene.rigid_bodies.size(), kMaxRigidBodies));
  double boundary_lattices = 0.0;  // the fluid boundary's lattice points of the bodies so far
  for (std::size_t k = 0; k < scene.rigid_bodies.size(); ++k) {
    RigidBodyDef& b = scene.rigid_bodies[k];
    const std::string path = element_path("rigid_bodies", k);
    for (std::size_t j = 0; j < k; ++j)
      if (output_name_key(scene.rigid_bodies[j].name) == output_name_key(b.name))
        fail(file, path + ".name",
             fmt::format("\"{}\" is also the name of rigid_bodies[{}] (names are compared ignoring case)", b.name, j));
    check_body_obj_name(scene, b, file, path);
    if (body_shape_of(b.shape) == BodyShape::Mesh) {
      // Mesh paths become absolute (a resumed bake may run elsewhere); the OBJ is read once.
      b.mesh.file = resolve_mesh_path(b.mesh.file, scene.base_dir);
      check_mesh_file(b.mesh.file, file, path + ".mesh.file");
      b.loaded_mesh = std::make_shared<const rigid::BodyMesh>(rigid::read_body_mesh(b.mesh, path + ".mesh"));
    }
    const MassProperties m = mass_properties(body_shape_def(b));
    if (!(m.mass >= kMinBodyMass))
      fail(file, path + ".density",
           fmt::format("gives a body of {:.3g} kg (density * volume); the lightest allowed is {:g} kg", m.mass,
                       kMinBodyMass));
    // With a fluid, the body is sampled into boundary particles at its spacing (fluid_body/).
    // The bound is on all the bodies' lattices together: each is sampled at load.
    if (!scene.fluids.empty()) {
      const double lattice = fluid_body::boundary_lattice_size(body_shape_def(b), m.extent, scene.fluids[0].spacing);
      boundary_lattices += lattice;
      if (boundary_lattices > fluid_body::kMaxBoundaryLattice)
        fail(file, path,
             fmt::format("is too large for the fluid's spacing {} m: its boundary particles would be sampled on a "
                         "lattice of {:.0f} points, {:.0f} with the bodies before it; the limit for all bodies "
                         "together is {:.0f}",
                         scene.fluids[0].spacing, lattice, boundary_lattices, fluid_body::kMaxBoundaryLattice));
    }
    if (!inside(b.position, scene.domain))
      fail(file, path + ".position",
           fmt::format("{} lies outside the domain {}", format_vec(b.position), format_domain(scene.domain)));
  }
}

}  // namespace

SceneSection rigid_bodies_section() {
  return {"rigid_bodies", true, "rigid bodies (box, sphere, capsule, OBJ mesh) with their own position and orientation",
          read_rigid_body, check_rigid_bodies, [] {
            std::vector<KeyDoc> mesh;
            append_prefixed(mesh, "mesh", key_docs(body_mesh_keys()));
            return std::vector<KeyTableDoc>{{"rigid_bodies", key_docs(rigid_body_keys())},
                                            {"rigid_body_mesh", std::move(mesh)}};
          }};
}

}  // namespace seiche::detail
