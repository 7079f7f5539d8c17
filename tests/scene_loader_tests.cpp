// The scene loader: defaults for absent keys, values that round-trip, and for every kind of bad
// input an error that names the file and the exact JSON path of the culprit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include "families/cloth/cloth_mesh.hpp"
#include "loop/family_registry.hpp"
#include "scene/json_parser.hpp"
#include "scene/scene_format_doc.hpp"
#include "scene/scene_section.hpp"
#include "seiche/scene_loader.hpp"
#include "seiche/simulation.hpp"

namespace seiche {
namespace {

namespace fs = std::filesystem;

const char* const kSource = "test.json";

SceneDef load(std::string_view text, const std::vector<std::string>& overrides = {}) {
  return load_scene_text(text, kSource, overrides);
}

// The SceneError thrown by loading `text`, or nullopt (and a test failure) if none was thrown.
std::optional<SceneError> load_error(std::string_view text, const std::vector<std::string>& overrides = {}) {
  try {
    load(text, overrides);
  } catch (const SceneError& e) {
    return e;
  }
  ADD_FAILURE() << "no SceneError for: " << text;
  return std::nullopt;
}

void expect_same(const BoxDef& a, const BoxDef& b) {
  EXPECT_EQ(a.min, b.min);
  EXPECT_EQ(a.max, b.max);
}

void expect_same(const SolverDef& a, const SolverDef& b) {
  EXPECT_EQ(a.frame_dt, b.frame_dt);
  EXPECT_EQ(a.substeps, b.substeps);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.density_tolerance, b.density_tolerance);
  EXPECT_EQ(a.max_iterations, b.max_iterations);
  EXPECT_EQ(a.gravity, b.gravity);
  EXPECT_EQ(a.relaxation, b.relaxation);
  EXPECT_EQ(a.tensile_k, b.tensile_k);
  EXPECT_EQ(a.tensile_n, b.tensile_n);
  EXPECT_EQ(a.tensile_dq, b.tensile_dq);
}

void expect_same(const DomainDef& a, const DomainDef& b) {
  EXPECT_EQ(a.min, b.min);
  EXPECT_EQ(a.max, b.max);
  EXPECT_EQ(a.friction, b.friction);
}

void expect_same(const FluidDef& a, const FluidDef& b) {
  expect_same(a.box, b.box);
  EXPECT_EQ(a.spacing, b.spacing);
  EXPECT_EQ(a.kernel_radius, b.kernel_radius);
  EXPECT_EQ(a.rest_density, b.rest_density);
  EXPECT_EQ(a.viscosity, b.viscosity);
  EXPECT_EQ(a.vorticity, b.vorticity);
  EXPECT_EQ(a.velocity, b.velocity);
}

void expect_same(const ParticleDef& a, const ParticleDef& b) {
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.v, b.v);
  EXPECT_EQ(a.mass, b.mass);
}

void expect_same(const DistanceConstraintDef& a, const DistanceConstraintDef& b) {
  EXPECT_EQ(a.i, b.i);
  EXPECT_EQ(a.j, b.j);
  EXPECT_EQ(a.rest_length, b.rest_length);
  EXPECT_EQ(a.compliance, b.compliance);
}

void expect_same(const ColliderDef& a, const ColliderDef& b) {
  EXPECT_EQ(a.shape, b.shape);
  EXPECT_EQ(a.point, b.point);
  EXPECT_EQ(a.normal, b.normal);
  expect_same(a.box, b.box);
  EXPECT_EQ(a.center, b.center);
  EXPECT_EQ(a.radius, b.radius);
  EXPECT_EQ(a.friction, b.friction);
}

// A directory under the system temp directory, removed with everything in it.
class TempDir {
 public:
  TempDir() {
    std::random_device rd;
    path_ = fs::temp_directory_path() / ("seiche_scene_tests_" + std::to_string(rd()) + std::to_string(rd()));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  fs::path write(const std::string& name, std::string_view text) const {
    const fs::path file = path_ / name;
    std::ofstream(file, std::ios::binary) << text;
    return file;
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

fs::path repository_root() {
#ifdef SEICHE_SCENES_DIR
  return fs::path(SEICHE_SCENES_DIR).parent_path();
#else  // the sources are compiled with absolute paths, so __FILE__ locates the repository
  return fs::path(__FILE__).parent_path().parent_path();
#endif
}

std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// ---- Defaults --------------------------------------------------------------------------------

TEST(SceneLoader, EmptyDocumentIsTheDefaultScene) {
  const SceneDef scene = load("{}");
  const SceneDef defaults;
  EXPECT_EQ(scene.name, "scene");
  expect_same(scene.solver, defaults.solver);
  expect_same(scene.domain, defaults.domain);
  EXPECT_EQ(scene.output.frames, defaults.output.frames);
  EXPECT_TRUE(scene.fluids.empty());
  EXPECT_TRUE(scene.particles.empty());
  EXPECT_TRUE(scene.distance_constraints.empty());
  EXPECT_TRUE(scene.colliders.empty());
}

TEST(SceneLoader, EmptySectionsKeepTheirDefaults) {
  const SceneDef scene = load(R"({"solver": {}, "domain": {}, "output": {}, "fluids": [], "particles": [],
                                  "distance_constraints": [], "colliders": []})");
  const SceneDef defaults;
  expect_same(scene.solver, defaults.solver);
  expect_same(scene.domain, defaults.domain);
  EXPECT_EQ(scene.output.frames, defaults.output.frames);
}

TEST(SceneLoader, AbsentEntryKeysTakeTheStructDefaults) {
  const SceneDef scene = load(R"({
    "fluids": [ { "box": { "min": [0, 0, 0], "max": [0.5, 0.5, 0.5] } } ],
    "particles": [ { "x": [0.25, 0.5, 0.75] }, { "x": [0.5, 0.5, 0.5] } ],
    "distance_constraints": [ { "i": 0, "j": 1 } ],
    "colliders": [ { "sphere": { "radius": 0.5 } }, { "plane": {} }, { "box": {} } ] })");

  FluidDef fluid;
  fluid.box.max = {0.5f, 0.5f, 0.5f};
  ASSERT_EQ(scene.fluids.size(), 1u);
  expect_same(scene.fluids[0], fluid);

  ParticleDef particle;
  particle.x = {0.25f, 0.5f, 0.75f};
  ASSERT_EQ(scene.particles.size(), 2u);
  expect_same(scene.particles[0], particle);

  DistanceConstraintDef constraint;
  constraint.i = 0;
  constraint.j = 1;
  ASSERT_EQ(scene.distance_constraints.size(), 1u);
  expect_same(scene.distance_constraints[0], constraint);
  EXPECT_LT(scene.distance_constraints[0].rest_length, 0.0f) << "absent rest_length means the initial distance";

  ASSERT_EQ(scene.colliders.size(), 3u);
  ColliderDef sphere;
  sphere.shape = ColliderDef::Shape::Sphere;
  sphere.radius = 0.5f;
  expect_same(scene.colliders[0], sphere);
  expect_same(scene.colliders[1], ColliderDef{});  // a plane through the origin facing +y
  ColliderDef box;
  box.shape = ColliderDef::Shape::Box;
  expect_same(scene.colliders[2], box);
}

// ---- Values round-trip -----------------------------------------------------------------------

// Every value below is exactly representable as a float, so the comparisons are exact.
constexpr const char* kFullScene = R"({
  "name": "full",
  "solver": { "frame_dt": 0.005, "substeps": 7, "iterations": 3, "density_tolerance": 0.0625,
              "max_iterations": 5, "gravity": [0.5, -4.25, 1],
              "relaxation": 0.125, "tensile_k": 0.25, "tensile_n": 2, "tensile_dq": 0.375 },
  "domain": { "min": [-1, -2, -3], "max": [4, 5, 6], "friction": 0.5 },
  "output": { "frames": 17 },
  "fluids": [
    { "box": { "min": [-1, -2, -3], "max": [0, -1, -2] }, "spacing": 0.0625, "kernel_radius": 2.5,
      "rest_density": 500, "viscosity": 0.25, "vorticity": 0.75, "velocity": [1, 2, 3] },
    { "box": { "min": [1, 1, 1], "max": [1.5, 1.25, 2] }, "spacing": 0.0625, "kernel_radius": 2.5,
      "rest_density": 500, "viscosity": 0.25, "vorticity": 0.75 } ],
  "particles": [ { "x": [3, 3, 2], "v": [0, -1, 0.5], "mass": 10 }, { "x": [1, 5, 6], "mass": 0 },
                 { "x": [0, 0, 0], "mass": 2 } ],
  "distance_constraints": [ { "i": 0, "j": 1, "rest_length": 3, "compliance": 0.001953125 },
                            { "i": 2, "j": 0, "rest_length": 0 } ],
  "colliders": [ { "sphere": { "center": [1, 2, 3], "radius": 0.5 }, "friction": 0.25 },
                 { "plane": { "point": [0, 1, 0], "normal": [3, 0, 4] } },
                 { "box": { "min": [2, 2, 2], "max": [3, 2.5, 4] }, "friction": 1.5 } ] })";

