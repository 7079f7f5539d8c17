#include "seiche/cloth_obj_exporter.hpp"

#include <algorithm>
#include <stdexcept>

#include "cloth_solver.hpp"
#include "seiche/output_files.hpp"

namespace seiche {

namespace {

// The cloths' vertices are one run of ids in the store, cloth after cloth in vertex order
// (family_registry.cpp): the run starts at the smallest id of a cloth particle. Not the store's
// last ids: shape particles come after the cloths.
class ClothObjExporter final : public FrameExporter {
 public:
  explicit ClothObjExporter(const SceneDef& scene) {
    for (std::size_t c = 0; c < scene.cloths.size(); ++c) {
      names_.push_back(scene.cloths[c].name);
      shapes_.push_back(build_cloth_shape(scene.cloths[c], c, scene.name));
      vertices_ += shapes_.back().mesh.vertex_count();
    }
  }

  std::string name() const override { return "cloth obj"; }

  static std::size_t first_cloth_id(const ParticleStore& s) {
    std::size_t first = s.size();
    for (std::size_t k = 0; k < s.size(); ++k) {
      if (phase_material(s.phase[k]) == Material::Cloth) {
        first = std::min(first, std::size_t(s.id[k]));
      }
    }
    return first;
  }

  std::vector<std::filesystem::path> files(int frame) const override {
    std::vector<std::filesystem::path> f;
    for (const std::string& n : names_) f.emplace_back(frame_file_name(n, frame, "obj"));
    return f;
  }

  std::vector<EncodedFile> encode_frame(const FrameView& frame) const override {
    const ParticleStore& s = frame.particles;
    const std::vector<std::uint32_t> index_of_id = s.index_of_id();
    std::size_t id = first_cloth_id(s);
    if (id + vertices_ > s.size()) throw std::logic_error("cloth obj: the store holds too few cloth vertices");
    std::vector<EncodedFile> out;
    std::vector<Vec3> positions;
    for (std::size_t c = 0; c < shapes_.size(); ++c) {
      const std::size_t n = shapes_[c].mesh.vertex_count();
      positions.resize(n);
      for (std::size_t v = 0; v < n; ++v, ++id) {
        const std::uint32_t k = index_of_id[id];
        positions[v] = {s.x[k], s.y[k], s.z[k]};
      }
      out.push_back({frame_file_name(names_[c], frame.frame, "obj"),
                     encode_cloth_obj(shapes_[c].mesh, positions)});
    }
    return out;
  }

 private:
  std::vector<std::string> names_;
  std::vector<ClothShape> shapes_;
  std::size_t vertices_ = 0;
};

}  // namespace

std::unique_ptr<FrameExporter> make_cloth_obj_exporter(const SceneDef& scene) {
  if (scene.cloths.empty()) return nullptr;
  return std::make_unique<ClothObjExporter>(scene);
}

}  // namespace seiche
