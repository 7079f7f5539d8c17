// The "cloths" section: the key tables of a cloth and of its sheet, the reader, and the check
// that builds every cloth's mesh once (sheet or OBJ) with its topology, so that a broken OBJ, a
// pin past the last vertex or a vertex outside the domain is reported before anything runs; the
// mesh and topology stay in the definition for the cloth solver.
#include "cloth_reader.hpp"

#include <algorithm>
#include <memory>

#include <fmt/format.h>

#include "cloth_mesh.hpp"
#include "scene/output_name.hpp"
#include "scene/shared_keys.hpp"
#include "seiche/memory_estimate.hpp"

namespace seiche::detail {

namespace {

constexpr double kMaxSheetResolution = 4096;  // vertices per side: 16 M vertices in all
constexpr double kMaxThickness = 1;            // m: a sheet a metre thick is a unit mistake (cm as m)
constexpr double kMaxStretchCompliance = 1e8;  // m/N: 1 mN stretches an edge 100 km: no constraint left
constexpr double kMaxBendCompliance = 1e8;     // 1/(N m): 1e4 is cotton; 1e8 does not bend back at all

std::string_view name_rule() {
  static const std::string rule =
      fmt::format("{}; ignoring case, not `particles`, another cloth's, or (in a scene with fluid) the scene's name",
                  kOutputNameRule);
  return rule;
}

const KeyTable<ClothDef>& cloth_keys() {
  using K = Key<ClothDef>;
  static const KeyTable<ClothDef> keys{
      K("name", &ClothDef::name)
          .default_text("`cloth<k>`")
          .valid_note(name_rule())
          .doc("output file stem"),
      nested<ClothDef>("sheet", "object").default_text("–").valid_note("see below")
          .doc("a generated rectangular sheet"),
      nested<ClothDef>("mesh", "object").default_text("–").valid_note("see below")
          .doc("an OBJ triangle mesh"),
      K("mass_per_area", &ClothDef::mass_per_area, Range::above(0))
          .unit("kg/m²")
          .doc("a vertex gets a third of the area of each of its triangles (a vertex in no triangle: the "
               "mean)"),
      K("thickness", &ClothDef::thickness, Range::left_open(0, kMaxThickness))
          .unit("m")
          .doc("contact distance between its particles (self and cloth-cloth contacts); half of it is "
               "the particles' radius against colliders and the domain. Keep it below the edge length: "
               "vertices two edges apart are not excluded from contacts"),
      K("stretch_compliance", &ClothDef::stretch_compliance, Range::closed(0, kMaxStretchCompliance))
          .unit("m/N")
          .doc("XPBD compliance of every edge; 0 = inextensible"),
      K("bend_compliance", &ClothDef::bend_compliance, Range::left_open(0, kMaxBendCompliance))
          .unit("1/(N·m)")
          .doc("inverse bending stiffness B; `1e4` (B = 1e-4 N·m) bends like cotton, `1e2` like "
               "cardboard. Same unit for both models; independent of the mesh resolution"),
      K("bending", &ClothDef::bending)
          .choices({"dihedral", "isometric"})
          .doc("dihedral-angle hinges (any rest shape) or Bergou et al.'s isometric bending (quadratic, "
               "faster, assumes a flat rest shape)"),
      K("tethers", &ClothDef::tethers)
          .doc("long-range attachments (Kim et al. 2012): every free vertex stays within its rest "
               "distance of its 4 nearest pinned vertices; removes the visible stretch of hanging cloth "
               "at low iteration counts"),
      K("stretch_forests", &ClothDef::stretch_forests, Range::closed(0, 3))
          .default_text("1 with pins, else 0")
          .doc("spanning forests of the edges whose stretch constraints are solved exactly (linear "
               "time) every iteration, before the Gauss-Seidel sweep: the first grows from the pins and "
               "carries the cloth's weight to them (a sheet hanging from two point pins: max strain 39 % "
               "→ 2.3 % at 32², default solver settings); each further one takes edges the previous left "
               "(64²: 16 % with 1, 4 % with 3). 0 = Gauss-Seidel only. Absent: 1 for a cloth with pins "
               "(`pins`, or a `pin_box` that holds a vertex), 0 for one without (no cost). The step is "
               "safeguarded (capped geometric stiffness, line search; docs/design.md): no energy gain at "
               "1 substep x 1 iteration per 1/24 s frame; at several substeps x 2 iterations per 1/24 s "
               "a small gain remains (16²: +2 % at 4 x 2). It costs a serial sweep per forest and "
               "iteration. Checkpoints hold the edge multipliers the forests read, so a resumed bake is "
               "byte-identical"),
      K("self_collision", &ClothDef::self_collision)
          .doc("contacts between vertices of this cloth that share no triangle"),
      K("friction", &ClothDef::friction, Range::at_least(0))
          .doc("Coulomb friction of particle contacts (the largest of the cloths' values is used); "
               "against a rigid body, sqrt(this x the body's `friction`)"),
      K("pins", &ClothDef::pins, Range::at_least(0))
          .valid_note("< the number of vertices")
          .doc("vertices pinned in place (mass 0)"),
      nested<ClothDef>("pin_box", "object (`min`, `max`)")
          .unit("m")
          .default_text("none")
          .valid_note("`min` ≤ `max`")
          .doc("vertices whose rest position lies inside are pinned too"),
      K("velocity", &ClothDef::velocity).unit("m/s").doc("initial velocity of every vertex"),
  };
  return keys;
}

const KeyTable<SheetDef>& sheet_keys() {
  using K = Key<SheetDef>;
  static const KeyTable<SheetDef> keys{
      K("origin", &SheetDef::origin).required().unit("m").valid_note("inside the domain")
          .doc("corner of vertex 0"),
      K("size", &SheetDef::size, Range::above(0)).unit("m").doc("extent along the plane's two axes"),
      K("resolution", &SheetDef::resolution, Range::closed(2, kMaxSheetResolution))
          .doc("vertices along the two axes; vertex (i, j) has index j·resolution[0] + i and UV "
               "(i/(r0−1), j/(r1−1))"),
      K("plane", &SheetDef::plane)
          .valid_note("two different letters of x, y, z")
          .doc("the axes the sheet spans, first axis first: `\"xz\"` is horizontal, `\"xy\"` upright"),
  };
  return keys;
}

SheetDef read_sheet(JsonReader r) {
  SheetDef s = read_object(r, sheet_keys());
  const std::string& p = s.plane;
  if (p.size() != 2 || p[0] == p[1] || std::string("xyz").find(p[0]) == std::string::npos ||
      std::string("xyz").find(p[1]) == std::string::npos)
    r.fail_at("plane", fmt::format("\"{}\" is not two different axes of x, y, z (e.g. \"xz\", \"xy\")", p));
  return s;
}

void read_cloth(JsonReader r, SceneDef& scene) {
  ClothDef c;
  c.name = fmt::format("cloth{}", scene.cloths.size());
  read_keys(r, cloth_keys(), c);
  if (const std::string problem = output_name_problem(c.name); !problem.empty()) r.fail_at("name", problem);
  if (auto box = r.optional_object("pin_box")) c.pin_box = read_box(*box);
  auto sheet = r.optional_object("sheet");
  auto mesh = r.optional_object("mesh");
  r.finish();
  if (sheet.has_value() == mesh.has_value())
    r.fail_here(sheet ? "has both \"sheet\" and \"mesh\"; a cloth is one of them"
                      : "needs a shape: \"sheet\" (generated) or \"mesh\" (an OBJ file)");
  if (sheet) c.sheet = read_sheet(*sheet);
  if (mesh) c.mesh = read_mesh_placement(*mesh);
  scene.cloths.push_back(std::move(c));
}

// Every cloth's mesh is built here once and kept in the definition (mesh paths become absolute:
// a resumed bake may run elsewhere). First the whole scene's memory estimate: a sheet too large
// for this machine (4096 x 4096 with self-collision: about 34 GiB) is refused with its estimate
// here, before its mesh is built, not by std::bad_alloc (--max-memory is checked once loaded).
void check_cloths(SceneDef& scene, const std::string& file) {
  if (!scene.cloths.empty()) check_scene_memory(scene, file, std::nullopt);
  // Taken output stems, compared as output_name_key (equal ignoring case: the same files on a
  // case-folding file system), with who took them: the particle files, the fluid's .vdb / .obj
  // (named after the scene), the cloths before.
  std::vector<std::pair<std::string, std::string>> taken{{"particles", "the particle files (particles.%04d.ply)"}};
  if (!scene.fluids.empty())
    taken.emplace_back(output_name_key(scene.name),
                       fmt::format("name (\"{}\", the scene's name, which names the fluid's files)", scene.name));
  for (std::size_t k = 0; k < scene.cloths.size(); ++k) {
    ClothDef& c = scene.cloths[k];
    const std::string path = element_path("cloths", k);
    const std::string key = output_name_key(c.name);
    for (const auto& [other, owner] : taken)
      if (other == key)
        fail(file, path + ".name",
             fmt::format("\"{}\" writes the same files as {} (output names are compared ignoring case: "
                         "case-folding file systems); give the cloth another name",
                         c.name, owner));
    taken.emplace_back(key, fmt::format("{}.name (\"{}\")", path, c.name));
    auto mesh = std::make_shared<ClothMesh>();
    if (c.mesh) {
      c.mesh->file = resolve_mesh_path(c.mesh->file, scene.base_dir);
      check_mesh_file(c.mesh->file, file, path + ".mesh.file");
      *mesh = read_obj_mesh(c.mesh->file, *c.mesh, path + ".mesh");
    } else {
      *mesh = make_sheet(*c.sheet, file, path + ".sheet");
    }
    auto topology = std::make_shared<const ClothTopology>(
        build_topology(*mesh, c.mesh ? c.mesh->file : file, path + (c.mesh ? ".mesh.file" : ".sheet")));
    const auto n = static_cast<long long>(mesh->vertex_count());
    for (std::size_t p = 0; p < c.pins.size(); ++p) {
      if (c.pins[p] >= n)
        fail(file, element_path(path + ".pins", p),
             fmt::format("vertex {} is out of range: the cloth has {} vertices (0..{})", c.pins[p], n, n - 1));
    }
    for (const Vec3& x : mesh->positions) {
      if (!inside(x, scene.domain))
        fail(file, path + (c.mesh ? ".mesh" : ".sheet"),
             fmt::format("vertex at {} is outside the domain {}", format_vec(x), format_domain(scene.domain)));
    }
    c.loaded_mesh = std::move(mesh);
    c.loaded_topology = std::move(topology);
  }
}

std::vector<KeyTableDoc> cloth_docs() {
  std::vector<KeyDoc> shapes;
  append_prefixed(shapes, "sheet", key_docs(sheet_keys()));
  append_prefixed(shapes, "mesh", key_docs(mesh_placement_keys()));
  return {{"cloths", key_docs(cloth_keys())}, {"cloth_shapes", std::move(shapes)}};
}

}  // namespace

SceneSection cloths_section() {
  return {"cloths", true, "cloths: generated sheets or OBJ meshes", read_cloth, check_cloths, cloth_docs};
}

}  // namespace seiche::detail
