// Checkpoints and the bake loop: a restored simulation continues bit for bit; damaged or foreign
// checkpoints are refused with a message naming the file; an interrupted or failed bake keeps
// its last complete frame and checkpoint and resumes to the same bytes as an uninterrupted one.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

#include "families/distance/distance_solver.hpp"
#include "seiche/bake.hpp"
#include "seiche/kernels/simd_info.hpp"
#include "seiche/checkpoint.hpp"
#include "seiche/input_fingerprint.hpp"
#include "seiche/memory_estimate.hpp"
#include "seiche/output_files.hpp"
#include "seiche/runner.hpp"
#include "seiche/scene_loader.hpp"
#include "seiche/simulation.hpp"
#include "test_temp_dir.hpp"

using namespace seiche;
namespace fs = std::filesystem;

namespace {

// Every pass runs: fluid (density, vorticity, viscosity) falling around a sphere, a chain of raw
// particles on distance constraints hanging from a pinned one, the domain's walls. About 2000
// particles, so that the grid sort reorders the store every substep.
const char* const kScene = R"({
  "name": "mixed",
  "solver": { "substeps": 4, "iterations": 2 },
  "domain": { "min": [0, 0, 0], "max": [1, 1, 0.5] },
  "output": { "frames": 12, "checkpoint_every": 4, "vdb": [] },
  "colliders": [ { "sphere": { "center": [0.6, 0.15, 0.25], "radius": 0.1 } } ],
  "fluids": [ { "box": { "min": [0, 0, 0], "max": [0.36, 0.6, 0.3] }, "spacing": 0.03,
                "vorticity": 0.05, "viscosity": 0.02 } ],
  "particles": [ { "x": [0.8, 0.9, 0.25], "mass": 0 }, { "x": [0.85, 0.9, 0.25] }, { "x": [0.9, 0.9, 0.25] },
                 { "x": [0.95, 0.9, 0.25] }, { "x": [0.95, 0.85, 0.25] } ],
  "distance_constraints": [ { "i": 0, "j": 1 }, { "i": 1, "j": 2 }, { "i": 2, "j": 3 },
                            { "i": 3, "j": 4, "compliance": 1e-4 } ] })";

SceneDef mixed_scene(const std::vector<std::string>& overrides = {}) {
  return load_scene_text(kScene, "mixed.json", overrides);
}

// A sheet hanging from two pinned corners: the stretch forests carry their multipliers from one
// substep to the next (the cloth family's checkpoint chunk).
const char* const kClothScene = R"({
  "name": "hanging",
  "solver": { "substeps": 4, "iterations": 4 },
  "domain": { "min": [0, 0, 0], "max": [1, 1, 1] },
  "cloths": [ { "sheet": { "origin": [0.2, 0.8, 0.2], "size": [0.5, 0.5], "resolution": [12, 12] },
                "pins": [0, 11] } ] })";

BakeRecipe mixed_recipe(int first, int last, const std::vector<std::string>& overrides = {}) {
  return make_bake_recipe("mixed", "mixed.json", kScene, overrides, first, last);
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = testing_support::temp_path("seiche_bake_tests_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_bytes(const fs::path& p, std::string_view bytes) {
  std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

// Every state column, bit for bit.
void expect_same_state(const ParticleStore& a, const ParticleStore& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  const std::size_t n = a.size();
  auto same = [n](const auto& x, const auto& y) {
    return std::memcmp(x.data(), y.data(), n * sizeof(x[0])) == 0;
  };
  EXPECT_TRUE(same(a.id, b.id)) << what << ": store order (id column) differs";
  EXPECT_TRUE(same(a.phase, b.phase)) << what << ": phase";
  EXPECT_TRUE(same(a.w, b.w)) << what << ": w";
  const char* names[] = {"x", "y", "z", "px", "py", "pz", "vx", "vy", "vz"};
  const FloatColumn* ca[] = {&a.x, &a.y, &a.z, &a.px, &a.py, &a.pz, &a.vx, &a.vy, &a.vz};
  const FloatColumn* cb[] = {&b.x, &b.y, &b.z, &b.px, &b.py, &b.pz, &b.vx, &b.vy, &b.vz};
  for (int c = 0; c < 9; ++c) EXPECT_TRUE(same(*ca[c], *cb[c])) << what << ": column " << names[c];
}

// Records what the bake hands an exporter and writes one small file per frame: the frame
// number, the time and a hash of the positions in id order.
class RecordingExporter : public FrameExporter {
 public:
  std::string name() const override { return "record"; }
  std::vector<fs::path> files(int frame) const override {
    return {frame_file_name("record", frame, "txt")};
  }
  std::uint64_t write_frame(const FrameView& v, const fs::path& dir) override {
    frames.push_back(v.frame);
    const ParticleStore& s = v.particles;
    std::vector<float> xyz(3 * s.size());
    for (std::size_t i = 0; i < s.size(); ++i) {
      const std::size_t k = std::size_t(s.id[i]);
      xyz[3 * k] = s.x[i], xyz[3 * k + 1] = s.y[i], xyz[3 * k + 2] = s.z[i];
    }
    const std::string text =
        std::to_string(v.frame) + " " + std::to_string(v.time) + " " +
        std::to_string(fnv1a64({reinterpret_cast<const char*>(xyz.data()), xyz.size() * 4})) + "\n";
    write_file_atomically(dir / files(v.frame)[0], text);
    return text.size();
  }
  std::vector<int> frames;
};

// The files of a bake folder that must match between bakes (report.json holds timings).
std::map<std::string, std::string> frame_files(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name != kBakeReportFile) files[name] = read_bytes(e.path());
  }
  return files;
}

void expect_no_temporary_files(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_NE(e.path().extension(), ".tmp") << "left a temporary file: " << e.path();
}

BakeOptions quiet_options(const fs::path& dir, std::vector<FrameExporter*> exporters = {}) {
  BakeOptions o;
  o.out_dir = dir;
  o.threads = 2;
  o.exporters = std::move(exporters);
  return o;
}

// A checkpoint file taken apart along its layout (checkpoint.hpp), to be changed in one place
// and sealed again (body size and checksum), so that only the reader's checks of that place
// stand between it and a restore.
struct CheckpointParts {
  struct Column {
    std::string name;
    std::uint8_t type;
    std::string values;
  };
  std::string head;  // version, fingerprint, frame, time, particle count
  std::uint64_t n = 0;
  std::vector<Column> columns;
  std::vector<std::pair<std::string, std::string>> chunks;

