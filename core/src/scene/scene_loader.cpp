// Scene loading in three steps: parse the text (rejecting duplicate keys), apply the command-line
// overrides to the JSON document, then read the document section by section into a SceneDef with
// every value checked. Checks that need more than one value (a fluid box inside the domain, a
// constraint index within "particles") run after all sections are read.
// docs/scene-format.md documents every key; keep it in step with the readers below.
#include "seiche/scene_loader.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <system_error>

#include <fmt/format.h>

#include "families/cloth/cloth_mesh.hpp"
#include "json_reader.hpp"

namespace seiche {

SceneError::SceneError(std::string file, std::string json_path, std::string problem)
    : std::runtime_error(file + ": " + json_path + ": " + problem),
      file_(std::move(file)),
      json_path_(std::move(json_path)),
      problem_(std::move(problem)) {}

namespace {

using detail::Json;
using detail::JsonReader;
using detail::Range;
using detail::element_path;
using detail::fail;
using detail::member_path;

constexpr double kMaxStepsPerFrame = 10000;      // substeps and iterations: more is a typo
constexpr double kMaxParticlesPerFluid = 50e6;   // a larger block is a typo in spacing or box
constexpr double kMaxParticles = 50e6;           // all blocks together (32-bit neighbor offsets)
// At 1 spacing the lattice neighbors sit exactly at r = h and the constraint has no gradient;
// past 4 a particle has some 270 neighbors, far past any useful accuracy.
constexpr double kMinKernelRadius = 1.5, kMaxKernelRadius = 4.0;
constexpr double kMinSubstep = 1e-6;             // s: below this, float time steps underflow
constexpr double kMinMass = 1e-12;               // kg: 1 / mass must be a finite float
constexpr double kLatticeTolerance = 1e-4;
constexpr double kMaxSheetResolution = 4096;     // vertices per side: 16 M vertices in all       // of a spacing, absorbs rounding of box edges
const std::string kCommandLine = "(command line)";

std::string format_vec(const Vec3& v) { return fmt::format("[{}, {}, {}]", v[0], v[1], v[2]); }
constexpr char kAxis[3] = {'x', 'y', 'z'};

// ---- Step 1: parse ---------------------------------------------------------------------------

// nlohmann keeps the last of two equal keys without a word; a scene with two "fluids" arrays is a
// mistake, so a parser callback tracks the path and the keys seen in each open object.
class DuplicateKeyCheck {
 public:
  explicit DuplicateKeyCheck(const std::string& file) : file_(&file) {}

  bool operator()(int /*depth*/, Json::parse_event_t event, Json& parsed) {
    switch (event) {
      case Json::parse_event_t::object_start: open_.push_back({false, 0, {}, {}}); break;
      case Json::parse_event_t::array_start: open_.push_back({true, 0, {}, {}}); break;
      case Json::parse_event_t::key: {
        Frame& top = open_.back();
        top.key = parsed.get<std::string>();
        if (std::find(top.seen.begin(), top.seen.end(), top.key) != top.seen.end())
          fail(*file_, path(), "duplicate key; a key may appear only once per object");
        top.seen.push_back(top.key);
        break;
      }
      case Json::parse_event_t::object_end:
      case Json::parse_event_t::array_end:
        open_.pop_back();
        next_element();
        break;
      case Json::parse_event_t::value: next_element(); break;
    }
    return true;
  }

 private:
  struct Frame {
    bool is_array;
    std::size_t index;           // arrays: the element being parsed
    std::string key;             // objects: the member being parsed
    std::vector<std::string> seen;
  };

  void next_element() {
    if (!open_.empty() && open_.back().is_array) ++open_.back().index;
  }

  std::string path() const {
    std::string p;
    for (const Frame& f : open_) p = f.is_array ? element_path(p, f.index) : member_path(p, f.key);
    return p;
  }

