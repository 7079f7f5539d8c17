// Core layer: the store, scenes run through the Simulation, the runner's files and report.
#include <gtest/gtest.h>

#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "loop/iteration_record.hpp"
#include "run/background_writer.hpp"
#include "run/progress.hpp"
#include "seiche/output_files.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/runner.hpp"
#include "seiche/scene_loader.hpp"
#include "seiche/simulation.hpp"
#include "seiche/vtk_particles.hpp"
#include "test_temp_dir.hpp"

using namespace seiche;
namespace fs = std::filesystem;

namespace {

fs::path scene_path(const char* name) { return fs::path(SEICHE_SCENES_DIR) / name; }

fs::path fresh_dir(const std::string& name) {
  const fs::path d = testing_support::temp_path("seiche_core_tests_" + name);
  fs::remove_all(d);
  return d;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool inside_domain(const Simulation& sim) {
  const auto& s = sim.particles();
  const auto& d = sim.scene().domain;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (!(s.x[i] >= d.min[0] && s.x[i] <= d.max[0] && s.y[i] >= d.min[1] && s.y[i] <= d.max[1] &&
          s.z[i] >= d.min[2] && s.z[i] <= d.max[2]))
      return false;
  }
  return true;
}

}  // namespace

// ---- Store ------------------------------------------------------------------------------------

TEST(ParticleStore, ColumnsAreAlignedPaddedAndOptional) {
  ParticleStore s;
  s.resize(37);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(s.x.data()) % 64, 0u);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(s.id.data()) % 64, 0u);
  EXPECT_EQ(s.vz.storage().size() % 16, 0u);
  EXPECT_GE(s.vz.storage().size(), 37u);
  EXPECT_FALSE(s.density.allocated());
  EXPECT_FALSE(s.omega_x.allocated());
  s.enable_fluid_columns();
  EXPECT_TRUE(s.density.allocated());
  EXPECT_EQ(s.density.size(), 37u);
}

TEST(ParticleStore, ReorderMovesEveryStateColumnByOnePermutation) {
  ParticleStore s;
  s.resize(5);
  for (int i = 0; i < 5; ++i) {
    s.x[i] = float(i), s.vy[i] = 10.0f * i, s.w[i] = 100.0f * i;
    s.id[i] = i, s.phase[i] = std::uint32_t(7 * i);
  }
  const std::vector<std::uint32_t> order = {3, 0, 4, 1, 2};
  s.reorder(order);
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(s.id[k], int(order[k]));
    EXPECT_EQ(s.x[k], float(order[k]));
    EXPECT_EQ(s.vy[k], 10.0f * order[k]);
    EXPECT_EQ(s.w[k], 100.0f * order[k]);
    EXPECT_EQ(s.phase[k], 7u * order[k]);
  }
  const auto inv = inverse_permutation(order);
  for (std::uint32_t k = 0; k < 5; ++k) EXPECT_EQ(inv[order[k]], k);
}

TEST(ParticleStore, TableDeclaresEveryColumnOnceWithItsKind) {
  ParticleStore s;
  std::vector<std::string> state, constant, scratch;
  for (const StoreColumn& c : s.columns())
    (c.kind == ColumnKind::State ? state : c.kind == ColumnKind::Constant ? constant : scratch).push_back(c.name);
  EXPECT_EQ(state, (std::vector<std::string>{"x", "y", "z", "px", "py", "pz", "vx", "vy", "vz", "w", "phase", "id"}));
  EXPECT_EQ(constant, std::vector<std::string>{"radius"});
  EXPECT_EQ(scratch, (std::vector<std::string>{"density", "lambda", "omega_x", "omega_y", "omega_z"}));
  ASSERT_NE(s.find("phase"), nullptr);
  EXPECT_EQ(s.find("phase")->type(), ColumnType::U32);
  EXPECT_EQ(s.find("id")->type(), ColumnType::I32);
  EXPECT_EQ(s.find("nothing"), nullptr);
}