  static constexpr std::size_t kPreamble = 8 + 4 + 8 + 8;
  explicit CheckpointParts(const std::string& file) {
    const std::string body = file.substr(kPreamble);
    std::size_t at = 0;
    auto take = [&](std::size_t size) {
      std::string bytes = body.substr(at, size);
      at += size;
      return bytes;
    };
    auto number = [&](auto value) {
      std::memcpy(&value, body.data() + at, sizeof(value));
      at += sizeof(value);
      return value;
    };
    auto text = [&] { return take(number(std::uint32_t())); };
    text();
    at += 8 + 4 + 8;
    n = number(std::uint64_t());
    head = body.substr(0, at);
    for (std::uint32_t k = number(std::uint32_t()); k > 0; --k) {
      std::string name = text();
      const auto type = number(std::uint8_t());
      columns.push_back({name, type, take(n * 4)});
    }
    for (std::uint32_t k = number(std::uint32_t()); k > 0; --k) {
      std::string name = text();
      chunks.emplace_back(name, take(number(std::uint64_t())));
    }
  }
  template <class T>
  static void put(std::string& out, T value) {
    out.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  std::string body() const {
    std::string b = head;
    put(b, std::uint32_t(columns.size()));
    for (const Column& c : columns) {
      put(b, std::uint32_t(c.name.size()));
      b += c.name;
      put(b, c.type);
      b += c.values;
    }
    put(b, std::uint32_t(chunks.size()));
    for (const auto& [name, bytes] : chunks) {
      put(b, std::uint32_t(name.size()));
      b += name;
      put(b, std::uint64_t(bytes.size()));
      b += bytes;
    }
    return b;
  }
  /// A checkpoint file of `body` in format `format`.
  static std::string seal(const std::string& body, std::uint32_t format = 3) {
    std::string file = "SEICHECP";
    put(file, format);
    put(file, std::uint64_t(body.size()));
    put(file, fnv1a64(body));
    return file + body;
  }
};

}  // namespace

// ---- Checkpoints ----------------------------------------------------------------------------

TEST(Checkpoint, RestoredSimulationContinuesBitForBit) {
  const SceneDef scene = mixed_scene();
  const std::uint64_t fingerprint = mixed_recipe(1, 12).scene_fingerprint();
  constexpr int kSaveAt = 5, kMore = 6;
  const fs::path file = fresh_dir("roundtrip") / "checkpoint.bin";

  Simulation straight(scene);
  for (int f = 0; f < kSaveAt; ++f) straight.step_frame();
  write_file_atomically(file, encode_checkpoint(straight, fingerprint));
  ParticleStore at_save;  // a copy of the saved state, to see the continuation move on
  at_save.resize(straight.particles().size());
  std::memcpy(at_save.y.data(), straight.particles().y.data(), at_save.size() * 4);
  // The store is in cell order, not id order: a restore that ignored the order would show.
  bool reordered = false;
  for (std::size_t i = 0; i < straight.particles().size(); ++i)
    reordered |= straight.particles().id[i] != int(i);
  EXPECT_TRUE(reordered);
  for (int f = 0; f < kMore; ++f) straight.step_frame();

  Simulation resumed(scene);
  const Checkpoint cp = read_checkpoint(file);
  EXPECT_EQ(cp.frame, kSaveAt);
  EXPECT_EQ(cp.time, kSaveAt * scene.solver.frame_dt);
  restore_checkpoint(resumed, cp, fingerprint, file);
  EXPECT_EQ(resumed.frame(), kSaveAt);
  expect_same_state(resumed.particles(), cp.state, "right after the restore");
  for (int f = 0; f < kMore; ++f) resumed.step_frame();

  EXPECT_EQ(resumed.frame(), straight.frame());
  EXPECT_EQ(resumed.time(), straight.time());
  expect_same_state(resumed.particles(), straight.particles(), "after stepping on");
  // The continuation did something: the fluid fell between the save and the end.
  float moved = 0.0f;
  for (std::size_t i = 0; i < at_save.size(); ++i)
    moved = std::max(moved, std::abs(straight.particles().y[i] - at_save.y[i]));
  EXPECT_GT(moved, 0.01f);
  // The distance constraints were remapped with the store: the chain still holds together.
  const FrameMetrics m = resumed.step_frame();
  ASSERT_NE(m.error("distance_error"), nullptr);
  EXPECT_LT(m.error("distance_error")->max, 0.25);
}