TEST(SceneLoader, FullSceneRoundTrips) {
  const SceneDef s = load(kFullScene);
  EXPECT_EQ(s.name, "full");

  EXPECT_EQ(s.solver.frame_dt, 0.005);
  EXPECT_EQ(s.solver.substeps, 7);
  EXPECT_EQ(s.solver.iterations, 3);
  EXPECT_EQ(s.solver.density_tolerance, 0.0625f);
  EXPECT_EQ(s.solver.max_iterations, 5);
  EXPECT_EQ(s.solver.gravity, (Vec3{0.5f, -4.25f, 1.0f}));
  EXPECT_EQ(s.solver.relaxation, 0.125f);
  EXPECT_EQ(s.solver.tensile_k, 0.25f);
  EXPECT_EQ(s.solver.tensile_n, 2);
  EXPECT_EQ(s.solver.tensile_dq, 0.375f);

  EXPECT_EQ(s.domain.min, (Vec3{-1.0f, -2.0f, -3.0f}));
  EXPECT_EQ(s.domain.max, (Vec3{4.0f, 5.0f, 6.0f}));
  EXPECT_EQ(s.domain.friction, 0.5f);
  EXPECT_EQ(s.output.frames, 17);

  ASSERT_EQ(s.fluids.size(), 2u);
  const FluidDef& f = s.fluids[0];
  EXPECT_EQ(f.box.min, (Vec3{-1.0f, -2.0f, -3.0f}));
  EXPECT_EQ(f.box.max, (Vec3{0.0f, -1.0f, -2.0f}));
  EXPECT_EQ(f.spacing, 0.0625f);
  EXPECT_EQ(f.kernel_radius, 2.5f);
  EXPECT_EQ(f.rest_density, 500.0f);
  EXPECT_EQ(f.viscosity, 0.25f);
  EXPECT_EQ(f.vorticity, 0.75f);
  EXPECT_EQ(f.velocity, (Vec3{1.0f, 2.0f, 3.0f}));
  EXPECT_EQ(s.fluids[1].box.max, (Vec3{1.5f, 1.25f, 2.0f}));
  EXPECT_EQ(s.fluids[1].velocity, (Vec3{0.0f, 0.0f, 0.0f}));

  ASSERT_EQ(s.particles.size(), 3u);
  EXPECT_EQ(s.particles[0].x, (Vec3{3.0f, 3.0f, 2.0f}));
  EXPECT_EQ(s.particles[0].v, (Vec3{0.0f, -1.0f, 0.5f}));
  EXPECT_EQ(s.particles[0].mass, 10.0f);
  EXPECT_EQ(s.particles[1].mass, 0.0f);  // pinned
  EXPECT_EQ(s.particles[2].mass, 2.0f);

  ASSERT_EQ(s.distance_constraints.size(), 2u);
  EXPECT_EQ(s.distance_constraints[0].i, 0);
  EXPECT_EQ(s.distance_constraints[0].j, 1);
  EXPECT_EQ(s.distance_constraints[0].rest_length, 3.0f);
  EXPECT_EQ(s.distance_constraints[0].compliance, 0.001953125f);
  EXPECT_EQ(s.distance_constraints[1].i, 2);
  EXPECT_EQ(s.distance_constraints[1].rest_length, 0.0f);  // explicit zero is a length, not "unset"

  ASSERT_EQ(s.colliders.size(), 3u);
  EXPECT_EQ(s.colliders[0].shape, ColliderDef::Shape::Sphere);
  EXPECT_EQ(s.colliders[0].center, (Vec3{1.0f, 2.0f, 3.0f}));
  EXPECT_EQ(s.colliders[0].radius, 0.5f);
  EXPECT_EQ(s.colliders[0].friction, 0.25f);
  EXPECT_EQ(s.colliders[1].shape, ColliderDef::Shape::Plane);
  EXPECT_EQ(s.colliders[1].point, (Vec3{0.0f, 1.0f, 0.0f}));
  EXPECT_NEAR(s.colliders[1].normal[0], 0.6f, 1e-7f);  // [3, 0, 4] normalized
  EXPECT_EQ(s.colliders[1].normal[1], 0.0f);
  EXPECT_NEAR(s.colliders[1].normal[2], 0.8f, 1e-7f);
  EXPECT_EQ(s.colliders[2].shape, ColliderDef::Shape::Box);
  EXPECT_EQ(s.colliders[2].box.min, (Vec3{2.0f, 2.0f, 2.0f}));
  EXPECT_EQ(s.colliders[2].box.max, (Vec3{3.0f, 2.5f, 4.0f}));
  EXPECT_EQ(s.colliders[2].friction, 1.5f);
}

TEST(SceneLoader, OutputBakeKeysRoundTrip) {
  const SceneDef defaults = load("{}");
  EXPECT_EQ(defaults.output.checkpoint_every, 10);
  EXPECT_TRUE(defaults.output.particles);
  EXPECT_TRUE(defaults.output.particles_ply);  // the PLY only, as before the key existed
  EXPECT_FALSE(defaults.output.particles_vtp);
  EXPECT_TRUE(defaults.output.vdb_surface && defaults.output.vdb_density);
  EXPECT_FALSE(defaults.output.vdb_points || defaults.output.vdb_velocity || defaults.output.mesh);
  EXPECT_EQ(defaults.output.compression, "blosc");

  const SceneDef s = load(R"({"output": {"checkpoint_every": 3, "particles": false, "vdb": ["v", "points"],
    "mesh": true, "voxel_size": 0.015625, "anisotropic": true, "half_float": true, "compression": "zip"}})");
  EXPECT_EQ(s.output.checkpoint_every, 3);
  EXPECT_FALSE(s.output.particles);
  EXPECT_FALSE(s.output.vdb_surface);
  EXPECT_FALSE(s.output.vdb_density);
  EXPECT_TRUE(s.output.vdb_points);
  EXPECT_TRUE(s.output.vdb_velocity);
  EXPECT_TRUE(s.output.mesh);
  EXPECT_EQ(s.output.voxel_size, 0.015625f);
  EXPECT_TRUE(s.output.anisotropic);
  EXPECT_TRUE(s.output.half_float);
  EXPECT_EQ(s.output.compression, "zip");

  const SceneDef none = load(R"({"output": {"vdb": [], "compression": "none"}})");
  EXPECT_FALSE(none.output.any_vdb());
  EXPECT_FALSE(none.output.needs_surface());
  EXPECT_EQ(none.output.compression, "none");
  EXPECT_FALSE(load("{}", {"output.vdb=[]"}).output.any_vdb());  // what the CLI's advice passes

  const SceneDef both = load(R"({"output": {"particle_formats": ["vtp", "ply"]}})");
  EXPECT_TRUE(both.output.particles_ply && both.output.particles_vtp);
  const SceneDef vtp = load("{}", {R"(output.particle_formats=["vtp"])"});
  EXPECT_FALSE(vtp.output.particles_ply);
  EXPECT_TRUE(vtp.output.particles_vtp);
}

TEST(SceneLoader, PlaneNormalIsNormalized) {
  const SceneDef s = load(R"({"colliders": [{"plane": {"normal": [0, 0, -1e-20]}},
                                            {"plane": {"normal": [1, 1, 1]}}]})");
  EXPECT_EQ(s.colliders[0].normal, (Vec3{0.0f, 0.0f, -1.0f}));  // tiny but nonzero is fine
  for (float n : s.colliders[1].normal) EXPECT_NEAR(n, 1.0f / std::sqrt(3.0f), 1e-7f);
}

TEST(SceneLoader, IntegersMayBeWrittenAsIntegralNumbers) {
  const SceneDef s = load(R"({"solver": {"substeps": 8.0, "iterations": 1e1}})");
  EXPECT_EQ(s.solver.substeps, 8);
  EXPECT_EQ(s.solver.iterations, 10);
}

TEST(SceneLoader, BoundaryValuesAreAccepted) {
  const SceneDef s = load(R"({
    "solver": {"substeps": 10000, "iterations": 1, "relaxation": 0, "tensile_k": 0, "tensile_n": 1},
    "fluids": [{"box": {"min": [0, 0, 0], "max": [0.02, 0.02, 0.02]}, "kernel_radius": 1.5,
                "viscosity": 1, "vorticity": 0}],
    "particles": [{"x": [1, 1, 1]}, {"x": [0, 0, 0]}],
    "output": {"frames": 1}})");
  EXPECT_EQ(s.solver.substeps, 10000);
  EXPECT_EQ(s.fluids[0].viscosity, 1.0f);
  EXPECT_EQ(s.particles[0].x, (Vec3{1.0f, 1.0f, 1.0f}));  // on the domain's corner: inside
}

TEST(SceneLoader, UpperBoundsAndTheSmallestMassAreAccepted) {
  // The documented bounds themselves are valid: mass 1e-12 (read as a float, 9.9999998e-13, it
  // was once refused as "at least 1e-12, got 1e-12") and each upper bound.
  const SceneDef s = load(R"({
    "solver": {"frame_dt": 10, "tensile_k": 1},
    "fluids": [{"box": {"min": [0, 0, 0], "max": [0.02, 0.02, 0.02]}, "rest_density": 1e5, "vorticity": 100}],
    "particles": [{"x": [1, 1, 1], "mass": 1e-12}, {"x": [0, 0, 0], "mass": 1e-12}],
    "distance_constraints": [{"i": 0, "j": 1, "compliance": 1e8}],
    "cloths": [{"sheet": {"origin": [0.5, 0.5, 0.5], "size": [0.1, 0.1], "resolution": [2, 2]},
                "thickness": 1, "stretch_compliance": 1e8, "bend_compliance": 1e8}]})");
  EXPECT_EQ(s.particles[0].mass, 1e-12f);
  EXPECT_TRUE(std::isfinite(1.0f / s.particles[0].mass));  // why the bound is there
  EXPECT_EQ(s.solver.frame_dt, 10.0);
  EXPECT_EQ(s.fluids[0].rest_density, 1e5f);
  EXPECT_EQ(s.cloths[0].bend_compliance, 1e8f);
  EXPECT_EQ(s.distance_constraints[0].compliance, 1e8f);
  // Just below the smallest mass is still refused.
  EXPECT_THROW(load(R"({"particles": [{"x": [0, 0, 0], "mass": 9.9e-13}]})"), SceneError);
}

// ---- Name ------------------------------------------------------------------------------------

TEST(SceneLoader, NameComesFromTheDocumentOrFileStem) {
  EXPECT_EQ(load("{}").name, "scene");
  EXPECT_EQ(load(R"({"name": "pool"})").name, "pool");

  const TempDir dir;
  EXPECT_EQ(load_scene_file(dir.write("wave_tank.json", "{}")).name, "wave_tank");
  EXPECT_EQ(load_scene_file(dir.write("other.json", R"({"name": "given"})")).name, "given");
}

// A name is one plain file-name part (scene/output_name.hpp): the portable character set, 1 to 64
// characters, not starting with '.' or '-'.
TEST(SceneLoader, NamesWithinTheRuleAreAccepted) {
  const std::string longest(64, 'n');
  EXPECT_EQ(load(R"({"name": ")" + longest + R"("})").name, longest);
  EXPECT_EQ(load(R"({"name": "Shot_12-v2.final"})").name, "Shot_12-v2.final");
  EXPECT_EQ(load(R"({"name": "a.."})").name, "a..");
}