TEST(ParticleStore, FamilyColumnsResizeReorderAndCopyWithTheTable) {
  ParticleStore s;
  s.resize(3);
  FloatColumn& rest = s.add_column<float>("shape.rest_x", ColumnKind::Constant);
  AlignedColumn<std::int32_t>& frame = s.add_column<std::int32_t>("rod.frame", ColumnKind::State);
  FloatColumn& work = s.add_column<float>("shape.work", ColumnKind::Scratch);
  EXPECT_THROW(s.add_column<float>("x", ColumnKind::State), std::invalid_argument);
  EXPECT_EQ(rest.size(), 3u);
  s.resize(5);
  EXPECT_EQ(rest.size(), 5u);
  EXPECT_EQ(frame.size(), 5u);
  EXPECT_EQ(work.size(), 5u);
  for (int i = 0; i < 5; ++i) s.x[i] = float(i), rest[i] = 10.0f * i, frame[i] = 100 * i, work[i] = float(-i);
  const std::vector<std::uint32_t> order = {3, 0, 4, 1, 2};
  s.reorder(order);
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(s.x[k], float(order[k]));
    EXPECT_EQ(rest[k], 10.0f * order[k]);   // Constant: moves with its particle
    EXPECT_EQ(frame[k], 100 * int(order[k]));  // State: too
    EXPECT_EQ(work[k], float(-k));          // Scratch: left alone
  }
  // A copy carries the whole table, its named members on its own columns.
  ParticleStore copy = s;
  copy.x[0] = -1.0f;
  EXPECT_EQ(s.x[0], float(order[0]));
  ASSERT_NE(copy.find("shape.rest_x"), nullptr);
  EXPECT_EQ(std::get<FloatColumn>(copy.find("shape.rest_x")->data)[2], 10.0f * order[2]);
  ParticleStore assigned;
  assigned = copy;
  EXPECT_EQ(assigned.x[0], -1.0f);
  EXPECT_EQ(assigned.size(), 5u);
  EXPECT_NE(assigned.x.data(), copy.x.data());
  EXPECT_GT(s.bytes(), ParticleStore().bytes());
}

// ---- Scenes through the simulation ---------------------------------------------------------------

TEST(IterationRecord, PacksOrUnpacksOnlyWhenTheOtherLayoutWasWrittenLast) {
  ParticleStore s;
  s.resize(6);
  for (std::size_t i = 0; i < 6; ++i) s.px[i] = float(i), s.py[i] = 10.0f + float(i), s.pz[i] = -float(i), s.w[i] = 0.5f;
  const kernels::ParticleView p = particle_view(s);
  IterationRecord record;
  record.reset({2, 4});
  EXPECT_EQ(record.current(), Layout::Columns);
  record.prepare(Layout::Packed, p);  // packs
  const kernels::Float4* r = record.packed().by_index();
  EXPECT_EQ(r[3].x, 3.0f);
  EXPECT_EQ(r[3].y, 13.0f);
  EXPECT_EQ(r[3].z, -3.0f);
  EXPECT_EQ(r[3].w, 0.5f);
  record.packed().by_index()[3].x = 7.0f;  // a packed pass writes a record
  record.prepare(Layout::Packed, p);       // the next packed pass: no pack over it
  EXPECT_EQ(r[3].x, 7.0f);
  record.prepare(Layout::Columns, p);  // unpacks the range, nothing outside it
  EXPECT_EQ(s.px[3], 7.0f);
  EXPECT_EQ(s.px[5], 5.0f);
  EXPECT_EQ(record.current(), Layout::Columns);
  s.px[3] = 8.0f;  // a column pass writes
  record.prepare(Layout::Columns, p);  // no unpack over it
  EXPECT_EQ(s.px[3], 8.0f);
  record.prepare(Layout::Packed, p);  // packs the new value
  EXPECT_EQ(r[3].x, 8.0f);
  record.reset({0, 5});  // after a reorder: the columns are the positions again
  EXPECT_EQ(record.current(), Layout::Columns);
  EXPECT_EQ(record.range().size(), 6u);
}

