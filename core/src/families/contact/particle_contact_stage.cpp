#include "particle_contact_stage.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include <tbb/parallel_for.h>

#include "families/fluid/fluid_ball_query.hpp"
#include "seiche/phase.hpp"

namespace seiche {

bool ParticleContactStage::shapes_touch(const SceneDef& scene) {
  return scene.shapes.size() > 1 || (!scene.shapes.empty() && (!scene.cloths.empty() || !scene.fluids.empty()));
}

bool ParticleContactStage::needed(const SceneDef& scene) {
  if (shapes_touch(scene)) return true;
  if (scene.cloths.empty()) return false;
  if (scene.cloths.size() > 1 || !scene.fluids.empty()) return true;
  return scene.cloths[0].self_collision;
}

ParticleContactStage::ParticleContactStage(const ClothSolver* cloth, const SceneDef& scene, float fluid_radius)
    : cloth_(cloth), fluid_radius_(fluid_radius), with_shapes_(shapes_touch(scene)) {
  for (std::size_t c = 0; cloth != nullptr && c < cloth->cloth_count(); ++c) {
    max_distance_ = std::max(max_distance_, cloth->thickness(c));
    friction_ = std::max(friction_, cloth->friction(c));
  }
  // Two shapes' particles touch at the sum of their radii (half their spacings): at most the
  // largest spacing.
  if (with_shapes_)
    for (const ShapeDef& shape : scene.shapes) max_distance_ = std::max(max_distance_, shape.spacing);
  shape_count_ = with_shapes_ ? scene.shapes.size() : 0;
  // Shapes and fluid: a shape particle near the fluid's box goes into the grid too.
  if (with_shapes_ && fluid_radius > 0.0f)
    for (const ShapeDef& shape : scene.shapes)
      fluid_reach_ = std::max(fluid_reach_, kCandidateMargin * (0.5f * shape.spacing + fluid_radius));
  for (int a = 0; a < 3; ++a) domain_min_[a] = scene.domain.min[a], domain_max_[a] = scene.domain.max[a];
}

// Calls visit(j, contact_distance) for every candidate partner of grid particle i (cloth or
// shape), grid partners first (in grid order), then, for a cloth particle, fluid partners (in the
// fluid grid's order).
template <class Visit>
void ParticleContactStage::visit_candidates(const ParticleStore& store, const Neighborhood* fluid,
                                            std::uint32_t i, Visit&& visit) const {
  const float xi = store.px[i], yi = store.py[i], zi = store.pz[i];
  if (!std::isfinite(xi) || !std::isfinite(yi) || !std::isfinite(zi)) return;
  const std::uint32_t ci = store.phase[i] >> 8;  // i's cloth or shape
  const bool i_cloth = phase_material(store.phase[i]) == Material::Cloth;
  const std::uint32_t vi = i_cloth ? std::uint32_t(store.id[i] - cloth_->first_id(ci)) : 0;
  const float ti = i_cloth ? cloth_->thickness(ci) : 0.0f;

  // With shapes in the grid or not (a compile-time flag, so that the cloth-only scan is the
  // cloth-only code).
  auto visit_grid = [&](std::uint32_t k, auto shapes_in_grid) {
    constexpr bool kShapes = decltype(shapes_in_grid)::value;
    const std::uint32_t j = grid_.order()[k];
    if (j == i) return;
    const std::uint32_t cj = store.phase[j] >> 8;
    bool same_cloth = false;
    float r;
    if (kShapes && !(i_cloth && phase_material(store.phase[j]) == Material::Cloth)) {
      // A shape with a cloth or with another shape: the sum of their collision radii (half a
      // shape's spacing, half a cloth's thickness). A shape's own particles never touch.
      if (!i_cloth && phase_material(store.phase[j]) == Material::Shape && cj == ci) return;
      r = store.radius[i] + store.radius[j];
    } else {
      same_cloth = cj == ci;
      if (same_cloth && !cloth_->self_collision(ci)) return;
      r = same_cloth ? ti : 0.5f * (ti + cloth_->thickness(cj));
    }
    const kernels::Float4& q = sorted_[k];
    const float dx = xi - q.x, dy = yi - q.y, dz = zi - q.z;
    const float reach = kCandidateMargin * r;
    if (!(dx * dx + dy * dy + dz * dz < reach * reach)) return;
    if (same_cloth && cloth_->adjacent(ci, vi, std::uint32_t(store.id[j] - cloth_->first_id(cj)))) return;
    visit(j, r);
  };

  // Grid partners: the grid's cells are at least twice the largest candidate distance, so the
  // 2 x 2 x 2 cells nearest to p_i hold every particle within it (a cell per axis on each side of
  // the cell boundary closest to p_i).
  {
    const neighbor::GridSpec& s = grid_.spec();
    const float p[3] = {xi, yi, zi};
    std::int32_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      const float u = (p[a] - s.origin[a]) / s.cell_size - 0.5f;
      const float first = std::clamp(std::floor(u), 0.0f, float(std::max(s.dims[a] - 2, 0)));
      lo[a] = std::int32_t(first);
      hi[a] = std::min(lo[a] + 1, s.dims[a] - 1);
    }
    auto scan = [&](auto shapes_in_grid) {
      for (std::int32_t z = lo[2]; z <= hi[2]; ++z)
        for (std::int32_t y = lo[1]; y <= hi[1]; ++y)
          for (std::int32_t x = lo[0]; x <= hi[0]; ++x) {
            const std::uint32_t cell = grid_.cell_index(x, y, z);
            for (std::uint32_t k = grid_.cell_begin(cell); k < grid_.cell_end(cell); ++k)
              visit_grid(k, shapes_in_grid);
          }
    };
    if (with_shapes_)
      scan(std::true_type{});
    else
      scan(std::false_type{});
  }
  if (!fluid || fluid->count() == 0 || (!i_cloth && fluid_reach_ == 0.0f)) return;