TEST(Checkpoint, DamagedFilesAreRefusedNamingTheFile) {
  const SceneDef scene = mixed_scene();
  Simulation sim(scene);
  sim.step_frame();
  const std::string good = encode_checkpoint(sim, 42);
  const fs::path dir = fresh_dir("damaged");
  const fs::path file = dir / "checkpoint.bin";

  auto refusal = [&](std::string_view bytes) -> std::string {
    write_bytes(file, bytes);
    try {
      read_checkpoint(file);
    } catch (const ResumeError& e) {
      return e.what();
    }
    return "(accepted)";
  };
  auto expect_refused = [&](std::string_view bytes, const std::string& why, const char* label) {
    const std::string message = refusal(bytes);
    EXPECT_NE(message.find(file.string()), std::string::npos) << label << ": " << message;
    EXPECT_NE(message.find(why), std::string::npos)
        << label << ": expected '" << why << "' in: " << message;
  };

  EXPECT_EQ(refusal(good), "(accepted)");
  expect_refused(std::string_view(good).substr(0, good.size() - 100), "truncated",
                 "truncated body");
  expect_refused(std::string_view(good).substr(0, 20), "ends inside", "truncated header");
  expect_refused("", "not a Seiche checkpoint", "empty");
  expect_refused("PK\x03\x04 some zip file", "not a Seiche checkpoint", "other file");
  std::string flipped = good;
  flipped[flipped.size() / 2] ^= 0x10;  // one bit inside the columns
  expect_refused(flipped, "checksum", "flipped bit");
  std::string future = good;
  future[8] = 9;  // format version 9
  expect_refused(future, "format version 9", "newer format");
  fs::remove(file);
  try {
    read_checkpoint(file);
    ADD_FAILURE() << "a missing checkpoint was accepted";
  } catch (const ResumeError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
}

TEST(Checkpoint, ClothStretchMultipliersAreTheClothFamilysChunk) {
  const SceneDef scene = load_scene_text(kClothScene, "hanging.json");
  const fs::path file = fresh_dir("cloth_chunk") / "checkpoint.bin";
  Simulation straight(scene);
  for (int f = 0; f < 3; ++f) straight.step_frame();
  write_file_atomically(file, encode_checkpoint(straight, 42));
  for (int f = 0; f < 3; ++f) straight.step_frame();

  const Checkpoint cp = read_checkpoint(file);
  ASSERT_EQ(cp.chunks.all().size(), 1u);
  const CheckpointChunks::Chunk& chunk = cp.chunks.all()[0];
  EXPECT_EQ(chunk.name, "cloth.stretch_multipliers");
  ASSERT_GT(chunk.bytes.size(), 0u);
  EXPECT_EQ(chunk.bytes.size() % 4, 0u);
  Simulation resumed(scene);
  restore_checkpoint(resumed, cp, 42, file);
  for (int f = 0; f < 3; ++f) resumed.step_frame();
  expect_same_state(resumed.particles(), straight.particles(), "cloth after stepping on");

  // The chunk matters: zeroed multipliers continue to other bits.
  Checkpoint zeroed = cp;
  zeroed.chunks = {};
  zeroed.chunks.put(chunk.name, std::string(chunk.bytes.size(), '\0'));
  Simulation forgetful(scene);
  restore_checkpoint(forgetful, zeroed, 42, file);
  for (int f = 0; f < 3; ++f) forgetful.step_frame();
  EXPECT_NE(std::memcmp(forgetful.particles().y.data(), straight.particles().y.data(),
                        straight.particles().size() * 4),
            0);
}

TEST(Checkpoint, DistanceForestMultipliersAreTheDistanceFamilysChunk) {
  // The mixed scene's chain hangs from a pinned particle: one forest, whose geometric stiffness
  // reads the multipliers of the substep before. Its fluid reorders the store every substep.
  const SceneDef scene = mixed_scene();
  const std::uint64_t fingerprint = mixed_recipe(1, 12).scene_fingerprint();
  const fs::path file = fresh_dir("distance_chunk") / "checkpoint.bin";
  Simulation straight(scene);
  ASSERT_TRUE(straight.distance() && straight.distance()->has_forests());
  for (int f = 0; f < 3; ++f) straight.step_frame();
  write_file_atomically(file, encode_checkpoint(straight, fingerprint));
  for (int f = 0; f < 3; ++f) straight.step_frame();

  const Checkpoint cp = read_checkpoint(file);
  const CheckpointChunks::Chunk* chunk = cp.chunks.find("distance.multipliers");
  ASSERT_NE(chunk, nullptr);
  EXPECT_EQ(chunk->bytes.size(), 4u * 4u);  // one float per constraint
  Simulation resumed(scene);
  restore_checkpoint(resumed, cp, fingerprint, file);
  for (int f = 0; f < 3; ++f) resumed.step_frame();
  expect_same_state(resumed.particles(), straight.particles(), "chain after stepping on");

  // The chunk matters: zeroed multipliers continue to other bits.
  Checkpoint zeroed = cp;
  zeroed.chunks = {};
  for (const CheckpointChunks::Chunk& c : cp.chunks.all())
    zeroed.chunks.put(c.name, c.name == chunk->name ? std::string(c.bytes.size(), '\0') : c.bytes);
  Simulation forgetful(scene);
  restore_checkpoint(forgetful, zeroed, fingerprint, file);
  for (int f = 0; f < 3; ++f) forgetful.step_frame();
  const auto chain_y = [](const ParticleStore& s) {
    std::vector<float> y(5);
    for (std::size_t i = 0; i < s.size(); ++i)
      if (s.id[i] < 5) y[std::size_t(s.id[i])] = s.y[i];  // the raw particles have the first ids
    return y;
  };
  EXPECT_NE(chain_y(forgetful.particles()), chain_y(straight.particles()));
}

TEST(Checkpoint, ColumnsAndChunksAreReadByNameAndCheckedAgainstTheScene) {
  const SceneDef scene = load_scene_text(kClothScene, "hanging.json");
  Simulation sim(scene);
  sim.step_frame();
  const std::string good = encode_checkpoint(sim, 42);
  const fs::path file = fresh_dir("by_name") / "checkpoint.bin";
  // What reading and restoring `bytes` into a fresh simulation of the scene says.
  auto refusal = [&](const std::string& bytes) -> std::string {
    write_bytes(file, bytes);
    try {
      Simulation fresh(scene);
      restore_checkpoint(fresh, read_checkpoint(file), 42, file);
    } catch (const ResumeError& e) {
      return e.what();
    }
    return "(accepted)";
  };
  auto expect_refused = [&](const std::string& bytes, const std::string& why, const char* label) {
    const std::string message = refusal(bytes);
    EXPECT_NE(message.find(file.string()), std::string::npos) << label << ": " << message;
    EXPECT_NE(message.find(why), std::string::npos) << label << ": expected '" << why << "' in: " << message;
  };
  const CheckpointParts parts(good);
  ASSERT_EQ(parts.columns.size(), 12u);
  ASSERT_EQ(parts.chunks.size(), 1u);
  EXPECT_EQ(refusal(CheckpointParts::seal(parts.body())), "(accepted)");  // the parts are the file

  CheckpointParts unknown_chunk = parts;
  unknown_chunk.chunks.emplace_back("shape.rest_rotations", std::string(16, '\1'));
  expect_refused(CheckpointParts::seal(unknown_chunk.body()),
                 "holds chunk 'shape.rest_rotations' that this seiche does not know", "unknown chunk");
  CheckpointParts unknown_column = parts;
  unknown_column.columns.push_back({"rod.twist", 0, std::string(parts.n * 4, '\0')});
  expect_refused(CheckpointParts::seal(unknown_column.body()),
                 "holds column 'rod.twist' that this seiche does not know", "unknown column");
  CheckpointParts not_state = parts;
  not_state.columns.push_back({"density", 0, std::string(parts.n * 4, '\0')});
  expect_refused(CheckpointParts::seal(not_state.body()), "column 'density'", "scratch column");

  CheckpointParts missing_column = parts;
  missing_column.columns.erase(missing_column.columns.begin() + 9);
  ASSERT_EQ(parts.columns[9].name, "w");
  expect_refused(CheckpointParts::seal(missing_column.body()), "no column 'w'", "missing column");
  CheckpointParts missing_chunk = parts;
  missing_chunk.chunks.clear();
  expect_refused(CheckpointParts::seal(missing_chunk.body()), "no chunk 'cloth.stretch_multipliers'",
                 "missing chunk");

  CheckpointParts short_chunk = parts;  // consistent, but one multiplier short
  short_chunk.chunks[0].second.resize(short_chunk.chunks[0].second.size() - 4);
  expect_refused(CheckpointParts::seal(short_chunk.body()), "chunk 'cloth.stretch_multipliers' holds",
                 "short chunk");
  std::string truncated = parts.body();  // the chunk's announced size runs past the end
  truncated.resize(truncated.size() - 4);
  expect_refused(CheckpointParts::seal(truncated), "ends inside chunk 'cloth.stretch_multipliers'",
                 "truncated chunk");
  CheckpointParts phase_as_float = parts;  // phase written as f32
  phase_as_float.columns[10].type = 0;
  ASSERT_EQ(parts.columns[10].name, "phase");
  expect_refused(CheckpointParts::seal(phase_as_float.body()), "column 'phase' is f32", "retyped column");
  expect_refused(CheckpointParts::seal(parts.body(), 2), "format version 2, this seiche reads version 3",
                 "format 2");
}

TEST(Checkpoint, CheckpointOfAnotherSceneIsRefused) {
  const fs::path file = fresh_dir("foreign") / "checkpoint.bin";
  Simulation sim(mixed_scene());
  sim.step_frame();
  const std::uint64_t fingerprint = mixed_recipe(1, 12).scene_fingerprint();
  write_file_atomically(file, encode_checkpoint(sim, fingerprint));
  const Checkpoint cp = read_checkpoint(file);

  // Same particle count, other settings: only the fingerprint tells them apart.
  const std::vector<std::string> other = {"solver.iterations=3"};
  const std::uint64_t other_fingerprint = mixed_recipe(1, 12, other).scene_fingerprint();
  EXPECT_NE(other_fingerprint, fingerprint);
  Simulation other_sim(mixed_scene(other));
  try {
    restore_checkpoint(other_sim, cp, other_fingerprint, file);
    ADD_FAILURE() << "a checkpoint of another scene was restored";
  } catch (const ResumeError& e) {
    EXPECT_NE(std::string(e.what()).find("another scene"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
  // Another particle count, even under a matching fingerprint.
  Simulation smaller(mixed_scene({"fluids.0.spacing=0.06"}));
  try {
    restore_checkpoint(smaller, cp, fingerprint, file);
    ADD_FAILURE() << "a checkpoint with another particle count was restored";
  } catch (const ResumeError& e) {
    EXPECT_NE(std::string(e.what()).find("particles"), std::string::npos) << e.what();
  }
  EXPECT_EQ(other_sim.frame(), 0);
}

// ---- bake.json ------------------------------------------------------------------------------

TEST(BakeRecipe, RoundTripsAndDetectsEdits) {
  const fs::path dir = fresh_dir("recipe");
  const BakeRecipe r = mixed_recipe(3, 9, {"solver.iterations=3", "output.frames=9"});
  write_file_atomically(dir / kBakeRecipeFile, encode_bake_recipe(r));
  const BakeRecipe back = read_bake_recipe(dir);
  EXPECT_EQ(back.scene_json, r.scene_json);
  EXPECT_EQ(back.overrides, r.overrides);
  EXPECT_EQ(back.first_frame, 3);
  EXPECT_EQ(back.last_frame, 9);
  EXPECT_EQ(back.scene_fingerprint(), r.scene_fingerprint());
  EXPECT_EQ(encode_bake_recipe(back), encode_bake_recipe(r));
  const SceneDef scene = load_recipe_scene(back, dir / kBakeRecipeFile);
  EXPECT_EQ(scene.solver.iterations, 3);
  EXPECT_EQ(scene.output.frames, 9);
  EXPECT_EQ(scene.name, "mixed");

  std::string text = read_bytes(dir / kBakeRecipeFile);
  text.replace(text.find("solver.iterations=3"), 19, "solver.iterations=4");
  write_bytes(dir / kBakeRecipeFile, text);
  try {
    read_bake_recipe(dir);
    ADD_FAILURE() << "an edited bake.json was accepted";
  } catch (const ResumeError& e) {
    EXPECT_NE(std::string(e.what()).find("bake.json"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_bake_recipe(dir / "missing"), ResumeError);
}

// A frame number must be a whole number in int's range: 2.5 once became 2, and 1e10 went through
// an out-of-range double-to-int conversion (undefined behaviour).
TEST(BakeRecipe, RefusesFrameNumbersThatAreNotWholeOrOutOfRange) {
  const fs::path dir = fresh_dir("recipe_frames");
  const std::string good = encode_bake_recipe(mixed_recipe(2, 9));
  ASSERT_NE(good.find("\"last_frame\": 9"), std::string::npos) << good;
  for (const auto& [key, from, to] :
       {std::tuple{"first_frame", "\"first_frame\": 2", "\"first_frame\": 2.5"},
        std::tuple{"last_frame", "\"last_frame\": 9", "\"last_frame\": 1e10"},
        std::tuple{"last_frame", "\"last_frame\": 9", "\"last_frame\": 10000000000"},
        std::tuple{"first_frame", "\"first_frame\": 2", "\"first_frame\": -3"},
        std::tuple{"first_frame", "\"first_frame\": 2", "\"first_frame\": \"2\""}}) {
    std::string text = good;
    text.replace(text.find(from), std::string(from).size(), to);
    write_bytes(dir / kBakeRecipeFile, text);
    try {
      read_bake_recipe(dir);
      ADD_FAILURE() << to << " was accepted";
    } catch (const ResumeError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("bake.json"), std::string::npos) << what;
      EXPECT_NE(what.find(std::string(key) + " must be a whole number in [1, 2147483647]"), std::string::npos)
          << what;
    }
  }
  // Written as 9.0 it is still frame 9.
  std::string text = good;
  text.replace(text.find("\"last_frame\": 9"), 15, "\"last_frame\": 9.0");
  write_bytes(dir / kBakeRecipeFile, text);
  EXPECT_EQ(read_bake_recipe(dir).last_frame, 9);
}

// A bake started by a build whose multiply-adds round differently (fused against the x86-64
// baseline's unfused) would not continue bit for bit: its resume is refused, naming both builds.
TEST(BakeRecipe, RefusesABakeStartedByTheOtherKindOfArithmetic) {
  const fs::path dir = fresh_dir("recipe_arithmetic");
  BakeRecipe r = mixed_recipe(1, 4);
  EXPECT_EQ(r.fused_multiply_add, kernels::simd_info().fused_multiply_add);
  EXPECT_EQ(r.simd, kernels::simd_description());
  write_file_atomically(dir / kBakeRecipeFile, encode_bake_recipe(r));
  EXPECT_EQ(read_bake_recipe(dir).fused_multiply_add, r.fused_multiply_add);

  BakeRecipe other_family = r;
  other_family.family = "another family";
  other_family.simd = "another build";
  write_file_atomically(dir / kBakeRecipeFile, encode_bake_recipe(other_family));
  try {
    read_bake_recipe(dir);
    ADD_FAILURE() << "a bake of another CPU family was accepted";
  } catch (const ResumeError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("another family"), std::string::npos) << what;
    EXPECT_NE(what.find(kernels::simd_info().family), std::string::npos) << what;
  }

  r.fused_multiply_add = !r.fused_multiply_add;
  r.simd = "another build";
  write_file_atomically(dir / kBakeRecipeFile, encode_bake_recipe(r));
  try {
    read_bake_recipe(dir);
    ADD_FAILURE() << "a bake of the other arithmetic was accepted";
  } catch (const ResumeError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("bake.json"), std::string::npos) << what;
    EXPECT_NE(what.find("another build"), std::string::npos) << what;
    EXPECT_NE(what.find(kernels::simd_description()), std::string::npos) << what;
  }
}

// ---- The bake loop --------------------------------------------------------------------------

TEST(Bake, InterruptedBakeResumesToTheSameBytes) {
  const SceneDef scene = mixed_scene();
  const fs::path straight_dir = fresh_dir("straight"), stopped_dir = fresh_dir("stopped");

  RecordingExporter straight_export;
  const BakeResult straight =
      bake_scene(scene, mixed_recipe(1, 12), quiet_options(straight_dir, {&straight_export}));
  EXPECT_EQ(straight.status, BakeResult::Status::Complete);
  EXPECT_EQ(straight.checkpoint_frame, 12);
  EXPECT_EQ(straight_export.frames, (std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}));
  EXPECT_GT(straight.bytes_written, 12u * 2000u * 28u);

  // Stop after frame 6: between checkpoints (every 4), so the interrupt writes its own.
  std::atomic<bool> stop{false};
  RecordingExporter first_export;
  BakeOptions o = quiet_options(stopped_dir, {&first_export});
  o.interrupt = &stop;
  o.after_frame = [&](int f) { stop = f == 6; };
  const BakeResult first = bake_scene(scene, mixed_recipe(1, 12), o);
  EXPECT_EQ(first.status, BakeResult::Status::Interrupted);
  EXPECT_EQ(first.frames_done, 6);
  EXPECT_EQ(first.checkpoint_frame, 6);
  EXPECT_EQ(read_checkpoint(stopped_dir / kCheckpointFile).frame, 6);
  EXPECT_FALSE(fs::exists(stopped_dir / "particles.0007.ply"));
  expect_no_temporary_files(stopped_dir);

  // The resume reads the scene from bake.json, as the CLI does.
  const BakeRecipe recipe = read_bake_recipe(stopped_dir);
  RecordingExporter second_export;
  BakeOptions resume = quiet_options(stopped_dir, {&second_export});
  resume.resume = true;
  resume.threads = 1;  // another thread count: still the same bytes
  const BakeResult second =
      bake_scene(load_recipe_scene(recipe, stopped_dir / kBakeRecipeFile), recipe, resume);
  EXPECT_EQ(second.status, BakeResult::Status::Complete);
  EXPECT_EQ(second.start_frame, 6);
  EXPECT_EQ(second_export.frames, (std::vector<int>{7, 8, 9, 10, 11, 12}));

  const auto a = frame_files(straight_dir), b = frame_files(stopped_dir);
  EXPECT_EQ(a.size(), 12u * 2 + 2);  // ply + record per frame, checkpoint.bin, bake.json
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, bytes] : a) {
    ASSERT_TRUE(b.count(name)) << name;
    EXPECT_TRUE(b.at(name) == bytes) << name << " differs after the resume";
  }

  // Resuming a complete bake does nothing.
  RecordingExporter third_export;
  BakeOptions again = quiet_options(stopped_dir, {&third_export});
  again.resume = true;
  EXPECT_EQ(bake_scene(scene, recipe, again).status, BakeResult::Status::AlreadyComplete);
  EXPECT_TRUE(third_export.frames.empty());
}

