// Shape matching as a family (core/src/families/shape/): a rigid box dropped onto a sphere
// tumbles, lands and comes to rest on the floor with its shape kept; the same bits at any thread
// count; a checkpoint continues bit for bit, its rotations chunk included.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "seiche/checkpoint.hpp"
#include "seiche/output_files.hpp"
#include "seiche/scene_loader.hpp"
#include "seiche/simulation.hpp"
#include "seiche/state_hash.hpp"
#include "seiche/thread_count.hpp"

using namespace seiche;
namespace fs = std::filesystem;

namespace {

// A 4 x 4 x 4 rigid box (0.2 m, 64 particles) falls from 0.3 m onto a sphere under one corner,
// tips over and slides to rest on the rough floor. At 16 substeps of 8 iterations the contacts
// and the shape converge together; at the defaults (8 x 2) a contact at one corner particle is
// resolved only 1/64 per iteration (the rigid projection spreads it over the body), the body
// sinks up to a sixth of a spacing into the sphere at impact and springs back with energy (up to
// 22 % within 5 frames at 8 x 4, 0.2 % at 16 x 8; docs/design.md, "Adding a constraint family").
constexpr const char* kBoxScene = R"({
  "solver": {"substeps": 16, "iterations": 8},
  "domain": {"min": [0, 0, 0], "max": [1, 1, 1], "friction": 0.6},
  "colliders": [{"sphere": {"center": [0.3, 0.0, 0.3], "radius": 0.15}, "friction": 0.3}],
  "shapes": [{"box": {"min": [0.3, 0.3, 0.3], "max": [0.5, 0.5, 0.5]}, "spacing": 0.05, "density": 500}]
})";
constexpr float kSpacing = 0.05f;

SceneDef box_scene() { return load_scene_text(kBoxScene, "box.json"); }

// Particle positions in id order (the store is not reordered without fluid, but a test should
// not rely on it).
std::vector<std::array<double, 3>> positions_by_id(const ParticleStore& s) {
  std::vector<std::array<double, 3>> p(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) p[std::size_t(s.id[i])] = {s.x[i], s.y[i], s.z[i]};
  return p;
}

double largest_distance_change(const std::vector<std::array<double, 3>>& a,
                               const std::vector<std::array<double, 3>>& b) {
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = i + 1; j < a.size(); ++j) {
      const double da = std::hypot(a[i][0] - a[j][0], a[i][1] - a[j][1], a[i][2] - a[j][2]);
      const double db = std::hypot(b[i][0] - b[j][0], b[i][1] - b[j][1], b[i][2] - b[j][2]);
      worst = std::max(worst, std::fabs(da - db));
    }
  return worst;
}

}  // namespace

TEST(ShapeMatching, FallingRigidBoxKeepsItsShapeAndComesToRest) {
  const SceneDef scene = box_scene();
  Simulation sim(scene);
  ASSERT_EQ(sim.particles().size(), 64u);
  const auto rest = positions_by_id(sim.particles());
  const FrameMetrics start = sim.state_metrics();
  const double energy_start = start.kinetic_energy + start.potential_energy;
  double worst_error = 0.0, worst_gain = 0.0;
  std::vector<double> energy{energy_start};
  FrameMetrics m;
  for (int f = 0; f < 150; ++f) {
    m = sim.step_frame();
    ASSERT_EQ(m.non_finite, 0u) << "frame " << m.frame;
    const ErrorRow* e = m.error("shape_error");
    ASSERT_NE(e, nullptr);
    worst_error = std::max(worst_error, e->max);
    energy.push_back(m.kinetic_energy + m.potential_energy);
    for (std::size_t back = 1; back <= 5 && back < energy.size(); ++back)  // the 1 % bar
      worst_gain = std::max(worst_gain, energy.back() / energy[energy.size() - 1 - back] - 1.0);
  }
  const auto now = positions_by_id(sim.particles());
  // Rigid: every one of the 2016 pairwise distances is its rest distance, to 0.5 % of a spacing
  // at rest, and no particle is more than 5 % of a spacing off the body's rigid fit through the
  // impacts (the last collision pass of a substep pushes the contact layer out after the shape
  // was matched).
  EXPECT_LT(largest_distance_change(rest, now), 0.005 * kSpacing);
  EXPECT_LT(worst_error, 0.05);
  EXPECT_LT(m.error("shape_error")->max, 0.005);
  EXPECT_LT(worst_gain, 0.01);
  // It tumbled: the edge along x at rest (particle 0 to particle 3) turned by more than 20 deg.
  const double edge[3] = {now[3][0] - now[0][0], now[3][1] - now[0][1], now[3][2] - now[0][2]};
  const double cos_turn = edge[0] / std::hypot(edge[0], edge[1], edge[2]);
  EXPECT_LT(cos_turn, std::cos(20.0 * 3.14159265358979 / 180.0));
  // At rest on the floor: slow, its lowest particle one radius above it, no energy gained.
  EXPECT_LT(m.max_speed, 0.05);
  double lowest = 1.0;
  for (const auto& p : now) lowest = std::min(lowest, p[1]);
  EXPECT_NEAR(lowest, 0.5 * kSpacing, 0.002);
  EXPECT_LT(m.kinetic_energy + m.potential_energy, energy_start);
}