TEST(Simulation, SeedWorkedExampleAfterOneFrame) {
  Simulation sim(load_scene_file(scene_path("seed_example.json")));
  sim.step_frame();
  const auto& s = sim.particles();
  ASSERT_EQ(s.size(), 2u);
  ASSERT_EQ(s.id[0], 0);
  EXPECT_NEAR(s.x[0], 14.0 / 3, 1e-5);
  EXPECT_NEAR(s.y[0], 19.0 / 6, 1e-5);
  EXPECT_NEAR(s.z[0], 7.0 / 3, 1e-5);
  EXPECT_NEAR(s.x[1], 8.0 / 3, 1e-5);
  EXPECT_NEAR(s.y[1], 25.0 / 6, 1e-5);
  EXPECT_NEAR(s.z[1], 13.0 / 3, 1e-5);
  EXPECT_EQ(sim.pipeline(), (std::vector<std::string>{"predict", "distance", "collisions", "update"}));
}

TEST(Simulation, FamiliesWriteTheirParticlesCollisionRadius) {
  // One raw particle, a fluid block of spacing 0.04, two cloths 6 mm and 20 mm thick.
  const Simulation sim(load_scene_text(R"({
    "domain": { "min": [0, 0, 0], "max": [1, 1, 1] },
    "particles": [ { "x": [0.9, 0.9, 0.9] } ],
    "fluids": [ { "box": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.2] }, "spacing": 0.04 } ],
    "cloths": [ { "sheet": { "origin": [0.3, 0.5, 0.3], "size": [0.2, 0.2], "resolution": [3, 3] }, "thickness": 0.006 },
                { "sheet": { "origin": [0.3, 0.8, 0.3], "size": [0.2, 0.2], "resolution": [4, 4] }, "thickness": 0.02 } ] })",
                                       "radii.json"));
  const ParticleStore& s = sim.particles();
  ASSERT_EQ(s.size(), 1u + 125u + 9u + 16u);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const int id = s.id[i];
    const float expected = id == 0 ? 0.0f : id <= 125 ? 0.02f : id <= 134 ? 0.003f : 0.01f;
    EXPECT_EQ(s.radius[i], expected) << "particle " << id;
  }
}

TEST(Simulation, ComplianceIsInPhysicalUnits) {
  // A 1 kg particle hanging from a pinned one on a constraint of compliance alpha: XPBD
  // oscillates around the static stretch m g alpha, whatever the substep count.
  for (int substeps : {4, 16}) {
    SceneDef scene;
    scene.domain.min = {-2, -2, -2};
    scene.domain.max = {2, 2, 2};
    scene.solver.substeps = substeps;
    scene.solver.iterations = 1;
    scene.particles = {{{0, 1, 0}, {0, 0, 0}, 0.0f}, {{0, 0, 0}, {0, 0, 0}, 1.0f}};
    const float alpha = 1e-3f;
    scene.distance_constraints = {{0, 1, 1.0f, alpha}};
    Simulation sim(scene);
    double mean_stretch = 0.0;
    const int frames = 120;  // 2 s: about 10 periods of 2 pi sqrt(m alpha) = 0.2 s
    for (int f = 0; f < frames; ++f) {
      sim.step_frame();
      const auto& s = sim.particles();
      const std::size_t hanging = s.id[0] == 1 ? 0 : 1;
      mean_stretch += (1.0 - s.y[hanging]) - 1.0;
    }
    mean_stretch /= frames;
    EXPECT_NEAR(mean_stretch, 9.81 * alpha, 0.1 * 9.81 * alpha) << substeps << " substeps";
  }
}

TEST(Simulation, RestingFluidColumnKeepsItsDensity) {
  SceneDef scene;
  scene.domain.min = {0, 0, 0};
  scene.domain.max = {0.3f, 1.0f, 0.3f};
  FluidDef column;
  column.box.min = {0, 0, 0};
  column.box.max = {0.3f, 0.6f, 0.3f};
  column.spacing = 0.02f;
  scene.fluids = {column};
  Simulation sim(scene);
  const std::size_t n = sim.particles().size();
  ASSERT_EQ(n, 15u * 30u * 15u);
  FrameMetrics m;
  for (int f = 0; f < 120; ++f) m = sim.step_frame();  // 2 s
  const ErrorRow* density = m.error("fluid_density_error");
  ASSERT_NE(density, nullptr);
  EXPECT_LT(density->mean, 0.01);
  EXPECT_LT(density->max, 0.05);
  EXPECT_EQ(m.non_finite, 0u);
  EXPECT_TRUE(inside_domain(sim));
  // Settled: the column is at rest (RMS speed from the kinetic energy, a few mm/s; surface
  // particles may still jitter, so the max speed is not the measure).
  double mass = 0.0;
  for (std::size_t i = 0; i < n; ++i) mass += 1.0 / sim.particles().w[i];
  EXPECT_LT(std::sqrt(2.0 * m.kinetic_energy / mass), 0.05);
}