TEST(Bake, FrameRangeWritesOnlyItsFramesFromAFullSimulation) {
  const SceneDef scene = mixed_scene();
  const fs::path full_dir = fresh_dir("range_full"), part_dir = fresh_dir("range_part");
  bake_scene(scene, mixed_recipe(1, 5), quiet_options(full_dir));
  RecordingExporter exporter;
  const BakeResult r = bake_scene(scene, mixed_recipe(3, 5), quiet_options(part_dir, {&exporter}));
  EXPECT_EQ(r.files_written, 6u);
  EXPECT_EQ(exporter.frames, (std::vector<int>{3, 4, 5}));
  for (int f = 1; f <= 6; ++f)
    EXPECT_EQ(fs::exists(part_dir / frame_file_name("particles", f, "ply")), f >= 3 && f <= 5) << f;
  EXPECT_EQ(read_bytes(part_dir / "particles.0003.ply"),
            read_bytes(full_dir / "particles.0003.ply"));
  EXPECT_EQ(read_bytes(part_dir / "particles.0005.ply"),
            read_bytes(full_dir / "particles.0005.ply"));
}

TEST(Bake, ReportHasTheExportTimeAndBytesOfEveryFrame) {
  const SceneDef scene = mixed_scene();  // checkpoint_every 4
  const fs::path dir = fresh_dir("report");
  RecordingExporter exporter;
  bake_scene(scene, mixed_recipe(2, 5), quiet_options(dir, {&exporter}));
  const nlohmann::json report = nlohmann::json::parse(read_bytes(dir / kBakeReportFile));
  ASSERT_EQ(report["frames"].size(), 5u);
  // Frame 1 is simulated but not written; checkpoints (all of one size) follow frames 4 and 5.
  const std::uint64_t checkpoint = fs::file_size(dir / kCheckpointFile);
  for (const auto& f : report["frames"]) {
    const int frame = f["frame"].get<int>();
    std::uint64_t expected = 0;
    if (frame >= 2)
      expected += fs::file_size(dir / frame_file_name("particles", frame, "ply")) +
                  fs::file_size(dir / exporter.files(frame)[0]);
    if (frame >= 4) expected += checkpoint;
    EXPECT_EQ(f["bytes_written"].get<std::uint64_t>(), expected) << "frame " << frame;
    EXPECT_GE(f["export_ms"].get<double>(), 0.0) << "frame " << frame;
  }
}