  const std::string* file_;
  std::vector<Frame> open_;
};

// "line 3, column 14" of the 0-based byte offset `pos` (clamped to the end of the text).
std::string line_and_column(std::string_view text, std::size_t pos) {
  pos = std::min(pos, text.size());
  const auto before = text.substr(0, pos);
  const std::size_t line = 1 + static_cast<std::size_t>(std::count(before.begin(), before.end(), '\n'));
  const std::size_t line_start = before.rfind('\n');
  const std::size_t column = line_start == std::string_view::npos ? pos + 1 : pos - line_start;
  return fmt::format("line {}, column {}", line, column);
}

Json parse_json(std::string_view text, const std::string& file) {
  try {
    DuplicateKeyCheck check(file);
    return Json::parse(text.begin(), text.end(), std::ref(check));
  } catch (const Json::parse_error& e) {
    // e.what() is "[json.exception.parse_error.101] parse error at line 4, column 0: <detail>".
    // nlohmann counts a newline as the start of the next line, so "tru\n" would be reported on
    // the line below the typo; recomputing from the byte offset names the line of the last read
    // character (e.byte is 1-based).
    const std::string message = e.what();
    const auto at = message.find(": ", message.find("parse error"));
    const std::string detail = at == std::string::npos ? message : message.substr(at + 2);
    fail(file, "", fmt::format("malformed JSON at {}: {}", line_and_column(text, e.byte > 0 ? e.byte - 1 : 0), detail));
  } catch (const Json::exception& e) {
    // out_of_range.406 "number overflow parsing '1e400'" has no offset: find the literal.
    std::string message = e.what();
    const auto bracket = message.find("] ");
    if (bracket != std::string::npos) message = message.substr(bracket + 2);
    const auto open = message.find('\'');
    const auto close = message.rfind('\'');
    const auto pos = open < close ? text.find(std::string_view(message).substr(open + 1, close - open - 1))
                                  : std::string_view::npos;
    fail(file, "",
         pos == std::string_view::npos ? fmt::format("malformed JSON: {}", message)
                                       : fmt::format("malformed JSON at {}: {}", line_and_column(text, pos), message));
  }
}

// ---- Step 2: overrides -----------------------------------------------------------------------

struct PathStep {
  std::string key;                   // an object member, or
  std::optional<std::size_t> index;  // an array element
};

// "fluids[0].box.min", "fluids.0.box.min" -> fluids, [0], box, min. A segment of digits after a
// dot is an index: no key of the scene format is a number.
std::vector<PathStep> parse_override_key(const std::string& key, const std::string& override_text) {
  const auto malformed = [&](std::string_view why) {
    fail(kCommandLine, key, fmt::format("malformed override \"{}\": {}", override_text, why));
  };
  const auto parse_index = [&](std::string_view digits) {
    std::size_t index = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), index);
    if (digits.empty() || ec != std::errc() || end != digits.data() + digits.size())
      malformed(fmt::format("\"{}\" is not an array index", digits));
    return index;
  };

  std::vector<PathStep> steps;
  std::size_t i = 0;
  while (i < key.size()) {
    if (key[i] == '[') {
      if (steps.empty()) malformed("the key must start with a name");
      const auto close = key.find(']', i);
      if (close == std::string::npos) malformed("'[' without ']'");
      steps.push_back({{}, parse_index(std::string_view(key).substr(i + 1, close - i - 1))});
      i = close + 1;
    } else {
      const auto end = std::min(key.find_first_of(".[", i), key.size());
      const std::string_view name = std::string_view(key).substr(i, end - i);
      if (name.empty()) malformed("empty name in the key");
      const bool digits = std::all_of(name.begin(), name.end(), [](char c) { return c >= '0' && c <= '9'; });
      if (digits && steps.empty()) malformed("the key must start with a name");
      steps.push_back(digits ? PathStep{{}, parse_index(name)} : PathStep{std::string(name), {}});
      i = end;
    }
    if (i < key.size() && key[i] == '.') {
      ++i;
      if (i == key.size() || key[i] == '[' || key[i] == '.') malformed("a '.' must be followed by a name or index");
    } else if (i < key.size() && key[i] != '[') {
      malformed(fmt::format("unexpected '{}'", key[i]));
    }
  }
  if (steps.empty()) malformed("empty key");
  return steps;
}

