// The "colliders" section: a collider is exactly one shape object plus a friction value. The key
// tables (the collider's, and one per shape), the reader, and the check of mesh colliders, which
// reads each OBJ once and keeps it in the definition for the collider family's SDF.
#include "collider_reader.hpp"

#include <cmath>
#include <memory>

#include "families/cloth/cloth_mesh.hpp"
#include "scene/shared_keys.hpp"

namespace seiche::detail {

namespace {

using K = Key<ColliderDef>;

const KeyTable<ColliderDef>& collider_keys() {
  static const KeyTable<ColliderDef> keys{
      nested<ColliderDef>("plane", "object").default_text("–").valid_note("see below").doc("a half-space"),
      nested<ColliderDef>("box", "object")
          .default_text("–")
          .valid_note("see below")
          .doc("a solid axis-aligned box"),
      nested<ColliderDef>("sphere", "object").default_text("–").valid_note("see below").doc("a solid sphere"),
      nested<ColliderDef>("capsule", "object")
          .default_text("–")
          .valid_note("see below")
          .doc("a solid capsule (a segment grown by a radius): poles, rods"),
      nested<ColliderDef>("mesh", "object")
          .default_text("–")
          .valid_note("see below")
          .doc("a solid closed triangle mesh (OBJ), collided through its signed distance field"),
      K("friction", &ColliderDef::friction, Range::at_least(0)).doc("Coulomb friction coefficient"),
  };
  return keys;
}

const KeyTable<ColliderDef>& plane_keys() {
  static const KeyTable<ColliderDef> keys{
      K("point", &ColliderDef::point).unit("m").doc("a point on the plane"),
      K("normal", &ColliderDef::normal).valid_note("not zero").doc("points into the free side; normalized on load"),
  };
  return keys;
}

const KeyTable<ColliderDef>& sphere_keys() {
  static const KeyTable<ColliderDef> keys{
      K("center", &ColliderDef::center).unit("m").doc("center"),
      K("radius", &ColliderDef::radius, Range::above(0)).required().unit("m").doc("radius"),
  };
  return keys;
}

const KeyTable<ColliderDef>& capsule_keys() {
  static const KeyTable<ColliderDef> keys{
      K("a", &ColliderDef::end_a).required().unit("m").doc("one end of the axis"),
      K("b", &ColliderDef::end_b).required().unit("m").doc("the other end (may equal `a`: a sphere)"),
      K("radius", &ColliderDef::radius, Range::above(0)).required().unit("m").doc("radius"),
  };
  return keys;
}

// The keys of a mesh collider besides its placement (mesh_placement_keys).
const KeyTable<ColliderDef>& mesh_sdf_keys() {
  static const KeyTable<ColliderDef> keys{
      K("voxel_size", &ColliderDef::voxel_size, Range::at_least(0))
          .unit("m")
          .default_text("`0` = 1/64 of the mesh's largest side")
          .doc("sample spacing of the signed distance field (built once, when the simulation starts, "
               "over the mesh's box grown by 4 samples; outside that box the mesh is not felt)"),
  };
  return keys;
}

void read_collider(JsonReader r, SceneDef& scene) {
  ColliderDef c;
  read_keys(r, collider_keys(), c);
  auto plane = r.optional_object("plane");
  auto box = r.optional_object("box");
  auto sphere = r.optional_object("sphere");
  auto capsule = r.optional_object("capsule");
  auto mesh = r.optional_object("mesh");
  r.finish();

  const int shapes = int(plane.has_value()) + int(box.has_value()) + int(sphere.has_value()) +
                     int(capsule.has_value()) + int(mesh.has_value());
  if (shapes != 1)
    r.fail_here(shapes == 0 ? "needs a shape: one of \"plane\", \"box\", \"sphere\", \"capsule\", \"mesh\""
                            : "has more than one of \"plane\", \"box\", \"sphere\", \"capsule\", \"mesh\"; "
                              "a collider has exactly one shape");
  if (plane) {
    c.shape = ColliderDef::Shape::Plane;
    read_keys(*plane, plane_keys(), c);
    plane->finish();
    const double length = std::sqrt(double(c.normal[0]) * c.normal[0] + double(c.normal[1]) * c.normal[1] +
                                    double(c.normal[2]) * c.normal[2]);
    if (!(length > 0)) plane->fail_at("normal", "must not be zero (it is normalized on load)");
    for (float& n : c.normal) n = static_cast<float>(n / length);
  } else if (box) {
    c.shape = ColliderDef::Shape::Box;
    c.box = read_box(*box);
  } else if (sphere) {
    c.shape = ColliderDef::Shape::Sphere;
    read_keys(*sphere, sphere_keys(), c);
    sphere->finish();
  } else if (capsule) {
    c.shape = ColliderDef::Shape::Capsule;
    read_keys(*capsule, capsule_keys(), c);
    capsule->finish();
  } else {
    c.shape = ColliderDef::Shape::Mesh;
    read_keys(*mesh, mesh_sdf_keys(), c);
    c.mesh = read_mesh_placement(*mesh);
  }
  scene.colliders.push_back(c);
}

// Mesh paths become absolute (a resumed bake may run elsewhere); each OBJ is read here, once, so
// that a broken file is reported before anything runs, and kept for the collider's SDF.
// Closedness is checked when the field is built (Simulation), with the same message.
void check_colliders(SceneDef& scene, const std::string& file) {
  for (std::size_t k = 0; k < scene.colliders.size(); ++k) {
    ColliderDef& c = scene.colliders[k];
    if (c.shape != ColliderDef::Shape::Mesh) continue;
    c.mesh.file = resolve_mesh_path(c.mesh.file, scene.base_dir);
    check_mesh_file(c.mesh.file, file, element_path("colliders", k) + ".mesh.file");
    c.loaded_mesh = std::make_shared<const ClothMesh>(
        read_obj_mesh(c.mesh.file, c.mesh, element_path("colliders", k) + ".mesh"));
  }
}

std::vector<KeyTableDoc> collider_docs() {
  std::vector<KeyDoc> shapes;
  append_prefixed(shapes, "plane", key_docs(plane_keys()));
  append_prefixed(shapes, "box", key_docs(box_keys()));
  append_prefixed(shapes, "sphere", key_docs(sphere_keys()));
  append_prefixed(shapes, "capsule", key_docs(capsule_keys()));
  append_prefixed(shapes, "mesh", key_docs(mesh_placement_keys()));
  append_prefixed(shapes, "mesh", key_docs(mesh_sdf_keys()));
  return {{"colliders", key_docs(collider_keys())}, {"collider_shapes", std::move(shapes)}};
}

}  // namespace

SceneSection colliders_section() {
  return {"colliders", true, "solid obstacles", read_collider, check_colliders, collider_docs};
}

}  // namespace seiche::detail