  // Fluid partners: the cells of the fluid grid within `cells` cells of p_i's cell. Contact
  // distance: a cloth particle's half thickness or a shape particle's radius (half its spacing),
  // plus the fluid particle's radius.
  const float r = (i_cloth ? 0.5f * ti : store.radius[i]) + fluid_radius_;
  const float reach = kCandidateMargin * r;
  for_each_fluid_particle_within(fluid->grid, store, xi, yi, zi, reach, [&](std::uint32_t j) { visit(j, r); });
}

void ParticleContactStage::find_candidates(const ParticleStore& store, const Neighborhood* fluid) {
  const std::size_t n = store.size();
  // The grid: cloth particles, and shape particles where shapes touch, sorted by cell into
  // sorted_ (the store stays as it is).
  if (with_shapes_) find_shape_partner_boxes(store);
  in_grid_.resize(n);
  grid_particles_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    const Material m = phase_material(store.phase[i]);
    const bool in = m == Material::Cloth || (with_shapes_ && m == Material::Shape && near_a_partner(store, i));
    in_grid_[i] = in ? 1 : 0;
    if (in) grid_particles_.push_back(std::uint32_t(i));
  }
  contacts_.clear();
  fluid_shape_.clear();
  if (grid_particles_.empty()) return;  // shapes far apart, no cloth: nothing to touch
  // The grid spans its particles' box (clamped to the domain grown by a cell: particles outside
  // share the border cells), with cells of twice the largest candidate distance (a query scans
  // 2 x 2 x 2 cells). A draped sheet fills its box sparsely, so the grid gets up to 32 cells per
  // particle before its cells grow.
  const float cell = 2.0f * kCandidateMargin * max_distance_;
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (std::uint32_t i : grid_particles_) {
    const float p[3] = {store.px[i], store.py[i], store.pz[i]};
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  }
  for (int a = 0; a < 3; ++a) {  // (NaN coordinates fail every comparison and leave lo/hi alone)
    lo[a] = std::max(lo[a], domain_min_[a]) - cell;
    hi[a] = std::min(hi[a], domain_max_[a]) + cell;
    if (!(lo[a] <= hi[a])) lo[a] = domain_min_[a], hi[a] = domain_max_[a];
  }
  const neighbor::GridSpec spec =
      neighbor::make_grid_spec(lo, hi, cell, std::max<std::size_t>(32 * grid_particles_.size(), 1 << 16));
  grid_.build(spec, store.px.data(), store.py.data(), store.pz.data(), in_grid_.data(), n);
  const std::size_t in_grid = grid_.num_in_grid();
  sorted_.resize(in_grid);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, in_grid, 4096), [&](const auto& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      const std::uint32_t j = grid_.order()[k];
      sorted_[k] = {store.px[j], store.py[j], store.pz[j], 0.0f};
    }
  });

  // Grid particles' lists, each in a fixed order, kMaxCandidates slots per particle.
  const std::size_t m = grid_particles_.size();
  std::vector<std::uint32_t>& count = count_;
  count.assign(m, 0);
  slot_partner_.resize(m * kMaxCandidates);
  slot_distance_.resize(m * kMaxCandidates);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 256), [&](const auto& r) {
    for (std::size_t g = r.begin(); g != r.end(); ++g) {
      std::uint32_t* partner = slot_partner_.data() + g * kMaxCandidates;
      float* distance = slot_distance_.data() + g * kMaxCandidates;
      std::uint32_t& n_g = count[g];
      visit_candidates(store, fluid, grid_particles_[g], [&](std::uint32_t j, float d) {
        if (n_g < kMaxCandidates) partner[n_g] = j, distance[n_g] = d, ++n_g;
      });
    }
  });

  // The contact list: grid particles with candidates, then the fluid particles they touch,
  // each fluid particle's cloth partners in cloth order (a transpose of the cloth lists). A shape
  // particle's fluid partners go to the momentum-keeping list instead (fluid_shape_).
  struct FluidPair {
    std::uint32_t fluid, cloth;
    float distance;
  };
  std::vector<FluidPair> fluid_pairs;
  std::vector<FluidShapePair> shape_pairs;
  for (std::size_t g = 0; g < m; ++g) {
    if (count[g] == 0) continue;
    const std::uint32_t i = grid_particles_[g];
    const bool i_shape = phase_material(store.phase[i]) == Material::Shape;
    const std::size_t entries_before = contacts_.partner.size();
    for (std::size_t e = g * kMaxCandidates; e < g * kMaxCandidates + count[g]; ++e) {
      const std::uint32_t j = slot_partner_[e];
      const bool j_fluid = phase_material(store.phase[j]) == Material::Fluid;
      if (i_shape && j_fluid) {
        shape_pairs.push_back({i, j, slot_distance_[e]});
        continue;
      }
      contacts_.partner.push_back(j);
      contacts_.distance.push_back(slot_distance_[e]);
      if (j_fluid) fluid_pairs.push_back({j, i, slot_distance_[e]});
    }
    if (contacts_.partner.size() == entries_before) continue;  // only fluid partners
    contacts_.particle.push_back(i);
    contacts_.start.push_back(std::uint32_t(contacts_.partner.size()));
  }
  if (!shape_pairs.empty()) build_fluid_shape_contacts(shape_pairs);
  std::stable_sort(fluid_pairs.begin(), fluid_pairs.end(),
                   [](const FluidPair& a, const FluidPair& b) { return a.fluid < b.fluid; });
  for (std::size_t e = 0; e < fluid_pairs.size(); ++e) {
    if (e == 0 || fluid_pairs[e].fluid != fluid_pairs[e - 1].fluid) {
      if (e > 0) contacts_.start.push_back(std::uint32_t(contacts_.partner.size()));
      contacts_.particle.push_back(fluid_pairs[e].fluid);
    }
    contacts_.partner.push_back(fluid_pairs[e].cloth);
    contacts_.distance.push_back(fluid_pairs[e].distance);
  }
  if (!fluid_pairs.empty()) contacts_.start.push_back(std::uint32_t(contacts_.partner.size()));
}