TEST(Simulation, DamBreakStaysFiniteAndInside) {
  Simulation sim(load_scene_text(default_scene_json(), "<default scene>"));
  const std::size_t n = sim.particles().size();
  ASSERT_GT(n, 40000u);
  for (int f = 0; f < 120; ++f) {  // 2 s
    const FrameMetrics m = sim.step_frame();
    ASSERT_EQ(m.non_finite, 0u) << "frame " << f + 1;
    ASSERT_EQ(m.particles, n);
  }
  EXPECT_TRUE(inside_domain(sim));
}

// ---- Runner: files, report, determinism -------------------------------------------------------------

TEST(Runner, OneAndTwoThreadsWriteBitIdenticalFiles) {
  // Fluid, a chain of raw particles on distance constraints, and colliders: every pass runs.
  std::vector<std::string> overrides = {"fluids.0.spacing=0.06", "fluids.1.spacing=0.06",
                                        "fluids.0.vorticity=0.05", "fluids.1.vorticity=0.05"};
  SceneDef scene = load_scene_file(scene_path("double_dam_break.json"), overrides);
  for (int k = 0; k < 10; ++k) scene.particles.push_back({{1.5f + 0.1f * k, 2.0f, 0.7f}, {0, 0, 0}, k == 0 ? 0.0f : 1.0f});
  for (int k = 0; k + 1 < 10; ++k) scene.distance_constraints.push_back({k, k + 1, -1.0f, 0.0f});
  RunOptions one, two;
  one.frames = two.frames = 30;
  one.threads = 1, two.threads = 2;
  one.out_dir = fresh_dir("threads1");
  two.out_dir = fresh_dir("threads2");
  run_scene(scene, one);
  run_scene(scene, two);
  for (int f : {1, 15, 30}) {
    const std::string name = frame_file_name("particles", f, "ply");
    const std::string a = read_file(one.out_dir / name), b = read_file(two.out_dir / name);
    ASSERT_FALSE(a.empty());
    EXPECT_TRUE(a == b) << name << " differs between 1 and 2 threads";
  }
}

TEST(Runner, WritesPlyInIdOrderAndAReport) {
  const fs::path dir = fresh_dir("report");
  SceneDef scene = load_scene_file(scene_path("dam_break.json"), std::vector<std::string>{"fluids.0.spacing=0.08"});
  scene.particles.push_back({{3.0f, 2.0f, 0.5f}, {0, 0, 0}, 1.0f});
  scene.particles.push_back({{3.2f, 2.0f, 0.5f}, {0, 0, 0}, 1.0f});
  scene.distance_constraints.push_back({0, 1, -1.0f, 0.0f});
  RunOptions o;
  o.frames = 3;
  o.out_dir = dir;
  o.report = dir / "report.json";
  const RunResult r = run_scene(scene, o);
  ASSERT_EQ(r.frames, 3);

  // PLY: header, then records of 7 values in id order.
  const std::string ply = read_file(dir / "particles.0003.ply");
  const std::size_t header_end = ply.find("end_header\n");
  ASSERT_NE(header_end, std::string::npos);
  EXPECT_NE(ply.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(ply.find("element vertex " + std::to_string(r.particles) + "\n"), std::string::npos);
  const char* body = ply.data() + header_end + 11;
  ASSERT_EQ(ply.size() - (header_end + 11), r.particles * 28);
  for (std::size_t k = 0; k < r.particles; ++k) {
    std::int32_t id;
    std::memcpy(&id, body + 28 * k + 24, 4);
    ASSERT_EQ(id, std::int32_t(k));
  }
  float y0;  // particle 0 fell for 3 frames under gravity
  std::memcpy(&y0, body + 4, 4);
  EXPECT_LT(y0, 2.0f);
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().extension() == ".tmp", false) << "left a temporary file: " << e.path();

  const nlohmann::json rep = nlohmann::json::parse(read_file(dir / "report.json"));
  EXPECT_EQ(r.report, read_file(dir / "report.json"));  // the result carries the report written
  EXPECT_EQ(rep["status"], "ok");
  EXPECT_EQ(rep["settings"]["particles"], r.particles);
  ASSERT_EQ(rep["frames"].size(), 3u);
  const auto& f3 = rep["frames"][2];
  EXPECT_EQ(f3["frame"], 3);
  EXPECT_EQ(f3["non_finite"], 0);
  for (const char* pass :
       {"predict", "neighbors", "fluid density", "distance", "collisions", "update", "viscosity"})
    EXPECT_TRUE(f3["pass_ms"].contains(pass)) << pass;
  EXPECT_EQ(rep["settings"]["density_tolerance"], 0.01);  // as written, not as its float
  EXPECT_EQ(f3["iterations"]["max"], scene.solver.iterations);  // nothing needed more
  EXPECT_FALSE(f3["pass_ms"].contains("vorticity"));  // off in this scene: not built, not timed
  EXPECT_GE(f3["fluid_density_error"]["max"].get<double>(), f3["fluid_density_error"]["mean"].get<double>());
  EXPECT_LT(f3["distance_error"]["max"].get<double>(), 1e-3);
  EXPECT_GT(f3["kinetic_energy"].get<double>(), 0.0);
  EXPECT_GT(f3["max_speed"].get<double>(), 0.0);
}