TEST(SceneLoader, NamesThatWouldLeaveTheOutputFolderOrBreakListingsAreRefused) {
  const struct {
    std::string name, problem;
  } cases[] = {
      {"/tmp/x", "contains '/', a path separator, at character 1"},
      {"../escape", "contains '/', a path separator, at character 3"},
      {"a/b", "contains '/', a path separator, at character 2"},
      {"./c", "contains '/'"},
      {"a\\\\b", "contains '\\', a path separator,"},
      {"..", "\"..\" is a folder, not a name"},
      {".", "\".\" is a folder, not a name"},
      {".hidden", "starts with '.'"},
      {"-rf", "starts with '-'"},
      {"a\\nb", "contains a newline at character 2"},
      {"tab\\there", "contains byte 0x09 at character 4"},
      {"two words", "contains a space at character 4"},
      {"caf\u00e9", "contains byte 0xc3 at character 4"},
      {std::string(65, 'n'), "is 65 characters long, more than 64"},
      {std::string(300, 'n'), "is 300 characters long, more than 64"},
      {"", "must not be empty"},
  };
  for (const auto& c : cases) {
    const auto e = load_error(R"({"name": ")" + c.name + R"("})");
    ASSERT_TRUE(e.has_value()) << c.name;
    EXPECT_EQ(e->json_path(), "name") << c.name;
    EXPECT_EQ(e->file(), kSource);
    EXPECT_NE(e->problem().find(c.problem), std::string::npos) << c.name << ": " << e->problem();
    EXPECT_NE(e->problem().find("it names output files"), std::string::npos) << e->problem();
    EXPECT_EQ(e->problem().find('\n'), std::string::npos) << "a message is one line: " << e->problem();
    // The same name through --set (quoted: a JSON string, with the same escapes) is the same error.
    const std::string override_text = "name=\"" + c.name + "\"";
    const auto o = load_error("{}", {override_text});
    ASSERT_TRUE(o.has_value()) << c.name;
    EXPECT_EQ(o->json_path(), "name");
    EXPECT_NE(o->problem().find(c.problem), std::string::npos) << c.name << ": " << o->problem();
  }
}

TEST(SceneLoader, AFileStemThatIsNoNameNeedsANameInTheScene) {
  const TempDir dir;
  const auto bad = [&](const char* file, const char* text) -> std::optional<SceneError> {
    try {
      load_scene_file(dir.write(file, text));
    } catch (const SceneError& e) {
      return e;
    }
    return std::nullopt;
  };
  const auto e = bad("shot 12.json", "{}");
  ASSERT_TRUE(e.has_value());
  EXPECT_EQ(e->json_path(), "name");
  EXPECT_NE(e->problem().find("its default, the file's stem, contains a space"), std::string::npos) << e->problem();
  EXPECT_NE(e->problem().find("set \"name\" in the scene or --set name="), std::string::npos) << e->problem();
  EXPECT_FALSE(bad(".hidden.json", "{}")->problem().empty());
  EXPECT_FALSE(bad("shot 12b.json", R"({"name": "shot_12"})").has_value());
}

// A cloth's name names its OBJ frames: the same rule, and no two names that write the same
// files, compared ignoring case (case-folding file systems); the message names both.
TEST(SceneLoader, ClothNamesFollowTheRuleAndWriteDistinctFiles) {
  const auto cloths = [](const std::string& a, const std::string& b, const std::string& extra = "") {
    const std::string sheet = R"("sheet": {"origin": [0.1, 0.5, 0.1], "size": [0.2, 0.2], "resolution": [3, 3]})";
    return R"({"name": "scene1", )" + extra + R"("cloths": [{"name": ")" + a + R"(", )" + sheet +
           R"(}, {"name": ")" + b + R"(", )" + sheet + "}]}";
  };
  EXPECT_EQ(load(cloths("sail", "flag")).cloths[1].name, "flag");
  struct Case {
    std::string json, path, problem;
  };
  const Case cases[] = {
      {cloths("/tmp/x", "b"), "cloths[0].name", "contains '/', a path separator, at character 1"},
      {cloths("a", "../escape"), "cloths[1].name", "contains '/'"},
      {cloths("c", "./c"), "cloths[1].name", "contains '/'"},
      {cloths("a", std::string(300, 'x')), "cloths[1].name", "is 300 characters long"},
      {cloths("a\\nb", "b"), "cloths[0].name", "contains a newline"},
      {cloths("sail", "Sail"), "cloths[1].name",
       "\"Sail\" writes the same files as cloths[0].name (\"sail\") (output names are compared ignoring case"},
      {cloths("c", "c"), "cloths[1].name", "\"c\" writes the same files as cloths[0].name (\"c\")"},
      {cloths("PARTICLES", "b"), "cloths[0].name", "writes the same files as the particle files"},
      {cloths("a", "Scene1", R"("fluids": [{"box": {"min": [0, 0, 0], "max": [0.5, 0.5, 0.5]}}], )"), "cloths[1].name",
       "writes the same files as name (\"scene1\", the scene's name"},
  };
  for (const Case& c : cases) {
    const auto e = load_error(c.json);
    ASSERT_TRUE(e.has_value()) << c.json;
    EXPECT_EQ(e->json_path(), c.path) << e->what();
    EXPECT_NE(e->problem().find(c.problem), std::string::npos) << e->problem();
  }
  // Without fluid the scene's name writes no frame files: a cloth may share it.
  EXPECT_EQ(load(cloths("scene1", "b")).cloths[0].name, "scene1");
  const std::string rename = "cloths.1.name=../esc";
  const auto o = load_error(cloths("a", "b"), {rename});
  ASSERT_TRUE(o.has_value());
  EXPECT_EQ(o->json_path(), "cloths[1].name");
}

// ---- Bad input: every case names the exact path ----------------------------------------------

struct BadCase {
  const char* label;      // test name suffix
  const char* json;
  const char* path;       // expected json_path()
  const char* problem;    // a substring of problem()
};

class BadScene : public testing::TestWithParam<BadCase> {};

TEST_P(BadScene, ThrowsWithPathAndFile) {
  const BadCase& c = GetParam();
  const auto e = load_error(c.json);
  ASSERT_TRUE(e.has_value());
  EXPECT_EQ(e->json_path(), c.path) << e->what();
  EXPECT_EQ(e->file(), kSource);
  EXPECT_NE(e->problem().find(c.problem), std::string::npos) << "problem: " << e->problem();
  EXPECT_EQ(std::string(e->what()), std::string(kSource) + ": " + c.path + ": " + e->problem());
}

// Fragments for the cases below.
#define FLUID_BOX R"("box": {"min": [0, 0, 0], "max": [0.5, 0.5, 0.5]})"
#define TWO_PARTICLES R"("particles": [{"x": [0, 0, 0]}, {"x": [1, 1, 1]}])"