// Sets one value, creating missing objects on the way; an array index must exist already. The
// value is then read and checked like any other, so a mistyped key fails as an unknown key.
void apply_override(Json& root, const std::string& override_text) {
  const auto eq = override_text.find('=');
  if (eq == std::string::npos)
    fail(kCommandLine, override_text, fmt::format("malformed override \"{}\": expected KEY=VALUE", override_text));
  const std::string key = override_text.substr(0, eq);
  const std::string value_text = override_text.substr(eq + 1);
  const std::vector<PathStep> steps = parse_override_key(key, override_text);

  Json value = Json::parse(value_text, nullptr, /*allow_exceptions=*/false);
  if (value.is_discarded()) value = value_text;  // not JSON: a plain string

  Json* node = &root;
  std::string path;
  for (std::size_t s = 0; s < steps.size(); ++s) {
    const PathStep& step = steps[s];
    const bool last = s + 1 == steps.size();
    if (step.index) {
      const std::size_t index = *step.index;
      if (!node->is_array())
        fail(kCommandLine, path, fmt::format("is {}, not an array; cannot set element {} (override \"{}\")",
                                             detail::describe_value(*node), index, override_text));
      if (index >= node->size())
        fail(kCommandLine, element_path(path, index),
             fmt::format("index {} is past the end of {} ({} {}; override \"{}\")", index,
                         detail::display_path(path), node->size(), node->size() == 1 ? "entry" : "entries",
                         override_text));
      node = &(*node)[index];
      path = element_path(path, index);
    } else {
      if (!node->is_object())
        fail(kCommandLine, path, fmt::format("is {}, not an object; cannot set \"{}\" (override \"{}\")",
                                             detail::describe_value(*node), step.key, override_text));
      if (!node->contains(step.key)) {
        if (!last && steps[s + 1].index)
          fail(kCommandLine, element_path(member_path(path, step.key), *steps[s + 1].index),
               fmt::format("index {} is past the end: {} is absent (override \"{}\")", *steps[s + 1].index,
                           member_path(path, step.key), override_text));
        (*node)[step.key] = Json::object();
      }
      node = &(*node)[step.key];
      path = member_path(path, step.key);
    }
    if (last) *node = value;
  }
}

// ---- Step 3: read the sections ---------------------------------------------------------------

SolverDef read_solver(JsonReader r) {
  SolverDef s;
  r.read("frame_dt", s.frame_dt, Range::above(0));
  r.read("substeps", s.substeps, Range::closed(1, kMaxStepsPerFrame));
  r.read("iterations", s.iterations, Range::closed(1, kMaxStepsPerFrame));
  r.read("density_tolerance", s.density_tolerance, Range::half_open(0, 1));
  r.read("max_iterations", s.max_iterations, Range::closed(1, kMaxStepsPerFrame));
  r.read("gravity", s.gravity);
  r.read("relaxation", s.relaxation, Range::at_least(0));
  r.read("damping", s.damping, Range::at_least(0));
  r.read("tensile_k", s.tensile_k, Range::at_least(0));
  r.read("tensile_n", s.tensile_n, Range::closed(1, 8));
  r.read("tensile_dq", s.tensile_dq, Range::open(0, 1));
  r.finish();
  if (s.frame_dt / s.substeps < kMinSubstep)
    r.fail_at("frame_dt", fmt::format("gives substeps of {} s (frame_dt / substeps); the smallest is {} s",
                                      s.frame_dt / s.substeps, kMinSubstep));
  return s;
}

DomainDef read_domain(JsonReader r) {
  DomainDef d;
  r.read("min", d.min);
  r.read("max", d.max);
  r.read("friction", d.friction, Range::at_least(0));
  r.finish();
  for (int a = 0; a < 3; ++a) {
    if (!(d.min[a] < d.max[a]))
      r.fail_here(fmt::format("min must be < max on every axis, but along {} min = {} and max = {}", kAxis[a],
                              d.min[a], d.max[a]));
  }
  return d;
}