TEST(Bake, FailedWriteKeepsTheLastFrameAndCheckpoint) {
  const SceneDef scene = mixed_scene({"output.checkpoint_every=2"});
  const std::vector<std::string> overrides = {"output.checkpoint_every=2"};
  const fs::path dir = fresh_dir("failed"), reference = fresh_dir("failed_reference");
  // A folder where frame 5's file should go: its rename fails, like a full disk would.
  fs::create_directories(dir / "particles.0005.ply" / "blocker");
  try {
    bake_scene(scene, mixed_recipe(1, 8, overrides), quiet_options(dir));
    ADD_FAILURE() << "the bake did not report the failed write";
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find((dir / "particles.0005.ply").string()), std::string::npos) << what;
    EXPECT_NE(what.find("frames up to 4 are complete"), std::string::npos) << what;
    EXPECT_NE(what.find("checkpoint of frame 4"), std::string::npos) << what;
    EXPECT_NE(what.find("seiche bake --resume"), std::string::npos) << what;
  }
  EXPECT_TRUE(fs::exists(dir / "particles.0004.ply"));
  EXPECT_EQ(read_checkpoint(dir / kCheckpointFile).frame, 4);
  expect_no_temporary_files(dir);

  fs::remove_all(dir / "particles.0005.ply");
  BakeOptions resume = quiet_options(dir);
  resume.resume = true;
  const BakeRecipe recipe = read_bake_recipe(dir);
  EXPECT_EQ(
      bake_scene(load_recipe_scene(recipe, dir / kBakeRecipeFile), recipe, resume).start_frame, 4);
  bake_scene(scene, mixed_recipe(1, 8, overrides), quiet_options(reference));
  for (int f = 1; f <= 8; ++f) {
    const std::string name = frame_file_name("particles", f, "ply");
    EXPECT_TRUE(read_bytes(dir / name) == read_bytes(reference / name)) << name;
  }
}

TEST(Bake, UnwritableFolderFailsBeforeSimulating) {
  RecordingExporter exporter;
  EXPECT_THROW(
      bake_scene(mixed_scene(), mixed_recipe(1, 3), quiet_options("/dev/null/seiche", {&exporter})),
      IoError);
  EXPECT_TRUE(exporter.frames.empty());
}

// ---- Output locations and an earlier bake in the folder ---------------------------------------

// An exporter whose file names leave the folder, as a cloth named "../x" would have before the
// names were checked at load.
class EscapingExporter : public RecordingExporter {
 public:
  explicit EscapingExporter(std::string stem) : stem_(std::move(stem)) {}
  std::vector<fs::path> files(int frame) const override { return {frame_file_name(stem_, frame, "txt")}; }

 private:
  std::string stem_;
};

TEST(Bake, AFileNameOutsideTheFolderFailsBeforeAnythingIsWritten) {
  const fs::path parent = fresh_dir("escape");
  for (const std::string& stem : {std::string("../escaped"), (parent / "absolute").string(), std::string("sub/dir")}) {
    const fs::path dir = parent / "out";
    EscapingExporter exporter(stem);
    try {
      bake_scene(mixed_scene(), mixed_recipe(1, 2), quiet_options(dir, {&exporter}));
      ADD_FAILURE() << stem << ": accepted";
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find("is not a plain file name inside the folder"), std::string::npos)
          << e.what();
    }
    EXPECT_TRUE(exporter.frames.empty()) << stem;
    EXPECT_FALSE(fs::exists(dir)) << stem << ": the folder was made";
    EXPECT_EQ(std::distance(fs::directory_iterator(parent), fs::directory_iterator()), 0) << stem;
  }
  // seiche run checks its exporters the same way (a cloth name set in code, past the loader).
  SceneDef cloth = load_scene_text(kClothScene, "hanging.json");
  cloth.cloths[0].name = "../escaped";
  RunOptions o;
  o.out_dir = parent / "run";
  o.frames = 1;
  EXPECT_THROW(run_scene(cloth, o), IoError);
  EXPECT_EQ(std::distance(fs::directory_iterator(parent), fs::directory_iterator()), 0);
}