const BadCase kBadCases[] = {
    // Document
    {"RootNotObject", "[1, 2]", "(root)", "expected a JSON object"},
    {"RootNull", "null", "(root)", "expected a JSON object"},
    {"Empty", "", "(root)", "malformed JSON at line 1, column 1"},
    {"TrailingComma", "{\n  \"solver\": {\"substeps\": 4,}\n}", "(root)", "malformed JSON at line 2, column"},
    {"BadLiteral", "{\n\n  \"name\": tru\n}", "(root)", "malformed JSON at line 3, column 14: syntax error"},
    {"BadLiteralMidLine", "{\"a\": 1,\n \"b\": tru}", "(root)", "at line 2, column 10:"},
    {"Truncated", "{\"a\":\n\n [1,2", "(root)", "at line 3, column 6:"},
    {"NumberOverflowsDouble", "{\"domain\":\n  {\"friction\": 1e400}}", "(root)",
     "malformed JSON at line 2, column 16: number overflow parsing '1e400'"},
    {"DuplicateKey", R"({"solver": {"substeps": 4, "substeps": 5}})", "solver.substeps", "duplicate key"},
    {"DuplicateKeyInArray", R"({"fluids": [{)" FLUID_BOX R"(}, {"box": {"min": [0,0,0], "min": [1,1,1]}}]})",
     "fluids[1].box.min", "duplicate key"},
    {"DuplicateSection", R"({"fluids": [], "output": {}, "fluids": []})", "fluids", "duplicate key"},
    {"DuplicateKeyAfterClosedEntries", R"({"fluids": [{}, {"box": {}}, {"box": {}, "spacing": 1, "box": {}}]})",
     "fluids[2].box", "duplicate key"},
    {"DuplicateKeyInNestedArrays", R"({"a": [[1, [2]], [3, {"b": [{}, {"c": {"d": 1, "e": {}, "d": 2}}]}]]})",
     "a[1][1].b[1].c.d", "duplicate key"},
    {"DuplicateRootKeyAfterNesting", R"({"solver": {"gravity": [0, -1, 0]}, "fluids": [{"box": {}}], "solver": {}})",
     "solver", "duplicate key"},
    // Unknown keys
    {"UnknownRootKey", R"({"solvr": {}})", "solvr", "unknown key; did you mean \"solver\"?"},
    {"UnknownSolverKey", R"({"solver": {"iteratons": 3}})", "solver.iteratons", "did you mean \"iterations\"?"},
    {"UnknownKeyNoHint", R"({"output": {"format": "vtk"}})", "output.format", "the keys here are: frames"},
    {"UnknownFluidKey", R"({"fluids": [{)" FLUID_BOX R"(, "spaceing": 0.1}]})", "fluids[0].spaceing",
     "did you mean \"spacing\"?"},
    {"UnknownBoxKey", R"({"fluids": [{"box": {"min": [0,0,0], "mx": [1,1,1]}}]})", "fluids[0].box.mx",
     "did you mean \"max\"?"},
    {"TypoOfRequiredKey", R"({"fluids": [{"bx": {}}]})", "fluids[0].bx", "did you mean \"box\"?"},
    {"UnknownColliderShape", R"({"colliders": [{"sphera": {"radius": 1}}]})", "colliders[0].sphera",
     "did you mean \"sphere\"?"},
    {"UnknownSphereKey", R"({"colliders": [{"sphere": {"radius": 1, "centre": [0,0,0]}}]})",
     "colliders[0].sphere.centre", "did you mean \"center\"?"},
    {"UnknownParticleKey", R"({"particles": [{"x": [0,0,0], "mas": 1}]})", "particles[0].mas",
     "did you mean \"mass\"?"},
    // Types and shapes
    {"StringForInteger", R"({"solver": {"substeps": "4"}})", "solver.substeps", "expected an integer, got string"},
    {"StringForNumber", R"({"domain": {"friction": "0.1"}})", "domain.friction", "expected a number, got string"},
    {"StringNan", R"({"solver": {"relaxation": "nan"}})", "solver.relaxation", "expected a number, got string \"nan\""},
    {"BoolForNumber", R"({"fluids": [{)" FLUID_BOX R"(, "spacing": true}]})", "fluids[0].spacing",
     "expected a number, got boolean"},
    {"NullForNumber", R"({"solver": {"frame_dt": null}})", "solver.frame_dt", "expected a number, got null"},
    {"FractionalInteger", R"({"solver": {"iterations": 2.5}})", "solver.iterations", "expected an integer, got 2.5"},
    {"HugeInteger", R"({"output": {"frames": 1e12}})", "output.frames", "outside the range of a 32-bit integer"},
    {"NameNotString", R"({"name": 5})", "name", "expected a string, got 5"},
    {"NameEmpty", R"({"name": ""})", "name", "must not be empty"},
    {"SectionNotObject", R"({"solver": 3})", "solver", "expected an object, got 3"},
    {"ListNotArray", R"({"fluids": {}})", "fluids", "expected an array of objects, got object"},
    {"EntryNotObject", R"({"particles": [{"x": [0,0,0]}, 7]})", "particles[1]", "expected an object, got 7"},
    {"VecTooShort", R"({"solver": {"gravity": [0, -9.81]}})", "solver.gravity", "expected 3 numbers, got 2"},
    {"VecTooLong", R"({"domain": {"max": [1, 1, 1, 1]}})", "domain.max", "expected 3 numbers, got 4"},
    {"VecNotArray", R"({"domain": {"max": 1}})", "domain.max", "expected an array of 3 numbers"},
    {"VecElementType", R"({"solver": {"gravity": [0, "down", 0]}})", "solver.gravity[1]", "expected a number"},
    // Not finite as float
    {"FloatOverflow", R"({"domain": {"friction": 1e39}})", "domain.friction", "not finite as a 32-bit float"},
    {"VecElementOverflow", R"({"solver": {"gravity": [0, -1e39, 0]}})", "solver.gravity[1]", "not finite"},
    // Ranges: solver
    {"FrameDtZero", R"({"solver": {"frame_dt": 0}})", "solver.frame_dt", "must be in (0, 10], got 0"},
    {"FrameDtNegative", R"({"solver": {"frame_dt": -0.01}})", "solver.frame_dt", "must be in (0, 10]"},
    {"SubstepsZero", R"({"solver": {"substeps": 0}})", "solver.substeps", "must be in [1, 10000], got 0"},
    {"SubstepsHuge", R"({"solver": {"substeps": 10001}})", "solver.substeps", "must be in [1, 10000]"},
    {"IterationsZero", R"({"solver": {"iterations": 0}})", "solver.iterations", "must be in [1, 10000]"},
    {"IterationsHuge", R"({"solver": {"iterations": 1000000}})", "solver.iterations", "must be in [1, 10000]"},
    {"DensityToleranceNegative", R"({"solver": {"density_tolerance": -0.01}})", "solver.density_tolerance",
     "must be in [0, 1), got -0.01"},
    {"DensityToleranceOne", R"({"solver": {"density_tolerance": 1}})", "solver.density_tolerance", "must be in [0, 1)"},
    {"MaxIterationsZero", R"({"solver": {"max_iterations": 0}})", "solver.max_iterations", "must be in [1, 10000]"},
    {"RelaxationNegative", R"({"solver": {"relaxation": -0.5}})", "solver.relaxation", "must be >= 0, got -0.5"},
    {"TensileKNegative", R"({"solver": {"tensile_k": -0.1}})", "solver.tensile_k", "must be in [0, 1]"},
    // Upper bounds: values past them passed once and gave NaN in frame 1
    {"FrameDtHuge", R"({"solver": {"frame_dt": 1e39}})", "solver.frame_dt", "must be in (0, 10], got 1e+39"},
    {"FrameDtAboveTen", R"({"solver": {"frame_dt": 10.5}})", "solver.frame_dt", "must be in (0, 10], got 10.5"},
    {"TensileKHuge", R"({"solver": {"tensile_k": 3e38}})", "solver.tensile_k", "must be in [0, 1], got 3e+38"},
    {"RestDensityHuge", R"({"fluids": [{)" FLUID_BOX R"(, "rest_density": 3e38}]})", "fluids[0].rest_density",
     "must be in (0, 100000], got 3e+38"},
    {"VorticityHuge", R"({"fluids": [{)" FLUID_BOX R"(, "vorticity": 3e38}]})", "fluids[0].vorticity",
     "must be in [0, 100], got 3e+38"},
    {"ConstraintComplianceHuge",
     "{" TWO_PARTICLES R"(, "distance_constraints": [{"i": 0, "j": 1, "compliance": 3e38}]})",
     "distance_constraints[0].compliance", "must be in [0, 100000000], got 3e+38"},
    {"ClothThicknessHuge", R"({"cloths": [{"sheet": {"origin": [0.5, 0.5, 0.5], "size": [0.1, 0.1], "resolution": [2, 2]}, "thickness": 3e38}]})", "cloths[0].thickness",
     "must be in (0, 1], got 3e+38"},
    {"ClothStretchComplianceHuge", R"({"cloths": [{"sheet": {"origin": [0.5, 0.5, 0.5], "size": [0.1, 0.1], "resolution": [2, 2]}, "stretch_compliance": 3e38}]})",
     "cloths[0].stretch_compliance", "must be in [0, 100000000], got 3e+38"},
    {"ClothBendComplianceHuge", R"({"cloths": [{"sheet": {"origin": [0.5, 0.5, 0.5], "size": [0.1, 0.1], "resolution": [2, 2]}, "bend_compliance": 3e38}]})", "cloths[0].bend_compliance",
     "must be in (0, 100000000], got 3e+38"},
    {"TensileNBelowOne", R"({"solver": {"tensile_n": 0}})", "solver.tensile_n", "must be in [1, 8]"},
    {"TensileNNotInteger", R"({"solver": {"tensile_n": 2.5}})", "solver.tensile_n", "integer"},
    {"TensileDqZero", R"({"solver": {"tensile_dq": 0}})", "solver.tensile_dq", "must be in (0, 1)"},
    {"TensileDqOne", R"({"solver": {"tensile_dq": 1}})", "solver.tensile_dq", "must be in (0, 1)"},
    // Ranges: domain, output
    {"DomainFlat", R"({"domain": {"min": [0, 0, 1], "max": [1, 1, 1]}})", "domain", "along z min = 1 and max = 1"},
    {"DomainInverted", R"({"domain": {"min": [2, 0, 0]}})", "domain", "along x min = 2 and max = 1"},
    {"DomainFrictionNegative", R"({"domain": {"friction": -0.1}})", "domain.friction", "must be >= 0"},
    {"FramesZero", R"({"output": {"frames": 0}})", "output.frames", "must be >= 1, got 0"},
    // Output: bake keys
    {"CheckpointEveryZero", R"({"output": {"checkpoint_every": 0}})", "output.checkpoint_every", "must be >= 1, got 0"},
    {"CheckpointEveryNegative", R"({"output": {"checkpoint_every": -5}})", "output.checkpoint_every", "must be >= 1"},
    {"CheckpointEveryFractional", R"({"output": {"checkpoint_every": 2.5}})", "output.checkpoint_every",
     "expected an integer"},
    {"VdbUnknownGrid", R"({"output": {"vdb": ["surface", "velocity"]}})", "output.vdb[1]",
     "\"velocity\" is not one of"},
    {"VdbDuplicateGrid", R"({"output": {"vdb": ["density", "points", "density"]}})", "output.vdb[2]",
     "\"density\" is listed twice"},
    {"VdbNotAnArray", R"({"output": {"vdb": "surface"}})", "output.vdb", "expected an array of strings"},
    {"VdbElementNotString", R"({"output": {"vdb": ["surface", 3]}})", "output.vdb[1]", "expected a string, got 3"},
    {"ParticleFormatUnknown", R"({"output": {"particle_formats": ["ply", "vtk"]}})", "output.particle_formats[1]",
     "\"vtk\" is not one of \"ply\" or \"vtp\""},
    {"ParticleFormatTwice", R"({"output": {"particle_formats": ["vtp", "vtp"]}})", "output.particle_formats[1]",
     "\"vtp\" is listed twice"},
    {"ParticleFormatsEmpty", R"({"output": {"particle_formats": []}})", "output.particle_formats",
     "lists no format: give \"ply\", \"vtp\" or both (a bake writes no particle files with output.particles = "
     "false)"},
    {"ParticleFormatsNotAnArray", R"({"output": {"particle_formats": "vtp"}})", "output.particle_formats",
     "expected an array of strings"},
    {"CompressionUnknown", R"({"output": {"compression": "lz4"}})", "output.compression",
     "\"lz4\" is not one of"},
    {"CompressionNotString", R"({"output": {"compression": true}})", "output.compression", "expected a string"},
    {"ParticlesNotBool", R"({"output": {"particles": 1}})", "output.particles", "expected true or false, got 1"},
    {"MeshNotBool", R"({"output": {"mesh": "yes"}})", "output.mesh", "expected true or false, got string"},
    {"AnisotropicNotBool", R"({"output": {"anisotropic": null}})", "output.anisotropic", "expected true or false"},
    {"HalfFloatNotBool", R"({"output": {"half_float": [true]}})", "output.half_float", "expected true or false"},
    {"VoxelSizeNegative", R"({"output": {"voxel_size": -0.01}})", "output.voxel_size", "must be >= 0"},
    // Ranges: fluids
    {"FluidBoxMissing", R"({"fluids": [{"spacing": 0.1}]})", "fluids[0].box", "required key is missing"},
    {"FluidBoxInverted", R"({"fluids": [{"box": {"min": [0, 0.5, 0], "max": [1, 0.25, 1]}}]})", "fluids[0].box",
     "min > max along y (0.5 > 0.25)"},
    {"SpacingZero", R"({"fluids": [{)" FLUID_BOX R"(, "spacing": 0}]})", "fluids[0].spacing", "must be > 0, got 0"},
    {"SpacingNegative", R"({"fluids": [{)" FLUID_BOX R"(, "spacing": -0.1}]})", "fluids[0].spacing", "must be > 0"},
    {"KernelRadiusBelowOne", R"({"fluids": [{)" FLUID_BOX R"(, "kernel_radius": 0.5}]})", "fluids[0].kernel_radius",
     "must be in [1.5, 4]"},
    {"KernelRadiusOne", R"({"fluids": [{)" FLUID_BOX R"(, "kernel_radius": 1}]})", "fluids[0].kernel_radius",
     "must be in [1.5, 4]"},
    {"KernelRadiusHuge", R"({"fluids": [{)" FLUID_BOX R"(, "kernel_radius": 5}]})", "fluids[0].kernel_radius",
     "must be in [1.5, 4]"},
    {"SubstepUnderflows", R"({"solver": {"frame_dt": 1e-30}})", "solver.frame_dt", "gives substeps of"},
    {"SubnormalMass", R"({"particles": [{"x": [0,0,0], "mass": 1e-40}]})", "particles[0].mass",
     "must be 0 (pinned) or at least"},
    {"RestDensityZero", R"({"fluids": [{)" FLUID_BOX R"(, "rest_density": 0}]})", "fluids[0].rest_density",
     "must be in (0, 100000]"},
    {"ViscosityAboveOne", R"({"fluids": [{)" FLUID_BOX R"(, "viscosity": 1.5}]})", "fluids[0].viscosity",
     "must be in [0, 1], got 1.5"},
    {"ViscosityNegative", R"({"fluids": [{)" FLUID_BOX R"(, "viscosity": -0.01}]})", "fluids[0].viscosity",
     "must be in [0, 1]"},
    {"VorticityNegative", R"({"fluids": [{)" FLUID_BOX R"(, "vorticity": -1}]})", "fluids[0].vorticity",
     "must be in [0, 100]"},
    {"FluidTooManyParticles", R"({"fluids": [{)" FLUID_BOX R"(, "spacing": 0.001}]})", "fluids[0].box",
     "would hold 125000000 particles"},
    {"FluidNoParticles", R"({"fluids": [{"box": {"min": [0, 0, 0], "max": [1, 0.01, 1]}}]})", "fluids[0].box",
     "holds no particles: along y it is 0.01 m thick, less than one spacing (0.02 m)"},
    {"FluidOutsideDomain", R"({"fluids": [{"box": {"min": [0.5, 0.5, 0.5], "max": [1.5, 1, 1]}}]})",
     "fluids[0].box", "reaches outside the domain [0, 0, 0]..[1, 1, 1]"},
    {"FluidSpacingDiffers",
     R"({"fluids": [{)" FLUID_BOX R"(}, {)" FLUID_BOX R"(, "spacing": 0.025}]})", "fluids[1].spacing",
     "0.025 differs from fluids[0] (0.02); all fluids of a scene share one material"},
    {"FluidKernelRadiusDiffers",
     R"({"fluids": [{)" FLUID_BOX R"(}, {)" FLUID_BOX R"(}, {)" FLUID_BOX R"(, "kernel_radius": 3}]})",
     "fluids[2].kernel_radius", "differs from fluids[0] (2)"},
    {"FluidRestDensityDiffers", R"({"fluids": [{)" FLUID_BOX R"(}, {)" FLUID_BOX R"(, "rest_density": 999}]})",
     "fluids[1].rest_density", "differs from fluids[0] (1000)"},
    {"FluidViscosityDiffers", R"({"fluids": [{)" FLUID_BOX R"(, "viscosity": 0}, {)" FLUID_BOX R"(}]})",
     "fluids[1].viscosity", "differs from fluids[0] (0)"},
    {"FluidVorticityDiffers", R"({"fluids": [{)" FLUID_BOX R"(}, {)" FLUID_BOX R"(, "vorticity": 0.5}]})",
     "fluids[1].vorticity", "differs from fluids[0] (0)"},
    // Particles
    {"ParticleXMissing", R"({"particles": [{"x": [0,0,0]}, {"v": [0, 0, 0]}]})", "particles[1].x",
     "required key is missing"},
    {"ParticleMassNegative", R"({"particles": [{"x": [0,0,0]}, {"x": [0,0,0]}, {"x": [0,0,0]},
                                               {"x": [0,0,0], "mass": -1}]})",
     "particles[3].mass", "must be >= 0, got -1"},
    {"ParticleOutsideDomain", R"({"particles": [{"x": [0,0,0]}, {"x": [5, 3, 2]}]})", "particles[1].x",
     "[5, 3, 2] is outside the domain [0, 0, 0]..[1, 1, 1]"},
    // Distance constraints
    {"ConstraintJMissing", "{" TWO_PARTICLES R"(, "distance_constraints": [{"i": 0}]})", "distance_constraints[0].j",
     "required key is missing"},
    {"ConstraintIndexTooLarge", "{" TWO_PARTICLES R"(, "distance_constraints": [{"i": 0, "j": 1}, {"i": 2, "j": 0}]})",
     "distance_constraints[1].i", "particle index 2 is out of range (valid: 0..1)"},
    {"ConstraintIndexNegative", "{" TWO_PARTICLES R"(, "distance_constraints": [{"i": 0, "j": -1}]})",
     "distance_constraints[0].j", "out of range (valid: 0..1)"},
    {"ConstraintWithoutParticles", R"({"distance_constraints": [{"i": 0, "j": 1}]})", "distance_constraints[0].i",
     "\"particles\" is empty"},
    {"ConstraintSameParticle", "{" TWO_PARTICLES R"(, "distance_constraints": [{"i": 1, "j": 1}]})",
     "distance_constraints[0].j", "equals i (1)"},
    {"ConstraintNegativeRestLength",
     "{" TWO_PARTICLES R"(, "distance_constraints": [{"i": 0, "j": 1, "rest_length": -1}]})",
     "distance_constraints[0].rest_length", "must be >= 0, got -1"},
    {"ConstraintNegativeCompliance",
     "{" TWO_PARTICLES R"(, "distance_constraints": [{"i": 0, "j": 1, "compliance": -1e-6}]})",
     "distance_constraints[0].compliance", "must be in [0, 100000000]"},
    {"ConstraintIndexNotInteger", "{" TWO_PARTICLES R"(, "distance_constraints": [{"i": 0.5, "j": 1}]})",
     "distance_constraints[0].i", "expected an integer"},
    // Colliders
    {"ColliderNoShape", R"({"colliders": [{"friction": 0.2}]})", "colliders[0]", "needs a shape"},
    {"ColliderTwoShapes", R"({"colliders": [{"plane": {}, "sphere": {"radius": 1}}]})", "colliders[0]",
     "exactly one shape"},
    {"ColliderFrictionNegative", R"({"colliders": [{"plane": {}, "friction": -1}]})", "colliders[0].friction",
     "must be >= 0"},
    {"SphereRadiusMissing", R"({"colliders": [{"plane": {}}, {"sphere": {"center": [0,0,0]}}]})",
     "colliders[1].sphere.radius", "required key is missing"},
    {"SphereRadiusZero", R"({"colliders": [{"sphere": {"radius": 0}}]})", "colliders[0].sphere.radius",
     "must be > 0"},
    {"PlaneNormalZero", R"({"colliders": [{"plane": {"normal": [0, 0, 0]}}]})", "colliders[0].plane.normal",
     "must not be zero"},
    {"ColliderBoxInverted", R"({"colliders": [{"box": {"min": [0, 0, 2], "max": [1, 1, 1]}}]})", "colliders[0].box",
     "min > max along z"},
    {"ColliderShapeNotObject", R"({"colliders": [{"plane": [0, 1, 0]}]})", "colliders[0].plane",
     "expected an object"},
    // Rigid bodies
    {"BodyNameMissing", R"({"rigid_bodies": [{"position": [0.5, 0.5, 0.5]}]})", "rigid_bodies[0].name",
     "required key is missing"},
    {"BodyPositionMissing", R"({"rigid_bodies": [{"name": "a"}]})", "rigid_bodies[0].position",
     "required key is missing"},
    {"BodyDensityZero", R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5], "density": 0}]})",
     "rigid_bodies[0].density", "must be in (0, 100000], got 0"},
    {"BodyDensityNegative", R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5], "density": -5}]})",
     "rigid_bodies[0].density", "must be in (0, 100000]"},
    {"BodyFrictionNegative",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5], "friction": -0.1}]})",
     "rigid_bodies[0].friction", "must be >= 0, got -0.1"},
    {"BodyDynamicFrictionNegative",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5], "dynamic_friction": -1}]})",
     "rigid_bodies[0].dynamic_friction", "must be >= 0, got -1"},
    {"BodyRestitutionAboveOne",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5], "restitution": 1.5}]})",
     "rigid_bodies[0].restitution", "must be in [0, 1], got 1.5"},
    {"BodyRestitutionNegative",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5], "restitution": -0.5}]})",
     "rigid_bodies[0].restitution", "must be in [0, 1], got -0.5"},
    {"BodyBoxSizeZero", R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5], "size": [0.1, 0, 0.1]}]})",
     "rigid_bodies[0].size", "every edge must be longer than 0 m (y is 0)"},
    {"BodyBoxSizeNegative",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5], "size": [0.1, 0.1, -1]}]})",
     "rigid_bodies[0].size", "(z is -1)"},
    {"BodyRadiusZero",
     R"({"rigid_bodies": [{"name": "a", "shape": "sphere", "position": [0.5, 0.5, 0.5], "radius": 0}]})",
     "rigid_bodies[0].radius", "must be > 0"},
    {"BodyCapsuleLengthNegative",
     R"({"rigid_bodies": [{"name": "a", "shape": "capsule", "position": [0.5, 0.5, 0.5], "length": -0.1}]})",
     "rigid_bodies[0].length", "must be > 0"},
    {"BodyUnknownShape", R"({"rigid_bodies": [{"name": "a", "shape": "cone", "position": [0.5, 0.5, 0.5]}]})",
     "rigid_bodies[0].shape", "\"box\""},
    {"BodySizeOfASphere",
     R"({"rigid_bodies": [{"name": "a", "shape": "sphere", "position": [0.5, 0.5, 0.5], "size": [1, 1, 1]}]})",
     "rigid_bodies[0].size", "a sphere has no \"size\""},
    {"BodyMeshWithoutItsObject", R"({"rigid_bodies": [{"name": "a", "shape": "mesh", "position": [0.5, 0.5, 0.5]}]})",
     "rigid_bodies[0].shape", "no \"mesh\" object"},
    {"BodyMeshOfABox",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5], "mesh": {"file": "cube.obj"}}]})",
     "rigid_bodies[0].mesh", "a box has no \"mesh\""},
    {"BodyMeshWithASize",
     R"({"rigid_bodies": [{"name": "a", "shape": "mesh", "position": [0.5, 0.5, 0.5], "size": [1, 1, 1],
                           "mesh": {"file": "cube.obj"}}]})",
     "rigid_bodies[0].size", "a mesh has no \"size\""},
    {"BodyMeshTranslated",
     R"({"rigid_bodies": [{"name": "a", "shape": "mesh", "position": [0.5, 0.5, 0.5],
                           "mesh": {"file": "cube.obj", "translate": [1, 0, 0]}}]})",
     "rigid_bodies[0].mesh.translate", "unknown key"},
    {"BodyMeshFileMissing",
     R"({"rigid_bodies": [{"name": "a", "shape": "mesh", "position": [0.5, 0.5, 0.5], "mesh": {"file": "/nonexistent/x.obj"}}]})",
     "rigid_bodies[0].mesh.file", "x.obj"},
    {"BodyDuplicateName",
     R"({"rigid_bodies": [{"name": "Arm", "position": [0.5, 0.5, 0.5]}, {"name": "arm", "position": [0.5, 0.5, 0.5]}]})",
     "rigid_bodies[1].name", "also the name of rigid_bodies[0]"},
    {"BodyNamedWorld", R"({"rigid_bodies": [{"name": "World", "position": [0.5, 0.5, 0.5]}]})",
     "rigid_bodies[0].name", "\"world\""},
    {"BodyNameWithSlash", R"({"rigid_bodies": [{"name": "a/b", "position": [0.5, 0.5, 0.5]}]})",
     "rigid_bodies[0].name", "'/'"},
    {"BodyOutsideDomain", R"({"rigid_bodies": [{"name": "a", "position": [0.5, 2, 0.5]}]})",
     "rigid_bodies[0].position", "outside the domain"},
    {"BodyTurnWithoutAxis",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5], "axis": [0, 0, 0], "angle": 30}]})",
     "rigid_bodies[0].axis", "is zero"},
    {"BodyTooLight",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5], "size": [1e-4, 1e-4, 1e-4], "density": 1}]})",
     "rigid_bodies[0].density", "the lightest allowed"},
    // Joints
    {"JointMissingBody",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"body_b": "b", "anchor": [0.5, 0.9, 0.5]}]})",
     "joints[0].body_b", "names no body: \"b\""},
    {"JointMissingBodyA",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"body_a": "c", "body_b": "a", "anchor": [0.5, 0.9, 0.5]}]})",
     "joints[0].body_a", "names no body: \"c\""},
    {"JointSameBody",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"body_a": "a", "body_b": "a", "anchor": [0.5, 0.9, 0.5]}]})",
     "joints[0].body_b", "also body_a"},
    {"JointAnchorMissing",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"body_b": "a"}]})",
     "joints[0].anchor", "required key is missing"},
    {"JointUnknownType",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "weld", "body_b": "a", "anchor": [0.5, 0.9, 0.5]}]})",
     "joints[0].type", "\"hinge\""},
    {"HingeAxisZero",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "hinge", "body_b": "a", "anchor": [0.5, 0.9, 0.5], "axis": [0, 0, 0]}]})",
     "joints[0].axis", "a hinge's axis must not be zero"},
    {"HingeLimitsInverted",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "hinge", "body_b": "a", "anchor": [0.5, 0.9, 0.5], "limits": [30, -30]}]})",
     "joints[0].limits", "above the upper limit"},
    {"HingeLimitsOutOfRange",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "hinge", "body_b": "a", "anchor": [0.5, 0.9, 0.5], "limits": [-200, 30]}]})",
     "joints[0].limits[0]", "[-180, 180]"},
    {"BallJointLimits",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"body_b": "a", "anchor": [0.5, 0.9, 0.5], "limits": [-30, 30]}]})",
     "joints[0].limits", "a ball joint has no \"limits\" (only a hinge has)"},
    {"HingeTwoMotorTargets",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "hinge", "body_b": "a", "anchor": [0.5, 0.9, 0.5], "target_angle": 10, "target_velocity": 5}]})",
     "joints[0].target_velocity", "not both"},
    {"DistanceRangeInverted",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "distance", "body_b": "a", "anchor": [0.5, 0.9, 0.5], "distance": [0.5, 0.2]}]})",
     "joints[0].distance", "the lower distance 0.5 is above the upper distance 0.2"},
    {"DistanceNegative",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "distance", "body_b": "a", "anchor": [0.5, 0.9, 0.5], "distance": [-1, 0.2]}]})",
     "joints[0].distance[0]", "must be >= 0"},
    {"SliderTravelInverted",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "slider", "body_b": "a", "anchor": [0.5, 0.5, 0.5], "axis": [1, 0, 0], "travel": [0.1, -0.1]}]})",
     "joints[0].travel", "the lower travel 0.1 is above the upper travel -0.1"},
    {"SliderAxisZero",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "slider", "body_b": "a", "anchor": [0.5, 0.5, 0.5], "axis": [0, 0, 0]}]})",
     "joints[0].axis", "a slider's axis must not be zero"},
    {"HingeTravel",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "hinge", "body_b": "a", "anchor": [0.5, 0.5, 0.5], "travel": [0, 1]}]})",
     "joints[0].travel", "only a slider has"},
    {"BallAnchorB",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"body_b": "a", "anchor": [0.5, 0.5, 0.5], "anchor_b": [0.5, 0.4, 0.5]}]})",
     "joints[0].anchor_b", "only a distance joint has"},
    {"UniversalAxesNotPerpendicular",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}, {"name": "b", "position": [0.5, 0.2, 0.5]}], "joints": [{"type": "universal", "body_a": "a", "body_b": "b", "anchor": [0.5, 0.35, 0.5], "axis": [0, 0, 1], "axis_b": [0, 0.1, 1]}]})",
     "joints[0].axis_b", "is at 5.711 degrees to axis [0, 0, 1]: a universal joint's axes must be perpendicular"},
    {"UniversalAxisBMissing",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}, {"name": "b", "position": [0.5, 0.2, 0.5]}], "joints": [{"type": "universal", "body_a": "a", "body_b": "b", "anchor": [0.5, 0.35, 0.5], "axis": [0, 0, 1]}]})",
     "joints[0].axis_b", "required key is missing"},
    {"UniversalAxisBZero",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}, {"name": "b", "position": [0.5, 0.2, 0.5]}], "joints": [{"type": "universal", "body_a": "a", "body_b": "b", "anchor": [0.5, 0.35, 0.5], "axis": [0, 0, 1], "axis_b": [0, 0, 0]}]})",
     "joints[0].axis_b", "a universal joint's axis_b must not be zero"},
    {"UniversalAxisZero",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}, {"name": "b", "position": [0.5, 0.2, 0.5]}], "joints": [{"type": "universal", "body_a": "a", "body_b": "b", "anchor": [0.5, 0.35, 0.5], "axis": [0, 0, 0], "axis_b": [1, 0, 0]}]})",
     "joints[0].axis", "a universal's axis must not be zero"},
    {"HingeAxisB",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "hinge", "body_b": "a", "anchor": [0.5, 0.9, 0.5], "axis_b": [1, 0, 0]}]})",
     "joints[0].axis_b", "a hinge joint has no \"axis_b\" (only a universal joint has)"},
    {"MotorWithoutTarget",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "hinge", "body_b": "a", "anchor": [0.5, 0.9, 0.5], "motor_compliance": 1e-3}]})",
     "joints[0].motor_compliance", "a motor without a target: give the hinge a target_angle or a target_velocity"},
    {"SliderMotorWithoutTarget",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "slider", "body_b": "a", "anchor": [0.5, 0.5, 0.5], "axis": [1, 0, 0], "motor_compliance": 1e-3}]})",
     "joints[0].motor_compliance", "give the slider a target_position or a target_velocity"},
    {"SliderTwoMotorTargets",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "slider", "body_b": "a", "anchor": [0.5, 0.5, 0.5], "axis": [1, 0, 0], "target_position": 0.1, "target_velocity": 1}]})",
     "joints[0].target_velocity", "a target position or at a target velocity, not both"},
    {"SliderTargetAngle",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "slider", "body_b": "a", "anchor": [0.5, 0.5, 0.5], "axis": [1, 0, 0], "target_angle": 10}]})",
     "joints[0].target_angle", "a slider joint has no \"target_angle\" (only a hinge has)"},
    {"HingeTargetPosition",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"type": "hinge", "body_b": "a", "anchor": [0.5, 0.9, 0.5], "target_position": 0.1}]})",
     "joints[0].target_position", "only a slider has"},
    {"BallTargetVelocity",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"body_b": "a", "anchor": [0.5, 0.9, 0.5], "target_velocity": 1}]})",
     "joints[0].target_velocity", "(only a hinge or a slider has)"},
    {"JointComplianceNegative",
     R"({"rigid_bodies": [{"name": "a", "position": [0.5, 0.5, 0.5]}], "joints": [{"body_b": "a", "anchor": [0.5, 0.9, 0.5], "compliance": -1}]})",
     "joints[0].compliance", "must be >= 0"},
};