TEST(Runner, NonFiniteStateStopsTheRun) {
  // A NaN velocity (which no scene file can hold) must stop the run, not be hidden by a wall.
  SceneDef scene;
  scene.particles = {{{0.5f, 0.5f, 0.5f}, {std::nanf(""), 0, 0}, 1.0f}};
  RunOptions o;
  o.frames = 5;
  o.report = fresh_dir("diverged") / "report.json";
  EXPECT_THROW(run_scene(scene, o), SimulationError);
  const nlohmann::json rep = nlohmann::json::parse(read_file(o.report));
  EXPECT_EQ(rep["status"], "error");
  EXPECT_GT(rep["frames"][0]["non_finite"].get<int>(), 0);
}

TEST(OutputFiles, BackgroundWriterWritesEveryFileInOrderAndStopsAtTheFirstFailure) {
  const fs::path dir = fresh_dir("background_writer");
  fs::create_directories(dir / "c.bin" / "x");  // a folder in the way: c.bin's rename fails
  BackgroundWriter writer(1);
  writer.submit(dir / "a.bin", "first");
  writer.submit(dir / "b.bin", std::string(1 << 20, 'b'));
  writer.finish();
  EXPECT_EQ(read_file(dir / "a.bin"), "first");
  EXPECT_EQ(read_file(dir / "b.bin").size(), std::size_t(1) << 20);
  writer.submit(dir / "c.bin", "third");
  try {
    writer.submit(dir / "d.bin", "fourth");  // may or may not see c's failure yet
    writer.submit(dir / "e.bin", "fifth");   // waits for room: c is done by then
    writer.finish();
    ADD_FAILURE() << "no IoError for c.bin";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "c.bin").string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(writer.finish(), IoError);  // the failure stays in force
  EXPECT_THROW(writer.submit(dir / "f.bin", "sixth"), IoError);
  for (const char* later : {"d.bin", "e.bin", "f.bin"}) EXPECT_FALSE(fs::exists(dir / later)) << later;
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_FALSE(e.path().filename().string().ends_with(".tmp")) << e.path();
}

TEST(OutputFiles, UnwritableFolderIsAnIoError) {
  EXPECT_THROW(prepare_output_directory("/dev/null/seiche"), IoError);
  EXPECT_THROW(write_file_atomically("/nonexistent-dir/x.ply", "data"), IoError);
}

// ---- Particles for ParaView: .vtp and .pvd ----------------------------------------------------