TEST(Bake, OutputFileChecksRefuseFoldersAndUncreatableFiles) {
  const fs::path dir = fresh_dir("writable");
  EXPECT_NO_THROW(check_output_file_writable(dir / "new" / "report.json"));
  EXPECT_TRUE(fs::is_directory(dir / "new"));            // its folder is made, as the writer would
  EXPECT_FALSE(fs::exists(dir / "new" / "report.json"));  // but no file is left
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "new"), fs::directory_iterator()), 0);
  for (const fs::path& bad : {dir, dir / "", fs::path("."), fs::path("/proc/seiche.json"),
                              fs::path("/dev/null/x.json")})
    EXPECT_THROW(check_output_file_writable(bad), IoError) << bad;
  EXPECT_THROW(prepare_output_directory("/proc"), IoError);
  EXPECT_NO_THROW(check_file_name_inside(dir, "sail.0001.obj"));
  EXPECT_NO_THROW(check_file_name_inside(dir, "a..0001.obj"));
  for (const char* bad : {"", ".", "..", "../x.obj", "/x.obj", "a/b.obj"})
    EXPECT_THROW(check_file_name_inside(dir, bad), IoError) << bad;
}

TEST(Bake, ANewBakeRemovesTheEarlierBakesFramesOutsideItsRangeAndNothingElse) {
  const SceneDef scene = mixed_scene();
  const fs::path dir = fresh_dir("rebake"), clean = fresh_dir("rebake_clean");
  RecordingExporter first;
  bake_scene(scene, mixed_recipe(1, 6), quiet_options(dir, {&first}));
  write_bytes(dir / "particles.0005.ply.bak", "a user's copy");
  write_bytes(dir / "render.0005.png", "a render");
  write_bytes(dir / "particles.0007.ply", "past the earlier bake's range: not provably its frame");
  RecordingExporter second;
  std::ostringstream progress;
  BakeOptions o = quiet_options(dir, {&second});
  o.progress = &progress;
  bake_scene(scene, mixed_recipe(3, 4), o);
  EXPECT_NE(progress.str().find("removed 8 frame files of the earlier bake"), std::string::npos) << progress.str();
  for (int f = 1; f <= 6; ++f) {
    EXPECT_EQ(fs::exists(dir / frame_file_name("particles", f, "ply")), f == 3 || f == 4) << f;
    EXPECT_EQ(fs::exists(dir / frame_file_name("record", f, "txt")), f == 3 || f == 4) << f;
  }
  for (const char* kept : {"particles.0005.ply.bak", "render.0005.png", "particles.0007.ply"})
    EXPECT_TRUE(fs::exists(dir / kept)) << kept;
  for (const char* kept : {"particles.0005.ply.bak", "render.0005.png", "particles.0007.ply"}) fs::remove(dir / kept);
  RecordingExporter third;
  bake_scene(scene, mixed_recipe(3, 4), quiet_options(clean, {&third}));
  EXPECT_EQ(frame_files(dir), frame_files(clean));

  // A resume is the same bake: nothing is removed. A bake.json that records no range removes
  // nothing either, and says so.
  bake_scene(scene, mixed_recipe(1, 6), quiet_options(dir));
  BakeOptions resume = quiet_options(dir);
  resume.resume = true;
  write_bytes(dir / "particles.0009.ply", "kept");
  EXPECT_EQ(bake_scene(scene, mixed_recipe(1, 6), resume).status, BakeResult::Status::AlreadyComplete);
  write_bytes(dir / kBakeRecipeFile, R"({"first_frame": 1, "last_frame": 2.5})");
  std::ostringstream warned;
  o = quiet_options(dir);
  o.progress = &warned;
  bake_scene(scene, mixed_recipe(1, 2), o);
  EXPECT_NE(warned.str().find("records no valid frame range"), std::string::npos) << warned.str();
  for (int f = 1; f <= 6; ++f) EXPECT_TRUE(fs::exists(dir / frame_file_name("particles", f, "ply"))) << f;
}

// ---- Particles for ParaView: the .vtp frames and their series -----------------------------------

namespace {

const std::vector<std::string> kVtpOverrides = {R"(output.particle_formats=["ply", "vtp"])"};

// The frames particles.pvd lists, by the number in each file name, after checking that each
// listed time is that frame's (frame * frame_dt, as the simulation computes it).
std::vector<int> series_frames(const fs::path& dir, double frame_dt) {
  const std::string pvd = read_bytes(dir / "particles.pvd");
  std::vector<int> frames;
  for (std::size_t at = pvd.find("<DataSet "); at != std::string::npos; at = pvd.find("<DataSet ", at + 1)) {
    auto attribute = [&](const std::string& key) {
      const std::size_t start = pvd.find(key + "=\"", at) + key.size() + 2;
      return pvd.substr(start, pvd.find('"', start) - start);
    };
    const std::string file = attribute("file");
    const int frame = std::stoi(file.substr(std::string("particles.").size(), 4));
    EXPECT_EQ(file, frame_file_name("particles", frame, "vtp"));
    EXPECT_EQ(std::stod(attribute("timestep")), frame * frame_dt) << file;
    frames.push_back(frame);
  }
  EXPECT_TRUE(pvd.ends_with("</Collection>\n</VTKFile>\n")) << pvd;
  return frames;
}

std::vector<int> vtp_frames_on_disk(const fs::path& dir) {
  std::vector<int> frames;
  for (int f = 1; f <= 99; ++f)
    if (fs::exists(dir / frame_file_name("particles", f, "vtp"))) frames.push_back(f);
  return frames;
}

std::vector<int> frame_range(int first, int last) {
  std::vector<int> frames;
  for (int f = first; f <= last; ++f) frames.push_back(f);
  return frames;
}

}  // namespace

TEST(Bake, VtpSeriesListsTheFramesOnDiskThroughAnInterruptAKillAndTheResumes) {
  const SceneDef scene = mixed_scene(kVtpOverrides);
  const double dt = scene.solver.frame_dt;
  const fs::path straight_dir = fresh_dir("vtp_straight"), stopped_dir = fresh_dir("vtp_stopped");
  bake_scene(scene, mixed_recipe(1, 12, kVtpOverrides), quiet_options(straight_dir));
  EXPECT_EQ(series_frames(straight_dir, dt), frame_range(1, 12));
  EXPECT_EQ(vtp_frames_on_disk(straight_dir), frame_range(1, 12));

  // Interrupted after frame 6 (a checkpoint of its own): the series lists frames 1-6, all there.
  std::atomic<bool> stop{false};
  BakeOptions o = quiet_options(stopped_dir);
  o.interrupt = &stop;
  o.after_frame = [&](int f) {
    EXPECT_EQ(series_frames(stopped_dir, dt), frame_range(1, f)) << "after frame " << f;
    stop = f == 6;
  };
  EXPECT_EQ(bake_scene(scene, mixed_recipe(1, 12, kVtpOverrides), o).status, BakeResult::Status::Interrupted);
  EXPECT_EQ(series_frames(stopped_dir, dt), frame_range(1, 6));
  EXPECT_EQ(vtp_frames_on_disk(stopped_dir), frame_range(1, 6));

  // Resumed, then killed after frame 10's files, before its checkpoint (every 4: the last is 8).
  const BakeRecipe recipe = read_bake_recipe(stopped_dir);
  BakeOptions resume = quiet_options(stopped_dir);
  resume.resume = true;
  resume.after_frame = [&](int f) {
    if (f == 10) throw std::runtime_error("killed");
  };
  EXPECT_THROW(bake_scene(load_recipe_scene(recipe, stopped_dir / kBakeRecipeFile), recipe, resume),
               std::runtime_error);
  EXPECT_EQ(read_checkpoint(stopped_dir / kCheckpointFile).frame, 8);
  EXPECT_EQ(series_frames(stopped_dir, dt), frame_range(1, 10));
  EXPECT_EQ(vtp_frames_on_disk(stopped_dir), frame_range(1, 10));

  // The next resume starts from frame 8: the series lists 1-8 before anything else is written,
  // then grows frame by frame (9 and 10 are rewritten with the same bytes).
  resume.threads = 1;  // another thread count: still the same bytes
  resume.after_frame = [&](int f) { EXPECT_EQ(series_frames(stopped_dir, dt), frame_range(1, f)) << f; };
  const BakeResult last = bake_scene(load_recipe_scene(recipe, stopped_dir / kBakeRecipeFile), recipe, resume);
  EXPECT_EQ(last.start_frame, 8);
  EXPECT_EQ(last.status, BakeResult::Status::Complete);
  const auto a = frame_files(straight_dir), b = frame_files(stopped_dir);
  EXPECT_EQ(a.size(), 12u * 2 + 3);  // ply + vtp per frame, particles.pvd, checkpoint.bin, bake.json
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, bytes] : a) {
    ASSERT_TRUE(b.count(name)) << name;
    EXPECT_TRUE(b.at(name) == bytes) << name << " differs after the resumes";
  }
  expect_no_temporary_files(stopped_dir);
}

