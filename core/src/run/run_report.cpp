#include "run_report.hpp"

#include <string>

#include <fmt/format.h>

#include "seiche/kernels/simd_info.hpp"

namespace seiche {

RunReport::RunReport(const SceneDef& scene, std::size_t particles, int frames, int threads,
                     const std::vector<std::string>& pipeline) {
  doc_["seiche_version"] = SEICHE_VERSION;
  doc_["simd"] = kernels::simd_description();
  doc_["scene"] = scene.name;
  doc_["settings"] = {{"particles", particles},
                      {"frames", frames},
                      {"frame_dt", scene.solver.frame_dt},
                      {"substeps", scene.solver.substeps},
                      {"iterations", scene.solver.iterations},
                      {"density_tolerance", std::stod(fmt::format("{}", scene.solver.density_tolerance))},
                      {"max_iterations", scene.solver.max_iterations},
                      {"threads", threads}};
  doc_["pipeline"] = pipeline;
  doc_["frames"] = nlohmann::json::array();
  doc_["status"] = "ok";
}

void RunReport::add_frame(const FrameMetrics& m, const PassTimer& timer) {
  nlohmann::json f;
  f["frame"] = m.frame;
  f["time"] = m.time;
  nlohmann::json pass_ms = nlohmann::json::object();
  double wall = 0.0;
  for (const auto& e : timer.entries()) {
    pass_ms[e.name] = e.frame_seconds * 1e3;
    wall += e.frame_seconds;
  }
  f["wall_ms"] = wall * 1e3;
  f["pass_ms"] = pass_ms;
  f["particles"] = m.particles;
  f["iterations"] = {{"mean", m.iterations_mean}, {"max", m.iterations_max}};
  for (const ErrorRow& e : m.errors) f[e.key] = {{"mean", e.mean}, {"max", e.max}};
  f["kinetic_energy"] = m.kinetic_energy;
  f["potential_energy"] = m.potential_energy;
  f["max_speed"] = m.max_speed;
  f["non_finite"] = m.non_finite;
  f["outside_domain"] = m.outside_domain;
  doc_["frames"].push_back(std::move(f));
}

void RunReport::add_frame_output(double export_ms, std::uint64_t bytes) {
  nlohmann::json& f = doc_["frames"].back();
  f["export_ms"] = export_ms;
  f["bytes_written"] = bytes;
}

void RunReport::set_frames(int frames) { doc_["settings"]["frames"] = frames; }

void RunReport::set_error(const std::string& message) {
  doc_["status"] = "error";
  doc_["error"] = message;
}

}  // namespace seiche
