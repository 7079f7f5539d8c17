// A consumer of the installed library (docs/api.md): loads a scene from JSON text with an
// override, steps it, reads particle columns by name, writes the last frame as PLY, and prints
// numbers a test checks. Usage: seiche_consumer OUT_DIR
//
// The scene is the PBD lecture's worked example (scenes/seed_example.json): one projection of a
// distance constraint of rest length 3 between a 10 kg particle at (5,3,2) and a 2 kg one at
// (1,5,6) moves them to (14/3, 19/6, 7/3) and (8/3, 25/6, 13/3); gravity is off, so the centre of
// mass (13/3, 10/3, 8/3) stays where it is while the pair then drifts and spins.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "seiche/seiche.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: seiche_consumer OUT_DIR\n");
    return 2;
  }
  const char* scene_json = R"({
    "name": "pair",
    "solver": { "frame_dt": 0.0166667, "substeps": 1, "iterations": 1, "gravity": [0, -9.81, 0] },
    "domain": { "min": [0, 0, 0], "max": [10, 10, 10] },
    "particles": [ { "x": [5, 3, 2], "mass": 10 }, { "x": [1, 5, 6], "mass": 2 } ],
    "distance_constraints": [ { "i": 0, "j": 1, "rest_length": 3, "compliance": 0 } ] })";
  try {
    const std::vector<std::string> overrides = {"solver.gravity=[0,0,0]"};
    const seiche::SceneDef scene = seiche::load_scene_text(scene_json, "<consumer>", overrides);
    seiche::Simulation sim(scene);
    const seiche::FrameMetrics first = sim.step_frame();
    const seiche::ParticleStore& p = sim.particles();
    const seiche::StoreColumn* x = p.find("x");  // a column by name (here the same as p.x)
    const std::vector<std::uint32_t> index_of_id = p.index_of_id();  // the store may be reordered
    for (std::uint32_t id = 0; id < index_of_id.size(); ++id) {
      const std::size_t i = index_of_id[id];
      std::printf("frame 1 particle %u: %.6f %.6f %.6f\n", id, p.x[i], p.y[i], p.z[i]);
    }
    for (int f = 2; f <= 10; ++f) sim.step_frame();
    double com[3] = {0, 0, 0}, mass = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double m = 1.0 / p.w[i];
      com[0] += m * p.x[i], com[1] += m * p.y[i], com[2] += m * p.z[i], mass += m;
    }
    const float dx = p.x[0] - p.x[1], dy = p.y[0] - p.y[1], dz = p.z[0] - p.z[1];
    std::printf("frame %d: distance %.6f, centre of mass %.6f %.6f %.6f, x column of %s\n", sim.frame(),
                std::sqrt(dx * dx + dy * dy + dz * dz), com[0] / mass, com[1] / mass, com[2] / mass,
                x && x->type() == seiche::ColumnType::F32 ? "float" : "?");
    const std::filesystem::path out = argv[1];
    seiche::prepare_output_directory(out);
    const std::filesystem::path ply = out / seiche::frame_file_name("particles", sim.frame(), "ply");
    seiche::write_file_atomically(ply, seiche::encode_particles_ply(p));
    const seiche::ErrorRow* distance_error = first.error("distance_error");
    std::printf("wrote %s; frame 1 distance error %.3g\n", ply.string().c_str(),
                distance_error ? distance_error->max : -1.0);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "seiche_consumer: %s\n", e.what());
    return 1;
  }
  return 0;
}