INSTANTIATE_TEST_SUITE_P(SceneLoader, BadScene, testing::ValuesIn(kBadCases),
                         [](const testing::TestParamInfo<BadCase>& info) { return std::string(info.param.label); });

// A scene of more rigid bodies than the body contacts' pair lists are bounded for (4096: every
// pair is kept and tested each substep) is refused at "rigid_bodies", naming the bound; 4096
// small bodies load.
TEST(SceneLoader, MoreThan4096RigidBodiesAreRefused) {
  const auto scene_of = [](int bodies) {
    std::string text = R"({"domain": {"min": [0, 0, 0], "max": [100, 1, 100]}, "rigid_bodies": [)";
    for (int k = 0; k < bodies; ++k)
      text += fmt::format(R"({}{{"name": "b{}", "position": [{}, 0.5, {}]}})", k == 0 ? "" : ",", k, 0.5 + k % 64, 0.5 + k / 64);
    return text + "]}";
  };
  EXPECT_EQ(load(scene_of(4096)).rigid_bodies.size(), 4096u);
  const std::optional<SceneError> e = load_error(scene_of(4097));
  ASSERT_TRUE(e.has_value());
  EXPECT_EQ(e->json_path(), "rigid_bodies");
  EXPECT_NE(std::string(e->what()).find("4097 bodies; at most 4096"), std::string::npos) << e->what();
}