OutputDef read_output(JsonReader r) {
  OutputDef o;
  r.read("frames", o.frames, Range::at_least(1));
  r.read("checkpoint_every", o.checkpoint_every, Range::at_least(1));
  r.read("particles", o.particles);
  std::vector<std::string> grids{"surface", "density"};
  r.read_string_set("vdb", grids, {"surface", "density", "points", "v"});
  auto listed = [&](const char* g) { return std::find(grids.begin(), grids.end(), g) != grids.end(); };
  o.vdb_surface = listed("surface");
  o.vdb_density = listed("density");
  o.vdb_points = listed("points");
  o.vdb_velocity = listed("v");
  r.read("mesh", o.mesh);
  r.read("voxel_size", o.voxel_size, Range::at_least(0));
  r.read("anisotropic", o.anisotropic);
  r.read("half_float", o.half_float);
  r.read_choice("compression", o.compression, {"blosc", "zip", "none"});
  r.finish();
  return o;
}

BoxDef read_box(JsonReader r) {
  BoxDef b;
  r.read("min", b.min);
  r.read("max", b.max);
  r.finish();
  for (int a = 0; a < 3; ++a) {
    if (b.min[a] > b.max[a])
      r.fail_here(fmt::format("min > max along {} ({} > {})", kAxis[a], b.min[a], b.max[a]));
  }
  return b;
}

FluidDef read_fluid(JsonReader r) {
  FluidDef f;
  r.read("spacing", f.spacing, Range::above(0));
  r.read("kernel_radius", f.kernel_radius, Range::closed(kMinKernelRadius, kMaxKernelRadius));
  r.read("rest_density", f.rest_density, Range::above(0));
  r.read("viscosity", f.viscosity, Range::closed(0, 1));
  r.read("vorticity", f.vorticity, Range::at_least(0));
  r.read("velocity", f.velocity);
  f.box = read_box(r.object("box"));  // required keys last: see JsonReader::require
  r.finish();
  return f;
}

ParticleDef read_particle(JsonReader r) {
  ParticleDef p;
  r.read("v", p.v);
  r.read("mass", p.mass, Range::at_least(0));
  if (p.mass != 0.0f && p.mass < kMinMass)
    r.fail_at("mass", fmt::format("must be 0 (pinned) or at least {} kg, got {}", kMinMass, p.mass));
  r.require("x");
  r.read("x", p.x);
  r.finish();
  return p;
}

DistanceConstraintDef read_distance_constraint(JsonReader r) {
  DistanceConstraintDef c;
  r.read("rest_length", c.rest_length, Range::at_least(0));  // absent: the initial distance (-1)
  r.read("compliance", c.compliance, Range::at_least(0));
  r.require("i");
  r.require("j");
  r.read("i", c.i);  // the range is checked against "particles" once all sections are read
  r.read("j", c.j);
  r.finish();
  return c;
}

ClothMeshDef read_mesh_placement(JsonReader r) {
  ClothMeshDef m;
  r.read("translate", m.translate);
  r.read("scale", m.scale, Range::above(0));
  r.require("file");
  r.read("file", m.file);
  r.finish();
  if (m.file.empty()) r.fail_at("file", "must not be empty");
  return m;
}

ColliderDef read_collider(JsonReader r) {
  ColliderDef c;
  r.read("friction", c.friction, Range::at_least(0));
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
    plane->read("point", c.point);
    plane->read("normal", c.normal);
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
    sphere->read("center", c.center);
    sphere->require("radius");
    sphere->read("radius", c.radius, Range::above(0));
    sphere->finish();
  } else if (capsule) {
    c.shape = ColliderDef::Shape::Capsule;
    capsule->require("a");
    capsule->require("b");
    capsule->require("radius");
    capsule->read("a", c.end_a);
    capsule->read("b", c.end_b);
    capsule->read("radius", c.radius, Range::above(0));
    capsule->finish();
  } else {
    c.shape = ColliderDef::Shape::Mesh;
    mesh->read("voxel_size", c.voxel_size, Range::at_least(0));
    c.mesh = read_mesh_placement(*mesh);
  }
  return c;
}

