#include "shape_family.hpp"

#include <algorithm>
#include <cmath>

#include "families/lattice.hpp"

namespace seiche {

namespace {
constexpr const char* kRotations = "shape.rotations";  // the checkpoint chunk of the rotations
}  // namespace

std::size_t ShapeFamily::particle_count(const SceneDef& scene) {
  std::size_t count = 0;
  for (const ShapeDef& s : scene.shapes) count += lattice_size(s.box, s.spacing);
  return count;
}

ShapeFamily::ShapeFamily(const SceneDef& scene, ParticleStore& store, std::size_t first)
    : store_(store),
      rest_x_(store.add_column<float>("shape.rest_x", ColumnKind::Constant)),
      rest_y_(store.add_column<float>("shape.rest_y", ColumnKind::Constant)),
      rest_z_(store.add_column<float>("shape.rest_z", ColumnKind::Constant)) {
  std::size_t k = first;
  clusters_.start.push_back(0);
  for (std::size_t c = 0; c < scene.shapes.size(); ++c) {
    const ShapeDef& s = scene.shapes[c];
    const float mass = s.density * s.spacing * s.spacing * s.spacing;
    const std::size_t begin = k;
    for_each_lattice_site(s.box, s.spacing, [&](float x, float y, float z) {
      store.x[k] = x, store.y[k] = y, store.z[k] = z;
      store.vx[k] = s.velocity[0], store.vy[k] = s.velocity[1], store.vz[k] = s.velocity[2];
      store.w[k] = 1.0f / mass;
      store.phase[k] = make_phase(Material::Shape, std::uint32_t(c));
      store.radius[k] = 0.5f * s.spacing;
      clusters_.particle.push_back(std::uint32_t(k));
      ++k;
    });
    // Equal masses: the rest centre of mass is the lattice's centroid (summed in double).
    double centre[3] = {0.0, 0.0, 0.0};
    for (std::size_t i = begin; i < k; ++i) centre[0] += store.x[i], centre[1] += store.y[i], centre[2] += store.z[i];
    const double count = double(std::max<std::size_t>(k - begin, 1));
    for (std::size_t i = begin; i < k; ++i) {
      rest_x_[i] = float(store.x[i] - centre[0] / count);
      rest_y_[i] = float(store.y[i] - centre[1] / count);
      rest_z_[i] = float(store.z[i] - centre[2] / count);
    }
    clusters_.start.push_back(std::uint32_t(clusters_.particle.size()));
    clusters_.stiffness.push_back(s.stiffness);
    clusters_.rotation.push_back(kernels::kIdentityRotation);
    spacing_.push_back(s.spacing);
  }
}

void ShapeFamily::add_passes(std::vector<Pass>& passes) {
  passes.push_back({"shape matching", Stage::Iterate, pass_order::kShapeMatching, true,
                    [this](const StepContext&) {
                      kernels::solve_shape_matching(particle_view(store_), rest(), clusters_);
                    }});
}

// The rigid fit of each cluster on the final positions x, and each particle's distance from it
// in units of its cluster's spacing. The fit runs on compact copies of the members (positions,
// inverse masses, rest offsets) and of the clusters, so that measuring changes nothing: not the
// store, not the rotations that warm-start the next solve.
void ShapeFamily::measure(FrameMetrics& m) {
  const ParticleStore& s = store_;
  const std::size_t members = clusters_.particle.size();
  std::vector<float> gx(members), gy(members), gz(members), w(members), rx(members), ry(members), rz(members);
  kernels::ShapeClusters fit = clusters_;
  for (std::size_t k = 0; k < members; ++k) {
    const std::uint32_t i = clusters_.particle[k];
    gx[k] = s.x[i], gy[k] = s.y[i], gz[k] = s.z[i], w[k] = s.w[i];
    rx[k] = rest_x_[i], ry[k] = rest_y_[i], rz[k] = rest_z_[i];
    fit.particle[k] = std::uint32_t(k);
  }
  for (float& stiffness : fit.stiffness) stiffness = 1.0f;
  kernels::ParticleView goal;
  goal.n = members;
  goal.px = gx.data(), goal.py = gy.data(), goal.pz = gz.data(), goal.w = w.data();
  kernels::solve_shape_matching(goal, {rx.data(), ry.data(), rz.data()}, fit);
  double sum = 0.0, worst = 0.0;
  for (std::size_t c = 0; c < fit.clusters(); ++c)
    for (std::uint32_t k = fit.start[c]; k < fit.start[c + 1]; ++k) {
      const std::uint32_t i = clusters_.particle[k];
      const double d = std::hypot(double(gx[k]) - s.x[i], double(gy[k]) - s.y[i], double(gz[k]) - s.z[i]) / spacing_[c];
      sum += d, worst = std::max(worst, d);
    }
  m.errors.push_back({"shape_error", "shape error", ErrorUnit::Ratio, members ? sum / double(members) : 0.0, worst});
}

void ShapeFamily::save_state(CheckpointChunks& chunks) const {
  chunks.put_values(kRotations, std::span<const kernels::Quaternion>(clusters_.rotation));
}

void ShapeFamily::restore_state(const CheckpointChunks& chunks) {
  chunks.get_values(kRotations, std::span<kernels::Quaternion>(clusters_.rotation));
}

}  // namespace seiche
