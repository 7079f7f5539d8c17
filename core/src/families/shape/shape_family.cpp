#include "shape_family.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

#include "families/shape/shape_sites.hpp"
#include "seiche/kernels/shape_plasticity.hpp"

namespace seiche {

namespace {
constexpr const char* kRotations = "shape.rotations";  // the checkpoint chunk of the rotations
constexpr const char* kPlastic = "shape.plastic";      // the chunk of the plastic deformations

// The multiples of h within [i - h, i + h]: the centres (along one axis) of the region clusters
// that hold cell i.
std::vector<std::int32_t> centres_around(std::int32_t i, std::int32_t h) {
  auto floor_div = [](std::int32_t a, std::int32_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); };
  std::vector<std::int32_t> centres;
  for (std::int32_t c = floor_div(i + h, h); c * h >= i - h; --c) centres.push_back(c * h);
  std::reverse(centres.begin(), centres.end());
  return centres;
}

// The pull of one iteration: `stiffness`, or with stiffness_per_substep the pull that, repeated
// over a substep's iterations, removes the fraction `stiffness` of a lone cluster's deviation:
// 1 - (1 - s)^(1 / iterations). std::pow runs once, here, not in the solve.
float iteration_stiffness(const ShapeDef& s, const SolverDef& solver) {
  if (!s.stiffness_per_substep) return s.stiffness;
  return float(1.0 - std::pow(1.0 - double(s.stiffness), 1.0 / double(solver.iterations)));
}

// Each cluster's size: the RMS distance of its members' rest positions from its rest centre of
// mass, sqrt(sum_k |q_k|^2 / n) (0 for an empty or one-point cluster).
std::vector<double> cluster_sizes(const kernels::ShapeClusters& clusters) {
  std::vector<double> sizes(clusters.clusters(), 0.0);
  for (std::size_t c = 0; c < clusters.clusters(); ++c) {
    double sum = 0.0;
    for (std::uint32_t k = clusters.start[c]; k < clusters.start[c + 1]; ++k)
      sum += double(clusters.rest_x[k]) * clusters.rest_x[k] + double(clusters.rest_y[k]) * clusters.rest_y[k] +
             double(clusters.rest_z[k]) * clusters.rest_z[k];
    const std::uint32_t n = clusters.start[c + 1] - clusters.start[c];
    sizes[c] = n > 0 ? std::sqrt(sum / double(n)) : 0.0;
  }
  return sizes;
}

}  // namespace

std::size_t ShapeFamily::particle_count(const SceneDef& scene) {
  std::size_t count = 0;
  for (const ShapeDef& s : scene.shapes) count += shape_site_count(s);
  return count;
}

ShapeFamily::ShapeFamily(const SceneDef& scene, ParticleStore& store, std::size_t first)
    : store_(store), first_id_(std::int32_t(first)) {
  std::size_t k = first;
  for (std::size_t c = 0; c < scene.shapes.size(); ++c) {
    ShapeDef s = scene.shapes[c];
    s.stiffness = iteration_stiffness(s, scene.solver);
    const ShapeSites sites = shape_sites(s, "shapes[" + std::to_string(c) + "]");
    const float mass = s.density * s.spacing * s.spacing * s.spacing;
    const std::size_t begin = k;
    for (const Vec3& x : sites.position) {
      store.x[k] = x[0], store.y[k] = x[1], store.z[k] = x[2];
      store.vx[k] = s.velocity[0], store.vy[k] = s.velocity[1], store.vz[k] = s.velocity[2];
      store.w[k] = 1.0f / mass;
      store.phase[k] = make_phase(Material::Shape, std::uint32_t(c));
      store.radius[k] = 0.5f * s.spacing;
      ++k;
    }
    const std::size_t clusters_before = clusters_.clusters();
    if (s.cluster_half_width > 0)
      add_region_clusters(s, sites, begin);
    else
      add_one_cluster(s, begin, k);
    for (std::size_t n = clusters_before; n < clusters_.clusters(); ++n) {
      clusters_.linear_blend[n] = s.linear_blend;
      clusters_.plasticity[n] = {s.yield, s.creep, s.max_plastic_strain};
    }
    plastic_ = plastic_ || s.creep > 0.0f;
  }
  clusters_.finish();
  size_ = cluster_sizes(clusters_);
}