SheetDef read_sheet(JsonReader r) {
  SheetDef s;
  r.read("size", s.size, Range::above(0));
  r.read("resolution", s.resolution, Range::closed(2, kMaxSheetResolution));
  r.read("plane", s.plane);
  r.require("origin");
  r.read("origin", s.origin);
  r.finish();
  const std::string& p = s.plane;
  if (p.size() != 2 || p[0] == p[1] || std::string("xyz").find(p[0]) == std::string::npos ||
      std::string("xyz").find(p[1]) == std::string::npos)
    r.fail_at("plane", fmt::format("\"{}\" is not two different axes of x, y, z (e.g. \"xz\", \"xy\")", p));
  return s;
}

ClothDef read_cloth(JsonReader r, std::size_t index) {
  ClothDef c;
  c.name = fmt::format("cloth{}", index);
  r.read("name", c.name);
  if (c.name.empty()) r.fail_at("name", "must not be empty");
  r.read("mass_per_area", c.mass_per_area, Range::above(0));
  r.read("thickness", c.thickness, Range::above(0));
  r.read("stretch_compliance", c.stretch_compliance, Range::at_least(0));
  r.read("bend_compliance", c.bend_compliance, Range::above(0));
  r.read_choice("bending", c.bending, {"dihedral", "isometric"});
  r.read("tethers", c.tethers);
  int forests = -1;  // absent: the pin-dependent default (ClothDef::stretch_forests)
  r.read("stretch_forests", forests, Range::closed(0, 3));
  if (forests >= 0) c.stretch_forests = forests;
  r.read("self_collision", c.self_collision);
  r.read("friction", c.friction, Range::at_least(0));
  r.read("pins", c.pins, Range::at_least(0));
  if (auto box = r.optional_object("pin_box")) c.pin_box = read_box(*box);
  r.read("velocity", c.velocity);
  auto sheet = r.optional_object("sheet");
  auto mesh = r.optional_object("mesh");
  r.finish();
  if (sheet.has_value() == mesh.has_value())
    r.fail_here(sheet ? "has both \"sheet\" and \"mesh\"; a cloth is one of them"
                      : "needs a shape: \"sheet\" (generated) or \"mesh\" (an OBJ file)");
  if (sheet) c.sheet = read_sheet(*sheet);
  if (mesh) c.mesh = read_mesh_placement(*mesh);
  return c;
}

// ---- Checks across sections ------------------------------------------------------------------

std::string resolve_mesh_path(const std::string& file, const std::string& base_dir) {
  const std::filesystem::path p(file);
  if (p.is_absolute() || base_dir.empty()) return file;
  return (std::filesystem::path(base_dir) / p).lexically_normal().string();
}

// A mesh file that is not there is the scene's error (it names the file); what is wrong inside
// an OBJ is reported by the OBJ reader, naming the OBJ.
void check_mesh_file(const std::string& mesh_file, const std::string& file, const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(mesh_file, ec))
    fail(file, path, fmt::format("cannot open the mesh {}: {}", mesh_file,
                                 std::filesystem::exists(mesh_file, ec) ? "not a regular file" : "no such file"));
}

bool inside(const Vec3& p, const DomainDef& d) {
  for (int a = 0; a < 3; ++a)
    if (p[a] < d.min[a] || p[a] > d.max[a]) return false;
  return true;
}