TEST(ShapeMatching, SameBitsAtEveryThreadCount) {
  const SceneDef scene = box_scene();
  auto run = [&](int threads) {
    return run_with_threads(threads, [&] {
      Simulation sim(scene);
      for (int f = 0; f < 40; ++f) sim.step_frame(FrameMeasure::Skip);
      return state_hash(sim.particles());
    });
  };
  const std::uint64_t one = run(1);
  EXPECT_EQ(run(2), one);
  EXPECT_EQ(run(3), one);
}

TEST(ShapeMatching, CheckpointContinuesBitForBitWithItsRotations) {
  const SceneDef scene = box_scene();
  const fs::path dir = fs::temp_directory_path() / "seiche_shape_checkpoint";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path file = dir / "checkpoint.bin";
  Simulation straight(scene);
  for (int f = 0; f < 30; ++f) straight.step_frame();  // tumbling off the sphere
  write_file_atomically(file, encode_checkpoint(straight, 7));
  for (int f = 0; f < 10; ++f) straight.step_frame();

  const Checkpoint cp = read_checkpoint(file);
  // The rotations warm-start the next solve: where the search ends in its last bits depends on
  // where it starts, so an exact continuation needs them.
  const CheckpointChunks::Chunk* rotations = cp.chunks.find("shape.rotations");
  ASSERT_NE(rotations, nullptr);
  EXPECT_EQ(rotations->bytes.size(), 16u);  // one cluster, a float quaternion
  Simulation resumed(scene);
  restore_checkpoint(resumed, cp, 7, file);
  for (int f = 0; f < 10; ++f) resumed.step_frame();
  EXPECT_EQ(state_hash(resumed.particles()), state_hash(straight.particles()));

  fs::remove_all(dir);
}

TEST(ShapeMatching, BadShapesAreRefusedNamingTheField) {
  auto message = [](const std::string& shape) {
    try {
      load_scene_text(R"({"shapes": [)" + shape + "]}", "bad.json");
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string thin = message(R"({"box": {"min": [0.1, 0.1, 0.1], "max": [0.5, 0.12, 0.5]}})");
  EXPECT_NE(thin.find("shapes[0].box"), std::string::npos) << thin;
  EXPECT_NE(thin.find("holds no particles"), std::string::npos) << thin;
  const std::string outside = message(R"({"box": {"min": [0.5, 0.5, 0.5], "max": [1.5, 0.9, 0.9]}})");
  EXPECT_NE(outside.find("outside the domain"), std::string::npos) << outside;
  const std::string light =
      message(R"({"box": {"min": [0.1, 0.1, 0.1], "max": [0.2, 0.2, 0.2]}, "spacing": 0.01, "density": 1e-9})");
  EXPECT_NE(light.find("shapes[0].density"), std::string::npos) << light;
  const std::string soft = message(R"({"box": {"min": [0.1, 0.1, 0.1], "max": [0.2, 0.2, 0.2]}, "stiffness": 0})");
  EXPECT_NE(soft.find("shapes[0].stiffness"), std::string::npos) << soft;
  EXPECT_NE(message(R"({"box": {"min": [0, 0, 0], "max": [0.2, 0.2, 0.2]}, "density": 2e5})").find("density"),
            std::string::npos);
  const std::string many = message(R"({"box": {"min": [0, 0, 0], "max": [1, 1, 1]}, "spacing": 0.009})");
  EXPECT_NE(many.find("the limit is 1000000 per shape"), std::string::npos) << many;
}