// The body as one cluster. Equal masses: the rest centre of mass is the lattice's centroid
// (summed in double).
void ShapeFamily::add_one_cluster(const ShapeDef& s, std::size_t begin, std::size_t end) {
  const ParticleStore& store = store_;
  double centre[3] = {0.0, 0.0, 0.0};
  for (std::size_t i = begin; i < end; ++i) centre[0] += store.x[i], centre[1] += store.y[i], centre[2] += store.z[i];
  const double count = double(std::max<std::size_t>(end - begin, 1));
  clusters_.begin_cluster(s.stiffness);
  for (std::size_t i = begin; i < end; ++i)
    clusters_.add_member(std::uint32_t(i), float(store.x[i] - centre[0] / count), float(store.y[i] - centre[1] / count),
                         float(store.z[i] - centre[2] / count));
  clusters_.end_cluster();
}

// Overlapping clusters: one per centre cell (every h-th cell along each axis) that holds a
// particle within h cells, in centre order (z, y, x), members in particle order. A particle in
// N clusters weighs 1/N of its mass in each; a cluster's rest centre of mass uses those weights.
void ShapeFamily::add_region_clusters(const ShapeDef& s, const ShapeSites& sites, std::size_t begin) {
  const ParticleStore& store = store_;
  const std::int32_t h = s.cluster_half_width;
  using Entry = std::tuple<std::int32_t, std::int32_t, std::int32_t, std::uint32_t>;  // centre z, y, x, particle
  std::vector<Entry> entries;
  std::vector<std::uint32_t> memberships(sites.size(), 0);
  for (std::uint32_t p = 0; p < sites.size(); ++p) {
    const auto& cell = sites.cell[p];
    const auto cx = centres_around(cell[0], h), cy = centres_around(cell[1], h), cz = centres_around(cell[2], h);
    for (std::int32_t z : cz)
      for (std::int32_t y : cy)
        for (std::int32_t x : cx) entries.emplace_back(z, y, x, p);
    memberships[p] = std::uint32_t(cx.size() * cy.size() * cz.size());
  }
  std::sort(entries.begin(), entries.end());
  std::vector<std::vector<std::uint32_t>> members_of(sites.size());
  for (std::size_t e = 0; e < entries.size();) {
    std::size_t end = e;
    while (end < entries.size() && std::get<0>(entries[end]) == std::get<0>(entries[e]) &&
           std::get<1>(entries[end]) == std::get<1>(entries[e]) && std::get<2>(entries[end]) == std::get<2>(entries[e]))
      ++end;
    double weight = 0.0, centre[3] = {0.0, 0.0, 0.0};
    for (std::size_t m = e; m < end; ++m) {
      const std::uint32_t p = std::get<3>(entries[m]);
      const std::size_t i = begin + p;
      const double share = 1.0 / double(memberships[p]);
      weight += share;
      centre[0] += share * store.x[i], centre[1] += share * store.y[i], centre[2] += share * store.z[i];
    }
    for (double& v : centre) v /= weight;
    clusters_.begin_cluster(s.stiffness);
    clusters_.overlapping.back() = 1;
    for (std::size_t m = e; m < end; ++m) {
      const std::uint32_t p = std::get<3>(entries[m]);
      const std::size_t i = begin + p;
      members_of[p].push_back(std::uint32_t(clusters_.members()));
      clusters_.add_member(std::uint32_t(i), float(store.x[i] - centre[0]), float(store.y[i] - centre[1]),
                           float(store.z[i] - centre[2]), float(1.0 / double(memberships[p])));
    }
    clusters_.end_cluster();
    e = end;
  }
  if (clusters_.shared_start.empty()) clusters_.shared_start.push_back(0);
  for (std::uint32_t p = 0; p < sites.size(); ++p) {
    clusters_.shared_particle.push_back(std::uint32_t(begin + p));
    clusters_.shared_member.insert(clusters_.shared_member.end(), members_of[p].begin(), members_of[p].end());
    clusters_.shared_start.push_back(std::uint32_t(clusters_.shared_member.size()));
    clusters_.shared_stiffness.push_back(s.stiffness);
  }
}