// The fluid-shape contacts from their pairs in shape order (each shape particle's fluid partners
// in the fluid grid's order): fluid-major by a stable sort, and each shape particle's entries.
void ParticleContactStage::build_fluid_shape_contacts(std::vector<FluidShapePair>& pairs) {
  std::vector<std::uint32_t> entry_of(pairs.size());  // pair (shape order) -> entry (fluid order)
  std::vector<std::uint32_t> order(pairs.size());
  for (std::size_t e = 0; e < pairs.size(); ++e) order[e] = std::uint32_t(e);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return pairs[a].fluid < pairs[b].fluid; });
  kernels::ParticleContacts& f = fluid_shape_.first;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const FluidShapePair& pair = pairs[order[k]];
    if (k > 0 && pair.fluid != pairs[order[k - 1]].fluid) f.start.push_back(std::uint32_t(f.partner.size()));
    if (k == 0 || pair.fluid != pairs[order[k - 1]].fluid) f.particle.push_back(pair.fluid);
    entry_of[order[k]] = std::uint32_t(f.partner.size());
    f.partner.push_back(pair.shape);
    f.distance.push_back(pair.distance);
  }
  f.start.push_back(std::uint32_t(f.partner.size()));
  for (std::size_t e = 0; e < pairs.size(); ++e) {
    if (e > 0 && pairs[e].shape != pairs[e - 1].shape)
      fluid_shape_.second_start.push_back(std::uint32_t(fluid_shape_.second_entry.size()));
    if (e == 0 || pairs[e].shape != pairs[e - 1].shape) fluid_shape_.second.push_back(pairs[e].shape);
    fluid_shape_.second_entry.push_back(entry_of[e]);
  }
  fluid_shape_.second_start.push_back(std::uint32_t(fluid_shape_.second_entry.size()));
}