// ---- Parsing big documents ------------------------------------------------------------------

// The parser builds the document nlohmann's own parser builds: every value type, escapes, nesting
// of arrays and objects in both orders, empty containers, and a root that is not an object.
TEST(SceneParser, BuildsTheSameDocumentAsNlohmann) {
  const std::string texts[] = {
      R"({"a": [1, -2, 3.5e-3, 18446744073709551615, -9223372036854775808, true, false, null, "s\u00e9\n"],
          "b": {"c": [[], {}, [[{"d": [{}]}]], {"e": {"f": []}}], "g": ""}, "": 0, "z": [[1, 2], [3]]})",
      "[1, [2, {\"x\": [3]}], {}]", "\"text\"", "42", "null", "{}"};
  for (const std::string& text : texts) {
    EXPECT_EQ(detail::parse_json(text, "t.json"), nlohmann::json::parse(text)) << text;
  }
}

// An object of 100k keys: every key and value is in the document; a duplicate of the first key
// at the very end is still found, with its path.
TEST(SceneParser, ObjectOf100kKeys) {
  constexpr int kKeys = 100'000;
  std::string text = R"({"particles": [{"x": [0, 0, 0])";
  for (int k = 0; k < kKeys; ++k) text += ", \"key" + std::to_string(k) + "\": " + std::to_string(3 * k);
  const nlohmann::json document = detail::parse_json(text + "}]}", "keys.json");
  const nlohmann::json& object = document.at("particles").at(0);
  ASSERT_EQ(object.size(), static_cast<std::size_t>(kKeys) + 1);
  for (int k : {0, 1, 4'711, kKeys - 1}) EXPECT_EQ(object.at("key" + std::to_string(k)), 3 * k) << k;

  const auto e = load_error(text + R"(, "key0": 1}]})");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->json_path(), "particles[0].key0");
  EXPECT_NE(e->problem().find("duplicate key"), std::string::npos) << e->problem();
  // Without the duplicate, the document reaches the reader, which names the first unknown key.
  const auto unknown = load_error(text + "}]}");
  ASSERT_TRUE(unknown);
  EXPECT_EQ(unknown->json_path(), "particles[0].key0");
  EXPECT_NE(unknown->problem().find("unknown key"), std::string::npos) << unknown->problem();
}

// 200k raw particles (loading 160k took 8.75 s with the quadratic parser) load with every value
// in place; the time is measured by benchmarks/bench_scene_load, not here.
TEST(SceneParser, TwoHundredThousandRawParticles) {
  constexpr int kParticles = 200'000;
  const auto coordinate = [](int k, int axis) { return static_cast<float>(((k * (axis + 3)) % 1000) / 1024.0); };
  std::string text = R"({"domain": {"min": [0, 0, 0], "max": [1, 1, 1]}, "particles": [)";
  for (int k = 0; k < kParticles; ++k) {
    text += fmt::format("{}{{\"x\": [{}, {}, {}], \"v\": [{}, 0, 0], \"mass\": {}}}", k == 0 ? "" : ",",
                        coordinate(k, 0), coordinate(k, 1), coordinate(k, 2), k % 7, k % 3);
  }
  const SceneDef scene = load_scene_text(text + "]}", "many.json");
  ASSERT_EQ(scene.particles.size(), static_cast<std::size_t>(kParticles));
  for (int k : {0, 1, 99'999, kParticles - 1}) {
    const ParticleDef& p = scene.particles[static_cast<std::size_t>(k)];
    for (int axis = 0; axis < 3; ++axis) EXPECT_EQ(p.x[axis], coordinate(k, axis)) << k << " " << axis;
    EXPECT_EQ(p.v[0], static_cast<float>(k % 7)) << k;
    EXPECT_EQ(p.mass, static_cast<float>(k % 3)) << k;
  }
}

// ---- Files -----------------------------------------------------------------------------------

TEST(SceneLoaderFile, MissingFileSaysItCannotBeOpenedAndWhy) {
  const TempDir dir;
  const fs::path missing = dir.path() / "nope.json";
  try {
    load_scene_file(missing);
    FAIL() << "no SceneError";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.file(), missing.string());
    EXPECT_EQ(e.json_path(), "(file)");
    EXPECT_NE(e.problem().find("cannot open"), std::string::npos) << e.what();
    EXPECT_NE(e.problem().find("No such file"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind(missing.string() + ": (file): ", 0), 0u) << e.what();
  }
}

TEST(SceneLoaderFile, DirectoryIsNotAScene) {
  const TempDir dir;
  try {
    load_scene_file(dir.path());
    FAIL() << "no SceneError";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.json_path(), "(file)");
    EXPECT_NE(e.problem().find("directory"), std::string::npos) << e.what();
  }
}

// Refused before anything is read: a device would be read without end, a FIFO might block.
TEST(SceneLoaderFile, DevicesAndFifosAreNotScenes) {
  const TempDir dir;
  const fs::path fifo = dir.path() / "pipe.json";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const auto& [file, kind] : {std::pair{fs::path("/dev/zero"), "character device"}, std::pair{fifo, "FIFO"}}) {
    try {
      load_scene_file(file);
      FAIL() << "no SceneError for " << file;
    } catch (const SceneError& e) {
      EXPECT_EQ(e.file(), file.string());
      EXPECT_EQ(e.json_path(), "(file)");
      EXPECT_NE(e.problem().find("not a regular file"), std::string::npos) << e.what();
      EXPECT_NE(e.problem().find(kind), std::string::npos) << e.what();
    }
  }
}