void ShapeFamily::add_passes(std::vector<Pass>& passes) {
  passes.push_back({"shape matching", Stage::Iterate, pass_order::kShapeMatching, true,
                    [this](const StepContext&) { kernels::solve_shape_matching(particle_view(store_), clusters_); }});
  if (plastic_)
    passes.push_back({"shape plasticity", Stage::Update, pass_order::kShapePlasticity, true,
                      [this](const StepContext& c) {
                        kernels::update_shape_plasticity(particle_view(store_), clusters_, c.dt);
                      }});
}

// The rigid fit of each cluster on the final positions x, and the RMS distance of its members
// from it relative to the cluster's size (shape_family.hpp). The fit runs on compact copies of
// the members (positions, inverse masses; one copy per member, so overlapping clusters are fitted
// each on its own) and of the clusters, so that measuring changes nothing: not the store, not the
// rotations that warm-start the next solve.
void ShapeFamily::measure(FrameMetrics& m) {
  const ParticleStore& s = store_;
  const std::size_t members = clusters_.members();
  std::vector<float> gx(members), gy(members), gz(members), w(members);
  kernels::ShapeClusters fit = clusters_;
  for (std::size_t k = 0; k < members; ++k) {
    const std::uint32_t i = clusters_.particle[k];
    gx[k] = s.x[i], gy[k] = s.y[i], gz[k] = s.z[i], w[k] = s.w[i];
    fit.particle[k] = std::uint32_t(k);
  }
  for (float& stiffness : fit.stiffness) stiffness = 1.0f;
  for (float& beta : fit.linear_blend) beta = 0.0f;
  for (std::uint8_t& overlapping : fit.overlapping) overlapping = 0;
  fit.shared_particle.clear();
  kernels::ParticleView goal;
  goal.n = members;
  goal.px = gx.data(), goal.py = gy.data(), goal.pz = gz.data(), goal.w = w.data();
  kernels::solve_shape_matching(goal, fit);
  double sum = 0.0, worst = 0.0;
  for (std::size_t c = 0; c < fit.clusters(); ++c) {
    double squares = 0.0;
    for (std::uint32_t k = fit.start[c]; k < fit.start[c + 1]; ++k) {
      const std::uint32_t i = clusters_.particle[k];
      const double dx = double(gx[k]) - s.x[i], dy = double(gy[k]) - s.y[i], dz = double(gz[k]) - s.z[i];
      squares += dx * dx + dy * dy + dz * dz;
    }
    // A cluster of size 0 (one point, or every point at its centre) has no shape to keep: no error.
    const std::uint32_t n = fit.start[c + 1] - fit.start[c];
    const double error = n > 0 && size_[c] > 0.0 ? std::sqrt(squares / double(n)) / size_[c] : 0.0;
    sum += error, worst = std::max(worst, error);
  }
  const std::size_t clusters = fit.clusters();
  m.errors.push_back({"shape_error", "shape error", ErrorUnit::Ratio, clusters ? sum / double(clusters) : 0.0, worst});
}

void ShapeFamily::save_state(CheckpointChunks& chunks) const {
  chunks.put_values(kRotations, std::span<const kernels::Quaternion>(clusters_.rotation));
  if (plastic_) chunks.put_values(kPlastic, std::span<const kernels::Matrix3>(clusters_.plastic));
}

void ShapeFamily::restore_state(const CheckpointChunks& chunks) {
  chunks.get_values(kRotations, std::span<kernels::Quaternion>(clusters_.rotation));
  if (plastic_) chunks.get_values(kPlastic, std::span<kernels::Matrix3>(clusters_.plastic));
}

}  // namespace seiche