void check_fluids(const SceneDef& scene, const std::string& file) {
  double total = 0;
  const std::string domain = fmt::format("{}..{}", format_vec(scene.domain.min), format_vec(scene.domain.max));
  for (std::size_t k = 0; k < scene.fluids.size(); ++k) {
    const FluidDef& f = scene.fluids[k];
    const std::string path = element_path("fluids", k);
    const std::string box_path = path + ".box";

    // Lattice sites sit at (i + 0.5) * spacing from box.min, floor(extent / spacing) per axis.
    double count = 1;
    for (int a = 0; a < 3; ++a) {
      const double extent = double(f.box.max[a]) - double(f.box.min[a]);
      const double n = std::floor(extent / f.spacing + kLatticeTolerance);
      if (n < 1)
        fail(file, box_path, fmt::format("holds no particles: along {} it is {} m thick, less than one spacing ({} m)",
                                         kAxis[a], static_cast<float>(extent), f.spacing));
      count *= n;
    }
    if (count > kMaxParticlesPerFluid)
      fail(file, box_path, fmt::format("would hold {:.0f} particles at spacing {} m; the limit is {:.0f} per block",
                                       count, f.spacing, kMaxParticlesPerFluid));
    total += count;
    if (total > kMaxParticles)
      fail(file, box_path, fmt::format("brings the fluid to {:.0f} particles; the limit is {:.0f} in all", total,
                                       kMaxParticles));
    if (!inside(f.box.min, scene.domain) || !inside(f.box.max, scene.domain))
      fail(file, box_path, fmt::format("{}..{} reaches outside the domain {}", format_vec(f.box.min),
                                       format_vec(f.box.max), domain));

    // One material per scene: the solver keeps a single kernel radius and rest density.
    const FluidDef& first = scene.fluids.front();
    const auto same = [&](const char* key, float mine, float theirs) {
      if (mine != theirs)
        fail(file, path + "." + key,
             fmt::format("{} differs from fluids[0] ({}); all fluids of a scene share one material", mine, theirs));
    };
    same("spacing", f.spacing, first.spacing);
    same("kernel_radius", f.kernel_radius, first.kernel_radius);
    same("rest_density", f.rest_density, first.rest_density);
    same("viscosity", f.viscosity, first.viscosity);
    same("vorticity", f.vorticity, first.vorticity);
  }
}

void check_particles(const SceneDef& scene, const std::string& file) {
  for (std::size_t k = 0; k < scene.particles.size(); ++k) {
    const Vec3& x = scene.particles[k].x;
    if (!inside(x, scene.domain))
      fail(file, element_path("particles", k) + ".x",
           fmt::format("{} is outside the domain {}..{}", format_vec(x), format_vec(scene.domain.min),
                       format_vec(scene.domain.max)));
  }
}