// A sparse file one byte over the limit (nothing big is written) is refused by its size.
TEST(SceneLoaderFile, FileOverTheSizeLimitIsRefused) {
  const TempDir dir;
  const fs::path big = dir.write("big.json", "{}");
  fs::resize_file(big, kMaxSceneFileBytes + 1);
  try {
    load_scene_file(big);
    FAIL() << "no SceneError";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.file(), big.string());
    EXPECT_EQ(e.json_path(), "(file)");
    EXPECT_NE(e.problem().find(fmt::format("it holds {} bytes, over the limit of {} bytes", kMaxSceneFileBytes + 1,
                                           kMaxSceneFileBytes)),
              std::string::npos)
        << e.what();
  }
  fs::resize_file(big, 2);  // at the limit or below, the file is read: "{}" is the default scene
  EXPECT_EQ(load_scene_file(big).particles.size(), 0u);
}

TEST(SceneLoaderFile, ErrorsNameTheFile) {
  const TempDir dir;
  const fs::path malformed = dir.write("malformed.json", "{\n  \"solver\": {\n    \"substeps\": 4\n  \n");
  const fs::path bad_value = dir.write("bad_value.json", R"({"fluids": [{"box": {"max": [1, 1, 1]}, "spacing": -2}]})");
  try {
    load_scene_file(malformed);
    FAIL() << "no SceneError";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.file(), malformed.string());
    EXPECT_EQ(e.json_path(), "(root)");
    EXPECT_NE(e.problem().find("line 5"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(malformed.string()), std::string::npos);
  }
  try {
    load_scene_file(bad_value);
    FAIL() << "no SceneError";
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()), bad_value.string() + ": fluids[0].spacing: must be > 0, got -2");
  }
}

TEST(SceneLoaderFile, OverridesApplyToFiles) {
  const TempDir dir;
  const fs::path file = dir.write("tank.json", R"({"solver": {"substeps": 2}})");
  const std::vector<std::string> overrides = {"solver.substeps=6", "output.frames=3"};
  const SceneDef s = load_scene_file(file, overrides);
  EXPECT_EQ(s.solver.substeps, 6);
  EXPECT_EQ(s.output.frames, 3);
  EXPECT_EQ(s.name, "tank");
}

// ---- Overrides -------------------------------------------------------------------------------

constexpr const char* kOneFluid = R"({"fluids": [{"box": {"min": [0, 0, 0], "max": [0.5, 0.5, 0.5]}}]})";

TEST(SceneLoaderOverrides, CreateMissingSections) {
  const SceneDef s = load(kOneFluid, {"solver.iterations=8", "domain.max=[2, 2, 2]"});
  EXPECT_EQ(s.solver.iterations, 8);
  EXPECT_EQ(s.solver.substeps, SolverDef{}.substeps);  // the created section has only that key
  EXPECT_EQ(s.domain.max, (Vec3{2.0f, 2.0f, 2.0f}));
}

TEST(SceneLoaderOverrides, ArrayElementsByDotOrBracket) {
  EXPECT_EQ(load(kOneFluid, {"fluids.0.spacing=0.25"}).fluids[0].spacing, 0.25f);
  EXPECT_EQ(load(kOneFluid, {"fluids[0].spacing=0.125"}).fluids[0].spacing, 0.125f);
  EXPECT_EQ(load(kOneFluid, {"fluids[0].box.max[1]=0.25"}).fluids[0].box.max, (Vec3{0.5f, 0.25f, 0.5f}));
  EXPECT_EQ(load(R"({"solver": {"gravity": [0, -9.81, 0]}})", {"solver.gravity.1=-2"}).solver.gravity,
            (Vec3{0.0f, -2.0f, 0.0f}));
}

TEST(SceneLoaderOverrides, ValuesAreJsonOrPlainStrings) {
  const SceneDef s = load("{}", {"name=my_run", "solver.gravity=[0,-1.5,0]", "solver.frame_dt=0.01"});
  EXPECT_EQ(s.name, "my_run");
  EXPECT_EQ(s.solver.gravity, (Vec3{0.0f, -1.5f, 0.0f}));
  EXPECT_EQ(s.solver.frame_dt, 0.01);
  EXPECT_EQ(load("{}", {R"(name="42")"}).name, "42");
  // Only the first '=' separates: the value is "a=b" (no name may hold a '=', so it is refused).
  const auto e = load_error("{}", {"name=a=b"});
  ASSERT_TRUE(e.has_value());
  EXPECT_NE(e->problem().find("contains '=' at character 2"), std::string::npos) << e->problem();
}

TEST(SceneLoaderOverrides, LaterOverridesWinAndReplaceFileValues) {
  const SceneDef s = load(R"({"solver": {"substeps": 3}})", {"solver.substeps=5", "solver.substeps=9"});
  EXPECT_EQ(s.solver.substeps, 9);
}

TEST(SceneLoaderOverrides, TyposAreUnknownKeys) {
  auto e = load_error(kOneFluid, {"solver.iteratons=8"});
  ASSERT_TRUE(e);
  EXPECT_EQ(e->file(), kSource);
  EXPECT_EQ(e->json_path(), "solver.iteratons");
  EXPECT_NE(e->problem().find("did you mean \"iterations\""), std::string::npos) << e->what();

  e = load_error(kOneFluid, {"solvr.iterations=8"});
  ASSERT_TRUE(e);
  EXPECT_EQ(e->json_path(), "solvr");

  e = load_error(kOneFluid, {"fluids.0.spacng=0.1"});
  ASSERT_TRUE(e);
  EXPECT_EQ(e->json_path(), "fluids[0].spacng");
}

TEST(SceneLoaderOverrides, ValuesAreCheckedLikeFileValues) {
  auto e = load_error("{}", {"solver.substeps=0"});
  ASSERT_TRUE(e);
  EXPECT_EQ(e->json_path(), "solver.substeps");
  EXPECT_EQ(e->file(), kSource);

  e = load_error("{}", {"solver.relaxation=nan"});  // not JSON: the string "nan"
  ASSERT_TRUE(e);
  EXPECT_EQ(e->json_path(), "solver.relaxation");
  EXPECT_NE(e->problem().find("got string \"nan\""), std::string::npos) << e->what();

  e = load_error("{}", {"solver.tensile_k=inf"});
  ASSERT_TRUE(e);
  EXPECT_EQ(e->json_path(), "solver.tensile_k");

  e = load_error("{}", {"domain.friction=1e39"});
  ASSERT_TRUE(e);
  EXPECT_EQ(e->json_path(), "domain.friction");
  EXPECT_NE(e->problem().find("not finite"), std::string::npos) << e->what();
}