TEST(Bake, ANewBakeReplacesTheEarlierVtpFramesAndTheirSeries) {
  const SceneDef scene = mixed_scene(kVtpOverrides);
  const double dt = scene.solver.frame_dt;
  const fs::path dir = fresh_dir("vtp_rebake"), clean = fresh_dir("vtp_rebake_clean");
  bake_scene(scene, mixed_recipe(1, 6, kVtpOverrides), quiet_options(dir));
  ASSERT_EQ(series_frames(dir, dt), frame_range(1, 6));
  // Frames 3-4 again: before its first frame the series lists none of the earlier bake's.
  BakeOptions o = quiet_options(dir);
  o.after_frame = [&](int f) {
    EXPECT_EQ(series_frames(dir, dt), f < 3 ? std::vector<int>{} : frame_range(3, f)) << "after frame " << f;
    if (f < 3) {
      EXPECT_EQ(vtp_frames_on_disk(dir), frame_range(3, 4)) << "the earlier 1, 2, 5, 6 are removed";
    }
  };
  bake_scene(scene, mixed_recipe(3, 4, kVtpOverrides), o);
  EXPECT_EQ(series_frames(dir, dt), frame_range(3, 4));
  EXPECT_EQ(vtp_frames_on_disk(dir), frame_range(3, 4));
  bake_scene(scene, mixed_recipe(3, 4, kVtpOverrides), quiet_options(clean));
  EXPECT_EQ(frame_files(dir), frame_files(clean));
}

TEST(Bake, ParticleFormatsChooseTheParticleFiles) {
  // Only the .vtp: no PLY. The bake's summary names the series; particles = false writes none.
  const std::vector<std::string> vtp_only = {R"(output.particle_formats=["vtp"])"};
  const fs::path dir = fresh_dir("vtp_only"), none = fresh_dir("vtp_none");
  std::ostringstream summary;
  BakeOptions o = quiet_options(dir);
  o.summary = &summary;
  const BakeResult r = bake_scene(mixed_scene(vtp_only), mixed_recipe(1, 2, vtp_only), o);
  EXPECT_EQ(r.files_written, 4u);  // per frame the .vtp and the series
  EXPECT_FALSE(fs::exists(dir / "particles.0001.ply"));
  EXPECT_TRUE(fs::exists(dir / "particles.0002.vtp"));
  EXPECT_NE(summary.str().find("particles.0001.vtp .. particles.0002.vtp"), std::string::npos) << summary.str();
  EXPECT_NE(summary.str().find("particles.pvd"), std::string::npos) << summary.str();
  const std::vector<std::string> off = {R"(output.particle_formats=["vtp"])", "output.particles=false"};
  bake_scene(mixed_scene(off), mixed_recipe(1, 2, off), quiet_options(none));
  for (const char* name : {"particles.0001.vtp", "particles.0001.ply", "particles.pvd"})
    EXPECT_FALSE(fs::exists(none / name)) << name;

  // seiche run writes the formats the scene lists, the series included.
  RunOptions run;
  run.out_dir = fresh_dir("vtp_run");
  run.frames = 2;
  run_scene(mixed_scene(vtp_only), run);
  EXPECT_FALSE(fs::exists(run.out_dir / "particles.0001.ply"));
  EXPECT_EQ(read_bytes(run.out_dir / "particles.0002.vtp"), read_bytes(dir / "particles.0002.vtp"));
  EXPECT_EQ(read_bytes(run.out_dir / "particles.pvd"), read_bytes(dir / "particles.pvd"));
}

// ---- Input fingerprints and the memory estimate ----------------------------------------------

// bake.json records the OBJ files the scene refers to as the loader read them; a resume finds a
// changed file (size or hash), a file the scene no longer names, and a missing one.
TEST(InputFingerprint, RecordedWithTheRecipeAndComparedOnResume) {
  const fs::path dir = fresh_dir("inputs");
  const std::string cube = read_bytes(fs::path(SEICHE_SCENES_DIR) / "meshes" / "cube.obj");
  write_bytes(dir / "cube.obj", cube);
  const std::string scene_text = R"({ "name": "meshes", "domain": { "min": [-1,0,-1], "max": [1,2,1] },
    "colliders": [ { "sphere": { "center": [0,0.3,0], "radius": 0.1 } },
                   { "mesh": { "file": "cube.obj", "scale": 0.4, "translate": [0,0.5,0] } } ],
    "particles": [ { "x": [0,1.5,0] } ] })";
  const SceneDef scene = load_scene_text(scene_text, "meshes.json", {}, dir);
  const std::vector<InputFile> inputs = scene_input_files(scene);
  ASSERT_EQ(inputs.size(), 1u);
  EXPECT_EQ(inputs[0].json_path, "colliders[1].mesh.file");
  EXPECT_EQ(inputs[0].file, (dir / "cube.obj").string());
  EXPECT_EQ(inputs[0].bytes, cube.size());
  EXPECT_EQ(inputs[0].fnv1a64, fnv1a64(cube));  // the bytes the loader read

  BakeRecipe r = make_bake_recipe("meshes", "meshes.json", scene_text, {}, 1, 4);
  r.scene_dir = dir.string();
  r.inputs = inputs;
  write_file_atomically(dir / kBakeRecipeFile, encode_bake_recipe(r));
  const BakeRecipe back = read_bake_recipe(dir);
  EXPECT_EQ(back.inputs, inputs);
  EXPECT_TRUE(input_file_changes(back.inputs, scene_input_files(load_recipe_scene(back, dir / kBakeRecipeFile))).empty());

  // One byte more: the size and the hash differ, and the message names the file and the path.
  write_bytes(dir / "cube.obj", cube + "\n");
  const std::vector<InputFile> now = scene_input_files(load_recipe_scene(back, dir / kBakeRecipeFile));
  EXPECT_EQ(now[0].bytes, cube.size() + 1);
  const std::vector<std::string> changes = input_file_changes(back.inputs, now);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_NE(changes[0].find((dir / "cube.obj").string()), std::string::npos) << changes[0];
  EXPECT_NE(changes[0].find("colliders[1].mesh.file"), std::string::npos) << changes[0];
  EXPECT_THROW(check_inputs_unchanged(back.inputs, now, dir / kBakeRecipeFile, false, nullptr), ResumeError);
  std::ostringstream warning;
  EXPECT_NO_THROW(check_inputs_unchanged(back.inputs, now, dir / kBakeRecipeFile, true, &warning));
  EXPECT_NE(warning.str().find("changed"), std::string::npos) << warning.str();
  // A file no longer in the scene, and one not recorded.
  EXPECT_EQ(input_file_changes(back.inputs, {}).size(), 1u);
  EXPECT_EQ(input_file_changes({}, now).size(), 1u);

  fs::remove(dir / "cube.obj");
  try {
    check_recorded_inputs_present(back.inputs, dir / kBakeRecipeFile);
    ADD_FAILURE() << "a missing input was accepted";
  } catch (const ResumeError& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "cube.obj").string()), std::string::npos) << e.what();
  }
}