namespace {

// The value of `attribute="..."` in the first XML element at or after `from` that has it.
std::string xml_attribute(const std::string& text, const std::string& attribute, std::size_t from = 0) {
  const std::string key = " " + attribute + "=\"";
  const std::size_t at = text.find(key, from);
  if (at == std::string::npos) return "<none>";
  const std::size_t start = at + key.size();
  return text.substr(start, text.find('"', start) - start);
}

// Where the DataArray called `name` starts in `header` (npos if none).
std::size_t data_array(const std::string& header, const char* name) {
  const std::size_t at = header.find(std::string(" Name=\"") + name + "\"");
  return at == std::string::npos ? at : header.rfind("<DataArray", at);
}

// A .vtp's appended arrays by name: the UInt64 byte count each starts with, and its bytes.
struct VtpArrays {
  std::string header;                     // the XML before <AppendedData>
  std::map<std::string, std::string> bytes;  // name -> the array's bytes
  std::uint64_t data_bytes = 0;           // from the '_' to </AppendedData>
};

VtpArrays read_vtp(const std::string& file) {
  VtpArrays v;
  const std::string appended = "<AppendedData encoding=\"raw\">\n   _";
  const std::size_t at = file.find(appended);
  if (at == std::string::npos) return v;
  v.header = file.substr(0, at);
  const std::size_t data = at + appended.size();
  const std::string tail = "\n  </AppendedData>\n</VTKFile>\n";
  if (!file.ends_with(tail)) return v;
  v.data_bytes = file.size() - tail.size() - data;
  for (const char* name : {"velocity", "id", "Points", "connectivity", "offsets"}) {
    const std::size_t element = data_array(v.header, name);
    if (element == std::string::npos) continue;
    const std::uint64_t offset = std::strtoull(xml_attribute(v.header, "offset", element).c_str(), nullptr, 10);
    std::uint64_t size = 0;
    if (offset + 8 > v.data_bytes) continue;
    std::memcpy(&size, file.data() + data + offset, 8);
    if (offset + 8 + size > v.data_bytes) continue;
    v.bytes[name] = file.substr(data + offset + 8, size);
  }
  return v;
}

}  // namespace

TEST(VtkParticles, VtpOfATinyStoreHoldsItsArraysInIdOrder) {
  // Three particles whose store order is not their id order (the grid sort reorders the store).
  ParticleStore s;
  s.resize(3);
  const std::int32_t ids[3] = {2, 0, 1};
  for (std::size_t i = 0; i < 3; ++i) {
    s.id[i] = ids[i];
    s.x[i] = 1.0f + ids[i], s.y[i] = -0.0f, s.z[i] = 0.5f * ids[i];
    s.vx[i] = 10.0f * ids[i], s.vy[i] = -9.81f, s.vz[i] = 1e-30f;
  }
  const std::string file = encode_particles_vtp(s);
  const VtpArrays v = read_vtp(file);
  ASSERT_FALSE(v.header.empty()) << file.substr(0, 400);
  EXPECT_EQ(xml_attribute(v.header, "type"), "PolyData");
  EXPECT_EQ(xml_attribute(v.header, "byte_order"), "LittleEndian");
  EXPECT_EQ(xml_attribute(v.header, "header_type"), "UInt64");
  EXPECT_EQ(xml_attribute(v.header, "NumberOfPoints"), "3");
  EXPECT_EQ(xml_attribute(v.header, "NumberOfVerts"), "3");
  EXPECT_EQ(xml_attribute(v.header, "NumberOfPolys"), "0");
  EXPECT_EQ(xml_attribute(v.header, "type", data_array(v.header, "id")), "Int32");
  EXPECT_EQ(xml_attribute(v.header, "NumberOfComponents", data_array(v.header, "velocity")), "3");
  // Five arrays with their UInt64 counts fill the appended data exactly.
  ASSERT_EQ(v.bytes.size(), 5u);
  EXPECT_EQ(v.data_bytes, 5 * 8 + 3 * (12 + 4 + 12 + 4 + 4));
  ASSERT_EQ(v.bytes.at("Points").size(), 36u);
  ASSERT_EQ(v.bytes.at("velocity").size(), 36u);
  for (const char* name : {"id", "connectivity", "offsets"}) ASSERT_EQ(v.bytes.at(name).size(), 12u) << name;
  float points[9], velocity[9];
  std::int32_t id[3], connectivity[3], offsets[3];
  std::memcpy(points, v.bytes.at("Points").data(), sizeof(points));
  std::memcpy(velocity, v.bytes.at("velocity").data(), sizeof(velocity));
  std::memcpy(id, v.bytes.at("id").data(), sizeof(id));
  std::memcpy(connectivity, v.bytes.at("connectivity").data(), sizeof(connectivity));
  std::memcpy(offsets, v.bytes.at("offsets").data(), sizeof(offsets));
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(id[k], k);
    EXPECT_EQ(points[3 * k], 1.0f + k);
    EXPECT_TRUE(std::signbit(points[3 * k + 1])) << "-0.0 kept bit for bit";
    EXPECT_EQ(points[3 * k + 2], 0.5f * k);
    EXPECT_EQ(velocity[3 * k], 10.0f * k);
    EXPECT_EQ(velocity[3 * k + 1], -9.81f);
    EXPECT_EQ(velocity[3 * k + 2], 1e-30f);
    EXPECT_EQ(connectivity[k], k);
    EXPECT_EQ(offsets[k], k + 1);
  }
}