struct BadOverride {
  const char* label;
  const char* override_text;
  const char* path;     // expected json_path(); the file is "(command line)"
  const char* problem;  // a substring of problem()
};

class BadOverrideTest : public testing::TestWithParam<BadOverride> {};

TEST_P(BadOverrideTest, ThrowsForTheCommandLine) {
  const BadOverride& c = GetParam();
  const auto e = load_error(kOneFluid, {c.override_text});
  ASSERT_TRUE(e.has_value());
  EXPECT_EQ(e->file(), "(command line)") << e->what();
  EXPECT_EQ(e->json_path(), c.path) << e->what();
  EXPECT_NE(e->problem().find(c.problem), std::string::npos) << "problem: " << e->problem();
}

const BadOverride kBadOverrides[] = {
    {"NoEquals", "solver.iterations", "solver.iterations", "expected KEY=VALUE"},
    {"EmptyKey", "=3", "(root)", "empty key"},
    {"EmptySegment", "solver..iterations=3", "solver..iterations", "malformed override"},
    {"TrailingDot", "solver.=3", "solver.", "malformed override"},
    {"UnclosedBracket", "fluids[0.spacing=1", "fluids[0.spacing", "without ']'"},
    {"BadIndex", "fluids[x].spacing=1", "fluids[x].spacing", "not an array index"},
    {"IndexPastEnd", "fluids.1.spacing=0.1", "fluids[1]", "index 1 is past the end of fluids (1 entry"},
    {"IndexPastEndBracket", "fluids[5].spacing=0.1", "fluids[5]", "past the end"},
    {"IndexIntoAbsentArray", "particles[0].mass=2", "particles[0]", "particles is absent"},
    {"IndexIntoAbsentSection", "solver.0=1", "solver[0]", "solver is absent"},
    {"IndexIntoAbsentVec", "solver.gravity[1]=-2", "solver.gravity[1]", "solver.gravity is absent"},
    {"IndexIntoObject", "fluids[0].box.0=1", "fluids[0].box", "is object, not an array"},
    {"KeyIntoArray", "fluids[0].box.min.x=1", "fluids[0].box.min", "is array of 3 elements, not an object"},
    {"VecIndexPastEnd", "fluids[0].box.max[3]=1", "fluids[0].box.max[3]", "past the end"},
};

INSTANTIATE_TEST_SUITE_P(SceneLoaderOverrides, BadOverrideTest, testing::ValuesIn(kBadOverrides),
                         [](const testing::TestParamInfo<BadOverride>& info) { return std::string(info.param.label); });

// ---- Errors ----------------------------------------------------------------------------------

TEST(SceneError, WhatIsFilePathProblem) {
  const SceneError e("a.json", "solver.substeps", "must be >= 1, got 0");
  EXPECT_STREQ(e.what(), "a.json: solver.substeps: must be >= 1, got 0");
  EXPECT_EQ(e.file(), "a.json");
  EXPECT_EQ(e.json_path(), "solver.substeps");
  EXPECT_EQ(e.problem(), "must be >= 1, got 0");
}

// ---- The embedded default scene --------------------------------------------------------------

TEST(DefaultScene, ParsesAndValidates) {
  ASSERT_FALSE(default_scene_json().empty());
  const SceneDef s = load_scene_text(default_scene_json(), "<default scene>");
  EXPECT_FALSE(s.fluids.empty());
  EXPECT_GT(s.fluids[0].spacing, 0.0f);
}

TEST(DefaultScene, MatchesScenesDamBreakJson) {
  const fs::path file = repository_root() / "scenes" / "dam_break.json";
  ASSERT_TRUE(fs::exists(file)) << file;
  EXPECT_EQ(default_scene_json(), read_text(file));
}

// docs/scene-format.md documents the format with one full example; it must stay a valid scene.
TEST(SceneFormatDoc, ExampleIsAValidScene) {
  const fs::path doc = repository_root() / "docs" / "scene-format.md";
  ASSERT_TRUE(fs::exists(doc)) << doc;
  const std::string text = read_text(doc);
  const std::string open = "```json\n";
  const auto begin = text.find(open);
  ASSERT_NE(begin, std::string::npos);
  const auto end = text.find("```", begin + open.size());
  ASSERT_NE(end, std::string::npos);
  const SceneDef s = load_scene_text(std::string_view(text).substr(begin + open.size(), end - begin - open.size()),
                                     doc.string());
  EXPECT_EQ(s.fluids.size(), 1u);
  EXPECT_EQ(s.particles.size(), 2u);
  EXPECT_EQ(s.distance_constraints.size(), 1u);
  EXPECT_EQ(s.colliders.size(), 3u);
  // The example writes the solver defaults (frame_dt rounded to 0.0166667).
  SolverDef defaults;
  EXPECT_NEAR(s.solver.frame_dt, defaults.frame_dt, 1e-6);
  defaults.frame_dt = s.solver.frame_dt;
  expect_same(s.solver, defaults);
}

// docs/scene-format.md's key tables are generated from the readers' key tables (scene keys
// declared once); the page must be the regenerated page. On a difference the regenerated page
// is written to the temp folder, to be copied over docs/scene-format.md.
TEST(SceneFormatDoc, KeyTablesMatchTheReaders) {
  const fs::path doc = repository_root() / "docs" / "scene-format.md";
  ASSERT_TRUE(fs::exists(doc)) << doc;
  const std::string text = read_text(doc);
  const std::string regenerated = detail::regenerate_scene_format(text);
  if (regenerated != text) {
    // Kept after the test (the reader copies it over the doc), named by the process: no other run
    // writes it.
    const fs::path out = fs::temp_directory_path() / ("scene-format." + std::to_string(::getpid()) + ".md");
    std::ofstream(out, std::ios::binary) << regenerated;
    FAIL() << doc << " differs from the key tables of the scene readers; the regenerated page is " << out
           << " (copy it over the doc after checking the difference)";
  }
}

// The generator renders each key from its table: type, unit, the struct's default, the range.
TEST(SceneFormatDoc, RowsRenderTheTableValues) {
  const std::string doc = detail::regenerate_scene_format(read_text(repository_root() / "docs" / "scene-format.md"));
  EXPECT_NE(doc.find("| `substeps` | integer | – | `8` | 1 … 10000 | XPBD substeps per frame |"), std::string::npos);
  EXPECT_NE(doc.find("| `spacing` | float | m | `0.02` | > 0 | particle spacing |"), std::string::npos);
  EXPECT_NE(doc.find("| `gravity` | vec3 | m/s² | `[0, -9.81, 0]` | finite |"), std::string::npos);
  EXPECT_NE(doc.find("| `tensile_dq` | float | – | `0.2` | in (0, 1) |"), std::string::npos);
  EXPECT_NE(doc.find("| `capsule.radius` | float | m | **required** | > 0 | radius |"), std::string::npos);
  EXPECT_NE(doc.find("| `bending` | string | – | `\"dihedral\"` | `\"dihedral\"` or `\"isometric\"` |"),
            std::string::npos);
}

TEST(SceneFormatDoc, MarkersMustNameEveryTableOnce) {
  // A page without markers leaves every table without a place.
  EXPECT_THROW(detail::regenerate_scene_format("# Scene format\n"), std::runtime_error);
  // A marker naming no table, and a marker without its end.
  const std::string page = read_text(repository_root() / "docs" / "scene-format.md");
  EXPECT_THROW(detail::regenerate_scene_format(page + "<!-- scene-keys: nope -->\n<!-- /scene-keys -->\n"),
               std::runtime_error);
  EXPECT_THROW(detail::regenerate_scene_format(page + "<!-- scene-keys: solver -->\n"), std::runtime_error);
}

// The reader registry: every section's key is a root key, read by the section's row.
TEST(SceneSections, EverySectionIsARootKey) {
  std::vector<std::string> keys;
  for (const detail::SceneSection& s : detail::scene_sections()) {
    keys.emplace_back(s.key);
    const std::string empty = s.is_array ? "[]" : "{}";
    EXPECT_NO_THROW(load("{\"" + std::string(s.key) + "\": " + empty + "}")) << s.key;
  }
  // One row per section, and every family the builder registry makes reads its section here.
  std::vector<std::string> sorted = keys;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end()) << "a section has two rows";
  for (const FamilyRow& row : family_rows()) {
    if (std::string_view(row.name) == "motion") continue;  // every scene's: no section
    EXPECT_TRUE(std::binary_search(sorted.begin(), sorted.end(), std::string(row.name)))
        << "the builder row '" << row.name << "' has no reader row";
  }
}

// OBJ meshes are read once, by the loader: the cloth solver and the collider's SDF use the mesh
// kept in the definition, so the simulation builds even after the files are gone.
TEST(SceneLoaderFile, MeshesAreReadOnceAtLoad) {
  const TempDir dir;
  const fs::path meshes = repository_root() / "scenes" / "meshes";
  fs::copy_file(meshes / "cloth_disc.obj", dir.path() / "disc.obj");
  fs::copy_file(meshes / "cube.obj", dir.path() / "cube.obj");
  const fs::path scene_file = dir.write("meshes.json", R"({
    "domain": { "min": [-2, -2, -2], "max": [2, 2, 2] },
    "colliders": [ { "mesh": { "file": "cube.obj", "scale": 0.5 } } ],
    "cloths": [ { "mesh": { "file": "disc.obj", "translate": [0, 1, 0] } } ] })");
  const SceneDef scene = load_scene_file(scene_file);
  ASSERT_EQ(scene.cloths.size(), 1u);
  ASSERT_EQ(scene.colliders.size(), 1u);
  ASSERT_TRUE(scene.cloths[0].loaded_mesh && scene.cloths[0].loaded_topology);
  ASSERT_TRUE(scene.colliders[0].loaded_mesh);
  const ClothMesh disc = read_obj_mesh(meshes / "cloth_disc.obj", *scene.cloths[0].mesh, "cloths[0].mesh");
  EXPECT_EQ(scene.cloths[0].loaded_mesh->positions, disc.positions);
  EXPECT_EQ(scene.colliders[0].loaded_mesh->vertex_count(), 8u);
  EXPECT_EQ(scene.colliders[0].loaded_mesh->positions[0], (Vec3{-0.25f, -0.25f, -0.25f}));

  fs::remove(dir.path() / "disc.obj");
  fs::remove(dir.path() / "cube.obj");
  const Simulation sim(scene);
  EXPECT_EQ(sim.particles().size(), disc.vertex_count());
}

}  // namespace
}  // namespace seiche
