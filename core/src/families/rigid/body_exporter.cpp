// bodies.%04d.jsonl: every rigid body's transform and velocities per frame, and with
// output.body_meshes each body's surface in the world as <body name>.%04d.obj (body_exporter.hpp).
#include "seiche/body_exporter.hpp"

#include <fmt/format.h>

#include <cmath>

#include "body_surface.hpp"
#include "seiche/output_files.hpp"

namespace seiche {

namespace {

constexpr const char* kStem = "bodies";

// The shortest text that reads back to the same double; null for a non-finite value (JSON has
// no NaN: a run that produced one stops with exit 4, but the file stays valid JSON).
template <std::size_t N>
std::string json_numbers(const std::array<double, N>& values) {
  std::string out = "[";
  for (std::size_t k = 0; k < N; ++k) {
    if (k > 0) out += ", ";
    out += std::isfinite(values[k]) ? fmt::format("{}", values[k]) : "null";
  }
  return out + "]";
}

class BodyExporter final : public FrameExporter {
 public:
  explicit BodyExporter(const SceneDef& scene) : scene_(scene) {
    if (scene.output.body_meshes)
      for (const RigidBodyDef& b : scene.rigid_bodies) surfaces_.push_back(rigid::body_surface(b));
  }

  std::string name() const override { return "bodies"; }

  std::vector<std::filesystem::path> files(int frame) const override {
    std::vector<std::filesystem::path> names{frame_file_name(kStem, frame, "jsonl")};
    for (std::size_t k = 0; k < surfaces_.size(); ++k)
      names.push_back(frame_file_name(scene_.rigid_bodies[k].name, frame, "obj"));
    return names;
  }

  std::vector<EncodedFile> encode_frame(const FrameView& frame) const override {
    std::vector<EncodedFile> files{
        {frame_file_name(kStem, frame.frame, "jsonl"), encode_bodies_jsonl(scene_, frame.bodies)}};
    for (std::size_t k = 0; k < surfaces_.size() && k < frame.bodies.size(); ++k) {
      const std::string& body = scene_.rigid_bodies[k].name;
      files.push_back(
          {frame_file_name(body, frame.frame, "obj"), rigid::encode_body_obj(body, surfaces_[k], frame.bodies[k])});
    }
    return files;
  }

 private:
  SceneDef scene_;
  std::vector<rigid::BodySurface> surfaces_;  // body frame; empty without output.body_meshes
};

}  // namespace

std::string encode_bodies_jsonl(const SceneDef& scene, std::span<const BodyPose> bodies) {
  std::string out;
  for (std::size_t k = 0; k < bodies.size() && k < scene.rigid_bodies.size(); ++k) {
    const BodyPose& b = bodies[k];
    // Body names are plain file-name parts (the reader's rule): nothing in them needs escaping.
    out += fmt::format(R"({{"name": "{}", "position": {}, "orientation": {}, "velocity": {}, "angular_velocity": {}}})",
                       scene.rigid_bodies[k].name, json_numbers(b.position), json_numbers(b.orientation),
                       json_numbers(b.velocity), json_numbers(b.angular_velocity));
    out += '\n';
  }
  return out;
}

std::unique_ptr<FrameExporter> make_body_exporter(const SceneDef& scene) {
  if (scene.rigid_bodies.empty()) return nullptr;
  return std::make_unique<BodyExporter>(scene);
}

}  // namespace seiche