// The boxes of the shapes (one each) and of all the cloth (the last), around their predicted
// positions, grown by the largest candidate distance; per shape, the other boxes its own meets.
void ParticleContactStage::find_shape_partner_boxes(const ParticleStore& store) {
  boxes_.assign(shape_count_ + 1, Box{});
  Box fluid_box;
  for (std::size_t i = 0; i < store.size(); ++i) {
    const Material m = phase_material(store.phase[i]);
    if (m == Material::Fluid && fluid_reach_ == 0.0f) continue;
    if (m != Material::Cloth && m != Material::Shape && m != Material::Fluid) continue;
    Box& box = m == Material::Fluid ? fluid_box
                                    : boxes_[m == Material::Cloth ? shape_count_ : std::size_t(store.phase[i] >> 8)];
    const float p[3] = {store.px[i], store.py[i], store.pz[i]};
    for (int a = 0; a < 3; ++a) box.lo[a] = std::min(box.lo[a], p[a]), box.hi[a] = std::max(box.hi[a], p[a]);
  }
  const float grow = kCandidateMargin * max_distance_;
  for (Box& box : boxes_)
    for (int a = 0; a < 3; ++a) box.lo[a] -= grow, box.hi[a] += grow;
  auto meet = [](const Box& a, const Box& b) {
    for (int k = 0; k < 3; ++k)
      if (!(a.lo[k] <= b.hi[k] && b.lo[k] <= a.hi[k])) return false;  // apart (or empty, or NaN)
    return true;
  };
  partner_boxes_.resize(shape_count_);
  for (std::size_t c = 0; c < shape_count_; ++c) {
    partner_boxes_[c].clear();
    for (std::size_t k = 0; k < boxes_.size(); ++k)
      if (k != c && meet(boxes_[c], boxes_[k])) partner_boxes_[c].push_back(std::uint32_t(k));
  }
  // The fluid's box, grown by the largest fluid-shape candidate distance, last: every shape's
  // partner (a shape particle inside it looks for fluid partners).
  if (fluid_reach_ > 0.0f) {
    for (int a = 0; a < 3; ++a) fluid_box.lo[a] -= fluid_reach_, fluid_box.hi[a] += fluid_reach_;
    boxes_.push_back(fluid_box);
    for (std::size_t c = 0; c < shape_count_; ++c) partner_boxes_[c].push_back(std::uint32_t(boxes_.size() - 1));
  }
}

// Whether shape particle i lies in the grown box of another shape or of the cloth: a particle
// outside every such box is farther than any candidate distance from every partner it could have.
bool ParticleContactStage::near_a_partner(const ParticleStore& store, std::size_t i) const {
  const float p[3] = {store.px[i], store.py[i], store.pz[i]};
  for (std::uint32_t k : partner_boxes_[store.phase[i] >> 8]) {
    const Box& box = boxes_[k];
    if (box.lo[0] <= p[0] && p[0] <= box.hi[0] && box.lo[1] <= p[1] && p[1] <= box.hi[1] && box.lo[2] <= p[2] &&
        p[2] <= box.hi[2])
      return true;
  }
  return false;
}

void ParticleContactStage::solve(const kernels::ParticleView& p) {
  if (contacts_.size() != 0) kernels::solve_particle_contacts(p, contacts_, friction_, scratch_);
  if (fluid_shape_.first.size() != 0) kernels::solve_sided_contacts(p, fluid_shape_, friction_, scratch_);
}

}  // namespace seiche