TEST(VtkParticles, NoParticlesWritesAValidFileWithNoPoints) {
  const ParticleStore empty;
  const std::string file = encode_particles_vtp(empty);
  const VtpArrays v = read_vtp(file);
  ASSERT_FALSE(v.header.empty()) << file;
  EXPECT_EQ(xml_attribute(v.header, "NumberOfPoints"), "0");
  EXPECT_EQ(xml_attribute(v.header, "NumberOfVerts"), "0");
  ASSERT_EQ(v.bytes.size(), 5u);  // every array is there, each a count of 0 bytes
  for (const auto& [name, bytes] : v.bytes) EXPECT_TRUE(bytes.empty()) << name;
  EXPECT_EQ(v.data_bytes, 5u * 8u);
}

TEST(VtkParticles, SeriesListsEachFrameWithItsTime) {
  const double dt = 1.0 / 60.0;
  const std::string pvd = encode_particle_series_pvd("particles", 3, 5, dt);
  EXPECT_EQ(xml_attribute(pvd, "type"), "Collection");
  std::size_t at = 0;
  for (int f = 3; f <= 5; ++f) {
    at = pvd.find("<DataSet", at);
    ASSERT_NE(at, std::string::npos) << f;
    EXPECT_EQ(xml_attribute(pvd, "file", at), frame_file_name("particles", f, "vtp"));
    // The time reads back as the simulation's own double, frame * frame_dt.
    EXPECT_EQ(std::strtod(xml_attribute(pvd, "timestep", at).c_str(), nullptr), f * dt) << f;
    ++at;
  }
  EXPECT_EQ(pvd.find("<DataSet", at), std::string::npos);
  EXPECT_NE(pvd.find("</Collection>\n</VTKFile>\n"), std::string::npos);
  // No frame yet: an empty series, still a whole file. The last possible frame ends the loop.
  const std::string none = encode_particle_series_pvd("particles", 3, 2, dt);
  EXPECT_EQ(none.find("<DataSet"), std::string::npos);
  EXPECT_NE(none.find("<Collection>\n  </Collection>"), std::string::npos) << none;
  const std::string last = encode_particle_series_pvd("particles", INT_MAX, INT_MAX, dt);
  EXPECT_EQ(xml_attribute(last, "file"), frame_file_name("particles", INT_MAX, "vtp"));
}

// The progress line: plain in logs; on a terminal a bar in front, cut to the terminal's width.
TEST(Progress, TerminalLineHasABarAndFitsTheWidth) {
  const std::string plain = progress_line(5, 20, "1000 particles  2.0 ms/frame", 3.0, "  1.2 MB written");
  EXPECT_EQ(plain, "frame 5/20  1000 particles  2.0 ms/frame  ETA 3.0 s  1.2 MB written");
  EXPECT_EQ(terminal_progress_line(plain, 5, 20, 20, 200), "[#####---------------] " + plain);
  EXPECT_EQ(terminal_progress_line(plain, 20, 20, 20, 200).substr(0, 22), "[####################]");
  EXPECT_EQ(terminal_progress_line(plain, 5, 20, 8, 200), "[##------] " + plain);
  EXPECT_EQ(terminal_progress_line(plain, 5, 20, 4, 200), plain);  // too short a bar: none
  // Never the full width: a full line wraps on some terminals and cannot be rewritten in place.
  EXPECT_EQ(terminal_progress_line(plain, 5, 20, 0, 40), plain.substr(0, 39));
}