// The estimate's particle store is the store's bytes() once every pass has enabled its columns:
// the same column table (built-in, fluid and vorticity scratch, 3 reorder spares) times the
// same padded length, allocated once (Simulation reserves the count). It may
// only be above: the 3 spares are allocated at the store's first reorder (the fluid's grid sort),
// so a store that never reorders holds 13 of the estimate's 16 columns or more (at most 23 % over).
TEST(MemoryEstimate, ParticleStoreIsTheStoresBytes) {
  for (const char* name : {"dam_break.json", "cloth_drape.json", "shapes.json", "cloth_on_fluid.json"}) {
    const SceneDef scene = load_scene_file(fs::path(SEICHE_SCENES_DIR) / name);
    const MemoryEstimate e = estimate_scene_memory(scene);
    Simulation sim(scene);
    sim.step_frame();
    EXPECT_EQ(e.particles, sim.particles().size()) << name;
    const double store = double(sim.particles().bytes());
    EXPECT_GE(double(e.particle_store), store) << name;
    EXPECT_LE(double(e.particle_store), (scene.fluids.empty() ? 16.0 / 13.0 : 1.0) * store) << name;
    EXPECT_GE(e.total(), e.particle_store + kProcessBytes) << name;
  }
  // A 4096 x 4096 sheet (the largest resolution): 16.8M vertices, 33.5M triangles; its estimate
  // is computed from the definition, before any mesh exists.
  SceneDef big;
  big.domain.min = {-10, -10, -10};
  big.domain.max = {10, 10, 10};
  ClothDef sheet;
  sheet.sheet = SheetDef{};
  sheet.sheet->resolution = {4096, 4096};
  big.cloths.push_back(sheet);
  const MemoryEstimate e = estimate_scene_memory(big);
  EXPECT_EQ(e.particles, 4096u * 4096u);
  EXPECT_EQ(e.largest().json_path, "cloths[0].sheet.resolution");
  const double vertices = 4096.0 * 4096.0, triangles = 2.0 * 4095.0 * 4095.0;
  EXPECT_NEAR(double(e.total()),
              vertices * (16 * 4 + kExportBytesPerParticle + kClothBytesPerVertex) + triangles * kClothBytesPerTriangle +
                  double(kProcessBytes),
              0.001 * double(e.total()));
  EXPECT_THROW(check_scene_memory(big, "big.json", std::uint64_t(1) << 30), SceneError);
  // A frame's .vtp buffer beside the PLY's, or instead of it (output.particle_formats).
  const std::uint64_t n = 4096u * 4096u;
  big.output.particles_vtp = true;
  EXPECT_EQ(estimate_scene_memory(big).total(), e.total() + kVtpExportBytesPerParticle * n);
  big.output.particles_ply = false;
  EXPECT_EQ(estimate_scene_memory(big).total(), e.total() + kVtpExportBytesPerParticle * n - kExportBytesPerParticle * n);
}

TEST(MemoryEstimate, SizesParseAndPrint) {
  EXPECT_EQ(parse_memory_size("512M"), std::uint64_t(512) << 20);
  EXPECT_EQ(parse_memory_size("2G"), std::uint64_t(2) << 30);
  EXPECT_EQ(parse_memory_size("1.5GiB"), std::uint64_t(3) << 29);
  EXPECT_EQ(parse_memory_size("64kB"), std::uint64_t(64) << 10);
  EXPECT_EQ(parse_memory_size("1000000"), std::uint64_t(1000000));
  for (const char* bad : {"", "x", "-1G", "0", "12x", "1GG", "1e30"}) EXPECT_FALSE(parse_memory_size(bad)) << bad;
  EXPECT_EQ(format_memory_size(100), "100 B");
  EXPECT_EQ(format_memory_size(std::uint64_t(3) << 29), "1.5 GiB");
  EXPECT_EQ(format_memory_size(std::uint64_t(300) << 20), "300 MiB");
  const std::optional<std::uint64_t> available = available_memory();
  ASSERT_TRUE(available);  // Linux: /proc/meminfo
  EXPECT_GT(*available, 0u);
}

// substeps x iterations per frame up to 1e5 and that times the particles up to 1e11 pass; past
// either, the scene is refused unless the caller allows huge work.
TEST(MemoryEstimate, WorkBoundRefusesAbsurdSettingsUnlessAllowed) {
  SceneDef two = load_scene_file(fs::path(SEICHE_SCENES_DIR) / "seed_example.json");
  two.solver.substeps = 1000;
  two.solver.iterations = 100;  // 1e5: at the bound
  EXPECT_NO_THROW(check_scene_work(two, "two.json", false));
  two.solver.iterations = 101;
  try {
    check_scene_work(two, "two.json", false);
    ADD_FAILURE() << "1.01e5 iterations per frame were accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.json_path(), "solver.substeps");
    EXPECT_NE(e.problem().find("--allow-huge-work"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(check_scene_work(two, "two.json", true));
  // The dam break (37^3 particles): 8 substeps x up to 32 iterations (density_tolerance) pass;
  // 1000 x 20 (2e4 iterations, 1.0e9 particle-iterations per frame) too; at a spacing 10x finer
  // (370^3 particles, 1.0e12 particle-iterations per frame) it is refused.
  SceneDef dam = load_scene_file(fs::path(SEICHE_SCENES_DIR) / "dam_break.json");
  EXPECT_NO_THROW(check_scene_work(dam, "dam.json", false));
  EXPECT_EQ(estimate_scene_memory(dam).particles, 50653u);  // 37^3
  dam.solver.substeps = 1000;
  dam.solver.iterations = 20;
  dam.solver.density_tolerance = 0.0f;  // exactly 2e4 iterations per frame
  EXPECT_NO_THROW(check_scene_work(dam, "dam.json", false));
  dam.fluids[0].spacing = 0.0027f;
  EXPECT_EQ(estimate_scene_memory(dam).particles, 370u * 370u * 370u);
  EXPECT_THROW(check_scene_work(dam, "dam.json", false), SceneError);
  EXPECT_NO_THROW(check_scene_work(dam, "dam.json", true));
}