void check_distance_constraints(const SceneDef& scene, const std::string& file) {
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

// Every cloth's mesh is built here once, so that a broken OBJ or a pin past the last vertex is
// reported before anything runs; mesh paths become absolute (a resumed bake may run elsewhere).
void check_cloths(SceneDef& scene, const std::string& file) {
  // Taken output stems: the particle files, and the fluid's .vdb / .obj (named after the scene).
  std::vector<std::string> names{"particles"};
  if (!scene.fluids.empty()) names.push_back(scene.name);
  for (std::size_t k = 0; k < scene.cloths.size(); ++k) {
    ClothDef& c = scene.cloths[k];
    const std::string path = element_path("cloths", k);
    if (std::find(names.begin(), names.end(), c.name) != names.end())
      fail(file, path + ".name",
           fmt::format("\"{}\" is taken (by the particle files, the fluid's files named after the scene, or another "
                       "cloth); "
                       "output files are named after it",
                       c.name));
    names.push_back(c.name);
    ClothMesh mesh;
    if (c.mesh) {
      c.mesh->file = resolve_mesh_path(c.mesh->file, scene.base_dir);
      check_mesh_file(c.mesh->file, file, path + ".mesh.file");
      mesh = read_obj_mesh(c.mesh->file, *c.mesh, path + ".mesh");
    } else {
      mesh = make_sheet(*c.sheet, file, path + ".sheet");
    }
    build_topology(mesh, c.mesh ? c.mesh->file : file, path + (c.mesh ? ".mesh.file" : ".sheet"));
    const auto n = static_cast<long long>(mesh.vertex_count());
    for (std::size_t p = 0; p < c.pins.size(); ++p) {
      if (c.pins[p] >= n)
        fail(file, element_path(path + ".pins", p),
             fmt::format("vertex {} is out of range: the cloth has {} vertices (0..{})", c.pins[p], n, n - 1));
    }
    for (const Vec3& x : mesh.positions) {
      if (!inside(x, scene.domain))
        fail(file, path + (c.mesh ? ".mesh" : ".sheet"),
             fmt::format("vertex at {} is outside the domain {}..{}", format_vec(x), format_vec(scene.domain.min),
                         format_vec(scene.domain.max)));
    }
  }
  for (std::size_t k = 0; k < scene.colliders.size(); ++k) {
    ColliderDef& c = scene.colliders[k];
    if (c.shape != ColliderDef::Shape::Mesh) continue;
    c.mesh.file = resolve_mesh_path(c.mesh.file, scene.base_dir);
    check_mesh_file(c.mesh.file, file, element_path("colliders", k) + ".mesh.file");
    const ClothMesh mesh = read_obj_mesh(c.mesh.file, c.mesh, element_path("colliders", k) + ".mesh");
    (void)mesh;  // closedness is checked when the field is built (Simulation), with the same message
  }
}

SceneDef read_scene(const Json& document, const std::string& file, const std::string& default_name,
                    const std::filesystem::path& base_dir) {
  JsonReader root(document, "", file);
  SceneDef scene;
  scene.name = default_name;
  scene.base_dir = base_dir.string();
  root.read("name", scene.name);
  if (scene.name.empty()) root.fail_at("name", "must not be empty");
  if (auto r = root.optional_object("solver")) scene.solver = read_solver(*r);
  if (auto r = root.optional_object("domain")) scene.domain = read_domain(*r);
  if (auto r = root.optional_object("output")) scene.output = read_output(*r);
  for (const JsonReader& r : root.objects("fluids")) scene.fluids.push_back(read_fluid(r));
  for (const JsonReader& r : root.objects("particles")) scene.particles.push_back(read_particle(r));
  for (const JsonReader& r : root.objects("distance_constraints"))
    scene.distance_constraints.push_back(read_distance_constraint(r));
  for (const JsonReader& r : root.objects("colliders")) scene.colliders.push_back(read_collider(r));
  for (const JsonReader& r : root.objects("cloths")) scene.cloths.push_back(read_cloth(r, scene.cloths.size()));
  root.finish();

  check_fluids(scene, file);
  check_particles(scene, file);
  check_distance_constraints(scene, file);
  check_cloths(scene, file);
  return scene;
}

SceneDef load_scene(std::string_view text, const std::string& file, std::span<const std::string> overrides,
                    const std::string& default_name, const std::filesystem::path& base_dir) {
  Json document = parse_json(text, file);
  if (!document.is_object())
    fail(file, "", "expected a JSON object at the top, got " + detail::describe_value(document));
  for (const std::string& o : overrides) apply_override(document, o);
  return read_scene(document, file, default_name, base_dir);
}

std::string read_file(const std::filesystem::path& path, const std::string& file) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) fail(file, "(file)", "cannot open: it is a directory");
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) fail(file, "(file)", "cannot open: " + std::generic_category().message(errno));
  std::string text;
  char buffer[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, f.get())) > 0) text.append(buffer, n);
  if (std::ferror(f.get())) fail(file, "(file)", "cannot read: " + std::generic_category().message(errno));
  return text;
}

}  // namespace

SceneDef load_scene_text(std::string_view json_text, std::string_view source,
                         std::span<const std::string> overrides, const std::filesystem::path& base_dir) {
  return load_scene(json_text, std::string(source), overrides, SceneDef{}.name, base_dir);
}

SceneDef load_scene_file(const std::filesystem::path& file, std::span<const std::string> overrides) {
  const std::string source = file.string();
  std::error_code ec;
  const std::filesystem::path dir = std::filesystem::absolute(file, ec).parent_path();
  return load_scene(read_file(file, source), source, overrides, file.stem().string(), dir);
}

}  // namespace seiche
