// The kernel families that bench_pbf (PBF density), bench_neighbor (grid + neighbor list) and
// bench_cloth_kernels (stretch, dihedral and isometric bending) do not cover, one kernel call per
// benchmark iteration, at 64k, 262k and 1M particles.
//
// Set-ups (fixed seeds; built once per size and kept, each benchmark run starts from a fresh
// copy of the particles, so that no run depends on what ran before):
//   block n:  n^3 particles, n = 40, 64, 100 (64,000 / 262,144 / 1,000,000), on bench_pbf's
//             lattice (spacing s = 0.05 m, compressed by 2 %, jittered by +-1 % of s), sorted into
//             cell order; velocities a smooth swirl of 1 m/s plus +-0.1 m/s noise; predicted
//             positions p = x + dt v, dt = 1/600 s; all free (w = 1), fluid.
//   sheet n:  n x n cloth vertices, n = 256, 512, 1024 (65,536 / 262,144 / 1,048,576), 1 cm apart
//             in the xz plane.
// Benchmarks, Args: n (as above), threads:
//   Predict, UpdateVelocities, DampVelocities (integrate.hpp) on block n. Damping alternates the
//     factors f and 1/f (f = exp(-1/s dt)) so that velocities neither decay to denormals nor grow.
//   Collisions (collisions.hpp) on block n, fluid radius s/2, against the domain box (shrunk by
//     s/2 so that the outer layer touches it), a tilted plane (cuts off the bottom quarter), a
//     sphere (r = 0.3 L, L = the block's side), a capsule (r = 0.15 L, across the block) and a
//     torus as an SDF sampled on 64^3 voxels spanning the block (every particle samples it);
//     friction 0.3 everywhere. in_contact: the fraction of particles the call moves.
//   CollisionsDomain: the same particles against the domain box alone (friction 0.3), what a
//     scene without colliders runs; the outer layer of the block touches it.
//   XsphViscosity, Vorticity (compute_vorticity), VorticityConfinement (its second pass) on
//     block n with bench_pbf's neighbor list (h = 2 s, about 31 neighbors) and volumes m / rho
//     from one PBF density pass; XSPH c = 0.01, confinement epsilon = 0.01; the vorticity the
//     second pass reads is the first pass's.
//   DistanceChains (distance_constraint.hpp) on block n in lattice order: the n^2 rows along x are
//     chains of n particles, n^2 (n - 1) stiff-ish links (compliance 1e-8 m/N, rest length s, so
//     every link is active), two colors; one XPBD iteration per call.
//   HeavyChainForest, HeavyChainGaussSeidel (distance_tree.hpp, distance_constraint.hpp), Args:
//     links n = 100, 1000, threads: one iteration of the raw distance family on the heavy
//     chain (make_heavy_chain: pinned at the top, its last particle 1000 times heavier, the
//     predicted positions jittered by +-1 % of a link), either the exact forest solve (one tree,
//     serial) or one colored Gauss-Seidel sweep (two colors, packing and unpacking the chain as
//     the iteration does); positions and multipliers restored before every call, untimed.
//   Tethers (tethers.hpp) on sheet n: the row z = 0 pinned, every other vertex tied to its 4
//     nearest pinned vertices (as cloth_solver.cpp does), max length its rest distance; the
//     predicted positions are stretched 3 % away from the pins and jittered by +-0.2 cm.
//     violated: the fraction of tethers longer than allowed.
//   ParticleContacts (particle_contacts.hpp) on two cloths of n x n/2 vertices (n^2 in all)
//     stacked 0.7 r apart (contact distance r = 1 cm, the cloths' thickness), jittered by
//     +-0.15 r, with the candidates the contact stage would find (a vertex and its 4 lattice
//     neighbors on the other cloth: those within 1.5 r), each pair listed from both sides;
//     friction 0.3 on a sideways substep motion of up to 0.05 r. active: the fraction of
//     candidate entries in contact.
//   ShapeMatching (shape_matching.hpp) on block n in lattice order, cut into rigid clusters of
//     4 x 4 x 4 particles (n^3 / 64 of them), rest shapes the lattice positions x; one projection
//     of every cluster per call on the predicted positions (the swirl moved them), restored
//     before every call, rotations warm-started from the previous call as in a substep.
//   Triad: the memory-bandwidth yardstick for the roofline in docs/performance.md, a STREAM-like
//     triad a[i] = b[i] + s c[i] on three float arrays of 64 MiB each (16 Mi elements, far past
//     the 32 MiB L3), split over the threads by tbb::parallel_for (static partition, the arrays
//     first touched the same way). bytes_per_second counts 12 bytes per element (read b and c,
//     write a; the write-allocate read of a is not counted, as STREAM does not).
//   Collisions, Tethers and ParticleContacts move the particles out of their contacts: their
//   predicted positions are restored before every call, outside the timing (PauseTiming), so
//   that every call sees the same contacts.
// Threads: 1, 2, 4, ... and std::thread::hardware_concurrency() (tbb::global_control).
// Reported: real time per call (ms); items_per_second (particles, or constraints: links,
// tethers, contact candidate entries); s_per_particle or s_per_constraint, the time per particle
// or constraint (seconds in CSV/JSON; the console shows it with an SI prefix: "3.1ns").
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <random>
#include <span>
#include <thread>
#include <vector>

#include "lattice_block.hpp"
#include "seiche/kernels/collisions.hpp"
#include "seiche/kernels/distance_constraint.hpp"
#include "seiche/kernels/distance_tree.hpp"
#include "seiche/kernels/shortest_path_forest.hpp"
#include "seiche/kernels/integrate.hpp"
#include "seiche/kernels/particle_contacts.hpp"
#include "seiche/kernels/pbf_density.hpp"
#include "seiche/kernels/shape_matching.hpp"
#include "seiche/kernels/tethers.hpp"
#include "seiche/kernels/vorticity_confinement.hpp"
#include "seiche/kernels/xsph_viscosity.hpp"
#include "seiche/neighbor/cell_grid.hpp"
#include "seiche/neighbor/neighbor_list.hpp"

using namespace seiche;

namespace {

constexpr float kSpacing = 0.05f;           // block lattice spacing (m)
constexpr float kRadius = 2.0f * kSpacing;  // SPH kernel radius h (m)
constexpr float kSheetSpacing = 0.01f;      // sheet vertex spacing (m)
constexpr float kDt = 1.0f / 600.0f;        // s: 60 fps, 10 substeps
constexpr float kFriction = 0.3f;

// ---- Particles ----------------------------------------------------------------------------------

struct Particles {
  std::vector<float> x, y, z, px, py, pz, vx, vy, vz, w;
  std::vector<float> radius;  // collision radii

  std::size_t size() const { return x.size(); }
  kernels::ParticleView view() {
    return {size(),    x.data(),  y.data(),  z.data(),  px.data(), py.data(),
            pz.data(), vx.data(), vy.data(), vz.data(), w.data(),  radius.data()};
  }
  void restore_predicted(const Particles& from) { px = from.px, py = from.py, pz = from.pz; }
};

// Block n (see the top of the file). cell_order: sorted by cell of h (as a fluid is); else in
// lattice order, x fastest.
Particles make_block(int n, bool cell_order) {
  Particles p;
  std::mt19937 rng(42);
  bench::append_jittered_lattice(n, kSpacing, rng, p.x, p.y, p.z);
  const std::size_t count = p.size();
  if (cell_order) bench::sort_by_cell(n * kSpacing, kRadius, p.x, p.y, p.z);
  const float side = n * kSpacing, k = 2.0f * std::numbers::pi_v<float> / side;
  std::uniform_real_distribution<float> noise(-0.1f, 0.1f);
  p.vx.resize(count), p.vy.resize(count), p.vz.resize(count);
  p.px.resize(count), p.py.resize(count), p.pz.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    p.vx[i] = std::sin(k * p.y[i]) + noise(rng);
    p.vy[i] = std::sin(k * p.z[i]) + noise(rng);
    p.vz[i] = std::sin(k * p.x[i]) + noise(rng);
    p.px[i] = p.x[i] + kDt * p.vx[i];
    p.py[i] = p.y[i] + kDt * p.vy[i];
    p.pz[i] = p.z[i] + kDt * p.vz[i];
  }
  p.w.assign(count, 1.0f);
  p.radius.assign(count, 0.0f);
  return p;
}

Particles make_cell_block(int n) { return make_block(n, true); }

// Appends a cols x rows sheet in the plane y = height, vertex (r, c) at (c, height, r) * spacing,
// at rest (p = x, v = 0), free.
void add_sheet(Particles& p, int cols, int rows, float height) {
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      p.x.push_back(c * kSheetSpacing), p.y.push_back(height), p.z.push_back(r * kSheetSpacing);
      p.px.push_back(p.x.back()), p.py.push_back(height), p.pz.push_back(p.z.back());
      p.vx.push_back(0.0f), p.vy.push_back(0.0f), p.vz.push_back(0.0f);
      p.w.push_back(1.0f);
      p.radius.push_back(0.0f);
    }
}

// ---- The set-ups of the benchmarks --------------------------------------------------------------

struct CollisionScene {
  Particles particles;
  std::vector<float> sdf_values;
  kernels::SdfGrid sdf;  // values -> sdf_values (a vector's buffer survives moves)
  kernels::CollisionParams params;
  float side = 0.0f;  // L (m)
  float in_contact = 0.0f;

  // The shapes point at `sdf`: made where the scene sits.
  std::array<kernels::CollisionShape, 4> shapes() const {
    using Kind = kernels::CollisionShape::Kind;
    const float L = side;
    std::array<kernels::CollisionShape, 4> s;
    const float tilt = 1.0f / std::sqrt(1.04f);  // plane normal (0.2, 1, 0) normalized
    s[0] = {Kind::Plane, {0.5f * L, 0.25f * L, 0.5f * L}, {0.2f * tilt, tilt, 0}, 0.0f, kFriction,
            nullptr};
    s[1] = {Kind::Sphere, {0.3f * L, 0.5f * L, 0.5f * L}, {0, 0, 0}, 0.3f * L, kFriction, nullptr};
    s[2] = {Kind::Capsule,
            {0.6f * L, 0.2f * L, 0.2f * L},
            {0.6f * L, 0.8f * L, 0.8f * L},
            0.15f * L,
            kFriction,
            nullptr};
    s[3] = {Kind::Sdf, {0, 0, 0}, {0, 0, 0}, 0.0f, kFriction, &sdf};
    return s;
  }
};

CollisionScene make_collision_scene(int n) {
  CollisionScene s;
  s.particles = make_block(n, true);
  const float L = s.side = n * kSpacing;
  for (int a = 0; a < 3; ++a)
    s.params.domain_min[a] = 0.5f * kSpacing, s.params.domain_max[a] = L - 0.5f * kSpacing;
  s.params.domain_friction = kFriction;
  s.particles.radius.assign(s.particles.size(), 0.5f * kSpacing);  // a fluid's particle radius
  // A torus around the y axis through (0.7, 0.6, 0.5) L: major radius 0.25 L, minor 0.1 L.
  constexpr int kVoxels = 64;
  s.sdf.voxel = L / (kVoxels - 1);
  for (int a = 0; a < 3; ++a) s.sdf.dims[a] = kVoxels;
  s.sdf_values.resize(std::size_t(kVoxels) * kVoxels * kVoxels);
  for (int k = 0; k < kVoxels; ++k)
    for (int j = 0; j < kVoxels; ++j)
      for (int i = 0; i < kVoxels; ++i) {
        const float x = i * s.sdf.voxel - 0.7f * L, y = j * s.sdf.voxel - 0.6f * L,
                    z = k * s.sdf.voxel - 0.5f * L;
        const float ring = std::hypot(x, z) - 0.25f * L;
        s.sdf_values[(std::size_t(k) * kVoxels + j) * kVoxels + i] = std::hypot(ring, y) - 0.1f * L;
      }
  s.sdf.values = s.sdf_values.data();
  // The fraction in contact: the particles one call moves.
  Particles probe = s.particles;
  const auto shapes = s.shapes();
  kernels::solve_collisions(probe.view(), s.params, shapes);
  std::size_t moved = 0;
  for (std::size_t i = 0; i < probe.size(); ++i)
    moved += probe.px[i] != s.particles.px[i] || probe.py[i] != s.particles.py[i] ||
             probe.pz[i] != s.particles.pz[i];
  s.in_contact = float(double(moved) / double(probe.size()));
  return s;
}

struct FluidBlock {
  Particles particles;
  neighbor::NeighborList list;
  std::vector<kernels::Float4> pos_volume, vel_volume;  // (x, y, z, m/rho), (vx, vy, vz, m/rho)
  std::vector<float> omega_x, omega_y, omega_z, omega_norm;

  kernels::NeighborSpan span() const { return {list.offsets.data(), list.indices.data()}; }
};

FluidBlock make_fluid_block(int n) {
  FluidBlock b;
  b.particles = make_block(n, true);
  Particles& p = b.particles;
  const std::size_t count = p.size();
  const float lo[3] = {0, 0, 0}, hi[3] = {n * kSpacing, n * kSpacing, n * kSpacing};
  neighbor::CellGrid grid;  // on the sorted positions: order() is the identity
  grid.build(neighbor::make_grid_spec(lo, hi, kRadius), p.x.data(), p.y.data(), p.z.data(), nullptr,
             count);
  neighbor::build_neighbor_list(grid, p.x.data(), p.y.data(), p.z.data(), count, kRadius, b.list);

  kernels::PbfParams prm;  // as bench_pbf
  prm.h = kRadius;
  prm.mass = float(1000.0 / kernels::lattice_kernel_sum(kSpacing, kRadius));
  prm.epsilon = float(0.01 * kernels::lattice_lambda_denominator(kSpacing, kRadius));
  prm.lambda_scale = float(1.0 / kernels::lattice_lambda_denominator(kSpacing, kRadius));
  b.pos_volume.resize(count), b.vel_volume.resize(count);
  for (std::size_t i = 0; i < count; ++i) b.pos_volume[i] = {p.x[i], p.y[i], p.z[i], 0.0f};
  std::vector<float> density(count), lambda(count);
  kernels::pbf_density_lambda(b.pos_volume.data(), b.span(), count, prm, density.data(),
                              lambda.data());
  for (std::size_t i = 0; i < count; ++i) {
    const float volume = prm.mass / density[i];
    b.pos_volume[i].w = volume;
    b.vel_volume[i] = {p.vx[i], p.vy[i], p.vz[i], volume};
  }
  b.omega_x.resize(count), b.omega_y.resize(count), b.omega_z.resize(count),
      b.omega_norm.resize(count);
  kernels::compute_vorticity(b.pos_volume.data(), b.vel_volume.data(), b.span(), count, kRadius,
                             b.omega_x.data(), b.omega_y.data(), b.omega_z.data());
  for (std::size_t i = 0; i < count; ++i)
    b.omega_norm[i] = std::sqrt(b.omega_x[i] * b.omega_x[i] + b.omega_y[i] * b.omega_y[i] +
                                b.omega_z[i] * b.omega_z[i]);
  return b;
}

struct Chains {
  Particles particles;
  kernels::DistanceConstraints links;
};

Chains make_chains(int n) {
  Chains c;
  c.particles = make_block(n, false);  // row (j, k) is particles [(k n + j) n, (k n + j + 1) n)
  std::vector<std::uint32_t> i, j;
  for (std::uint32_t row = 0; row < std::uint32_t(n) * n; ++row)
    for (std::uint32_t k = 0; k + 1 < std::uint32_t(n); ++k)
      i.push_back(row * n + k), j.push_back(row * n + k + 1);
  const std::vector<float> rest(i.size(), kSpacing), compliance(i.size(), 1e-8f);
  kernels::color_distance_constraints(i, j, rest, compliance, c.particles.size(), c.links);
  return c;
}

// The heavy chain at n links: n + 1 particles hanging straight down from a pinned first
// one, kSpacing apart, the last 1000 times heavier (w = 1e-3, the others 1); the predicted
// positions jittered by +-1 % of the link length in every direction, so that every link is off
// its rest length. As one forest (the raw distance family's default for a chain) and colored.
struct HeavyChain {
  Particles particles;
  kernels::DistanceConstraints links;
  kernels::DistanceForest forest;
};

HeavyChain make_heavy_chain(int n) {
  HeavyChain c;
  Particles& p = c.particles;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.01f * kSpacing, 0.01f * kSpacing);
  for (int k = 0; k <= n; ++k) {
    p.x.push_back(0.0f), p.y.push_back(-kSpacing * float(k)), p.z.push_back(0.0f);
    p.px.push_back(p.x.back() + jitter(rng)), p.py.push_back(p.y.back() + jitter(rng));
    p.pz.push_back(p.z.back() + jitter(rng));
    p.vx.push_back(0.0f), p.vy.push_back(0.0f), p.vz.push_back(0.0f);
    p.w.push_back(k == 0 ? 0.0f : k == n ? 1e-3f : 1.0f);
    p.radius.push_back(0.0f);
  }
  std::vector<std::uint32_t> i, j;
  std::vector<std::array<std::uint32_t, 2>> edges;
  for (std::uint32_t k = 0; k < std::uint32_t(n); ++k) i.push_back(k), j.push_back(k + 1), edges.push_back({k, k + 1});
  const std::vector<float> rest(i.size(), kSpacing), compliance(i.size(), 0.0f);
  const std::vector<std::uint32_t> source = kernels::color_distance_constraints(i, j, rest, compliance, p.size(), c.links);
  // The forest as the raw distance family grows it (distance_solver.cpp): from the pin.
  const std::vector<double> length(i.size(), double(kSpacing));
  std::vector<std::uint8_t> pinned(p.size(), 0), used(i.size(), 0);
  pinned[0] = 1;
  std::vector<kernels::ForestLinks> links(1);
  kernels::grow_shortest_path_forest(p.size(), edges, length, pinned, 0, 0, used, links[0]);
  c.forest = std::move(kernels::make_distance_forests(links, source)[0]);
  return c;
}

struct TetherSheet {
  Particles particles;
  kernels::Tethers tethers;
  float violated = 0.0f;
};

TetherSheet make_tether_sheet(int n) {
  constexpr std::size_t kPerVertex = 4;  // cloth_solver.cpp's kTethersPerVertex
  TetherSheet s;
  Particles& p = s.particles;
  add_sheet(p, n, n, 0.0f);
  std::fill_n(p.w.begin(), n, 0.0f);  // row 0: pinned vertices 0 .. n-1
  kernels::Tethers& t = s.tethers;
  t.start.push_back(0);
  std::vector<int> cols;
  for (int r = 1; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      cols.clear();  // the nearest pinned vertices: columns by |dc|, the lower first on ties
      auto take = [&](int col) {
        if (col >= 0 && col < n && cols.size() < kPerVertex) cols.push_back(col);
      };
      take(c);
      for (int dc = 1; dc <= 3; ++dc) take(c - dc), take(c + dc);
      for (int col : cols) {
        t.anchor.push_back(std::uint32_t(col));
        t.max_length.push_back(kSheetSpacing * std::hypot(float(col - c), float(r)));
      }
      t.particle.push_back(std::uint32_t(r * n + c));
      t.start.push_back(std::uint32_t(t.anchor.size()));
    }
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> jitter(-0.2f * kSheetSpacing, 0.2f * kSheetSpacing);
  for (std::size_t i = std::size_t(n); i < p.size(); ++i)
    p.px[i] += jitter(rng), p.py[i] += jitter(rng), p.pz[i] = 1.03f * p.pz[i] + jitter(rng);
  std::size_t violated = 0;
  for (std::size_t g = 0; g < t.groups(); ++g)
    for (std::uint32_t k = t.start[g]; k < t.start[g + 1]; ++k) {
      const std::uint32_t i = t.particle[g], a = t.anchor[k];
      violated +=
          std::hypot(p.px[i] - p.px[a], p.py[i] - p.py[a], p.pz[i] - p.pz[a]) > t.max_length[k];
    }
  s.violated = float(double(violated) / double(t.anchor.size()));
  return s;
}

struct ContactSheets {
  Particles particles;
  kernels::ParticleContacts contacts;
  float active = 0.0f;
};

ContactSheets make_contact_sheets(int n) {
  constexpr float kContact = kSheetSpacing;  // r: the cloths' thickness
  // A vertex's candidates on the other cloth: (row, column) offsets within 1.5 r.
  static constexpr std::array<int, 2> kStencil[] = {{0, 0}, {-1, 0}, {0, -1}, {0, 1}, {1, 0}};
  ContactSheets s;
  Particles& p = s.particles;
  const int cols = n, rows = n / 2;
  add_sheet(p, cols, rows, 0.0f);
  add_sheet(p, cols, rows, 0.7f * kContact);
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> jitter(-0.15f * kContact, 0.15f * kContact);
  std::uniform_real_distribution<float> motion(-0.05f * kContact, 0.05f * kContact);
  for (std::size_t i = 0; i < p.size(); ++i) {  // substep start x = p - a small sideways motion
    p.px[i] += jitter(rng), p.py[i] += jitter(rng), p.pz[i] += jitter(rng);
    p.x[i] = p.px[i] - motion(rng), p.y[i] = p.py[i], p.z[i] = p.pz[i] - motion(rng);
  }
  kernels::ParticleContacts& c = s.contacts;
  c.clear();
  const std::size_t per_sheet = std::size_t(cols) * rows;
  std::size_t active = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::size_t sheet = i / per_sheet, other = (1 - sheet) * per_sheet;
    const int r = int((i % per_sheet) / cols), col = int(i % cols);
    c.particle.push_back(std::uint32_t(i));
    for (const auto& [dr, dc] : kStencil) {
      if (r + dr < 0 || r + dr >= rows || col + dc < 0 || col + dc >= cols) continue;
      const std::size_t j = other + std::size_t(r + dr) * cols + std::size_t(col + dc);
      c.partner.push_back(std::uint32_t(j));
      c.distance.push_back(kContact);
      active += std::hypot(p.px[i] - p.px[j], p.py[i] - p.py[j], p.pz[i] - p.pz[j]) < kContact;
    }
    c.start.push_back(std::uint32_t(c.partner.size()));
  }
  s.active = float(double(active) / double(c.partner.size()));
  return s;
}

// ---- Benchmark plumbing -------------------------------------------------------------------------

// The set-up for size n, built on first use and kept until another size is asked for (a run
// calls a benchmark function several times; 1M-particle set-ups take a second or so).
template <auto make>
const auto& cached(int n) {
  using T = decltype(make(n));
  static std::unique_ptr<T> value;
  static int built = -1;
  if (built != n) value.reset(), value = std::make_unique<T>(make(n)), built = n;
  return *value;
}

// items_per_second and s_per_<unit> (seconds per particle or constraint, shown with an SI prefix:
// "3.1ns") for `items` particles or constraints per call.
void report(benchmark::State& state, double items, const char* counter) {
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(items));
  state.counters[counter] = benchmark::Counter(
      items, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

// Times `call` once per iteration.
template <class Call>
void time_calls(benchmark::State& state, Call&& call) {
  for (auto _ : state) {
    call();
    benchmark::ClobberMemory();
  }
}

// The same, restoring p's predicted positions from `setup` before every call (not timed).
template <class Call>
void time_calls_restoring(benchmark::State& state, Particles& p, const Particles& setup,
                          Call&& call) {
  for (auto _ : state) {
    state.PauseTiming();
    p.restore_predicted(setup);
    state.ResumeTiming();
    call();
    benchmark::ClobberMemory();
  }
}

tbb::global_control thread_limit(const benchmark::State& state) {
  return tbb::global_control(tbb::global_control::max_allowed_parallelism,
                             std::size_t(state.range(1)));
}

// ---- Benchmarks ---------------------------------------------------------------------------------

template <void (*kernel)(Particles&, bool)>
void BM_Integrate(benchmark::State& state) {
  const auto threads = thread_limit(state);
  Particles p = cached<make_cell_block>(int(state.range(0)));
  bool odd = false;
  time_calls(state, [&] { kernel(p, odd = !odd); });
  state.counters["particles"] = double(p.size());
  report(state, double(p.size()), "s_per_particle");
}

void predict(Particles& p, bool) {
  const float gravity[3] = {0.0f, -9.81f, 0.0f};
  kernels::predict_positions(p.view(), kDt, gravity);
}
void update(Particles& p, bool) { kernels::update_velocities(p.view(), kDt); }
void damp(Particles& p, bool odd) {
  const float f = std::exp(-1.0f * kDt);
  kernels::damp_velocities(p.view(), odd ? f : 1.0f / f);
}

void BM_Collisions(benchmark::State& state) {
  const auto threads = thread_limit(state);
  const CollisionScene& scene = cached<make_collision_scene>(int(state.range(0)));
  Particles p = scene.particles;
  const auto shapes = scene.shapes();
  time_calls_restoring(state, p, scene.particles,
                       [&] { kernels::solve_collisions(p.view(), scene.params, shapes); });
  state.counters["particles"] = double(p.size());
  state.counters["in_contact"] = scene.in_contact;
  report(state, double(p.size()), "s_per_particle");
}

// The domain alone: what a scene without colliders runs (the dam break, the cloth sheets).
void BM_CollisionsDomain(benchmark::State& state) {
  const auto threads = thread_limit(state);
  const CollisionScene& scene = cached<make_collision_scene>(int(state.range(0)));
  Particles p = scene.particles;
  time_calls_restoring(state, p, scene.particles,
                       [&] { kernels::solve_collisions(p.view(), scene.params, {}); });
  state.counters["particles"] = double(p.size());
  report(state, double(p.size()), "s_per_particle");
}

enum class FluidPass { Xsph, Vorticity, Confinement };

template <FluidPass pass>
void BM_Fluid(benchmark::State& state) {
  const auto threads = thread_limit(state);
  const FluidBlock& b = cached<make_fluid_block>(int(state.range(0)));
  const std::size_t n = b.particles.size();
  std::vector<float> ox(n), oy(n), oz(n);  // the output: new velocities, or omega
  time_calls(state, [&] {
    if constexpr (pass == FluidPass::Xsph)
      kernels::xsph_viscosity(b.pos_volume.data(), b.vel_volume.data(), b.span(), n, kRadius, 0.01f,
                              ox.data(), oy.data(), oz.data());
    if constexpr (pass == FluidPass::Vorticity)
      kernels::compute_vorticity(b.pos_volume.data(), b.vel_volume.data(), b.span(), n, kRadius,
                                 ox.data(), oy.data(), oz.data());
    if constexpr (pass == FluidPass::Confinement)  // adds to ox, oy, oz (never read back)
      kernels::apply_vorticity_confinement(
          b.pos_volume.data(), b.omega_norm.data(), b.omega_x.data(), b.omega_y.data(),
          b.omega_z.data(), b.span(), n, kRadius, 0.01f, kDt, ox.data(), oy.data(), oz.data());
  });
  state.counters["particles"] = double(n);
  state.counters["neighbors_per_particle"] = double(b.list.indices.size()) / double(n);
  report(state, double(n), "s_per_particle");
}

void BM_DistanceChains(benchmark::State& state) {
  const auto threads = thread_limit(state);
  Chains c = cached<make_chains>(int(state.range(0)));
  time_calls(state, [&] { kernels::solve_distance_constraints(c.particles.view(), c.links, kDt); });
  state.counters["particles"] = double(c.particles.size());
  state.counters["constraints"] = double(c.links.size());
  state.counters["colors"] = double(c.links.color_start.size() - 1);
  report(state, double(c.links.size()), "s_per_constraint");
}

// One iteration on the heavy chain: the exact forest solve (forest = true) or a colored
// Gauss-Seidel sweep on the columns (packing and unpacking the chain, as the iteration does when
// the forests run on the columns before it), from the same predicted positions and multipliers 0
// every call (restored untimed); tension 0 (the first substep's).
void BM_HeavyChain(benchmark::State& state, bool forest) {
  const auto threads = thread_limit(state);
  const HeavyChain& setup = cached<make_heavy_chain>(int(state.range(0)));
  HeavyChain c = setup;
  const std::vector<float> tension(c.links.size(), 0.0f);
  for (auto _ : state) {
    state.PauseTiming();
    c.particles.restore_predicted(setup.particles);
    std::fill(c.links.lambda.begin(), c.links.lambda.end(), 0.0f);
    state.ResumeTiming();
    if (forest)
      kernels::solve_distance_forest(c.particles.view(), c.links, c.forest, kDt, tension.data());
    else
      kernels::solve_distance_constraints(c.particles.view(), c.links, kDt);
    benchmark::ClobberMemory();
  }
  state.counters["constraints"] = double(c.links.size());
  report(state, double(c.links.size()), "s_per_constraint");
}

void BM_Tethers(benchmark::State& state) {
  const auto threads = thread_limit(state);
  const TetherSheet& s = cached<make_tether_sheet>(int(state.range(0)));
  Particles p = s.particles;
  time_calls_restoring(state, p, s.particles, [&] { kernels::solve_tethers(p.view(), s.tethers); });
  state.counters["particles"] = double(p.size());
  state.counters["constraints"] = double(s.tethers.anchor.size());
  state.counters["violated"] = s.violated;
  report(state, double(s.tethers.anchor.size()), "s_per_constraint");
}

void BM_ParticleContacts(benchmark::State& state) {
  const auto threads = thread_limit(state);
  const ContactSheets& s = cached<make_contact_sheets>(int(state.range(0)));
  Particles p = s.particles;
  std::vector<float> scratch;
  time_calls_restoring(state, p, s.particles, [&] {
    kernels::solve_particle_contacts(p.view(), s.contacts, kFriction, scratch);
  });
  state.counters["particles"] = double(p.size());
  state.counters["constraints"] = double(s.contacts.partner.size());
  state.counters["active"] = s.active;
  report(state, double(s.contacts.partner.size()), "s_per_constraint");
}

struct ShapeBlock {
  Particles particles;
  kernels::ShapeClusters clusters;
};

// Block n in lattice order (x fastest), the clusters its 4 x 4 x 4 sub-blocks.
ShapeBlock make_shape_block(int n) {
  ShapeBlock s{make_block(n, false), {}};
  const int cells = n / 4;
  for (int cz = 0; cz < cells; ++cz)
    for (int cy = 0; cy < cells; ++cy)
      for (int cx = 0; cx < cells; ++cx) {
        std::vector<std::uint32_t> members;
        for (int k = 0; k < 4; ++k)
          for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 4; ++i)
              members.push_back(std::uint32_t(((cz * 4 + k) * n + (cy * 4 + j)) * n + (cx * 4 + i)));
        double c[3] = {0, 0, 0};
        for (const std::uint32_t q : members) c[0] += s.particles.x[q], c[1] += s.particles.y[q], c[2] += s.particles.z[q];
        s.clusters.begin_cluster(1.0f);
        for (const std::uint32_t q : members)
          s.clusters.add_member(q, float(s.particles.x[q] - c[0] / 64), float(s.particles.y[q] - c[1] / 64),
                                float(s.particles.z[q] - c[2] / 64));
        s.clusters.end_cluster();
      }
  s.clusters.finish();
  return s;
}

void BM_ShapeMatching(benchmark::State& state) {
  const auto threads = thread_limit(state);
  const ShapeBlock& s = cached<make_shape_block>(int(state.range(0)));
  Particles p = s.particles;
  kernels::ShapeClusters clusters = s.clusters;
  time_calls_restoring(state, p, s.particles, [&] { kernels::solve_shape_matching(p.view(), clusters); });
  state.counters["particles"] = double(clusters.particle.size());
  state.counters["clusters"] = double(clusters.clusters());
  report(state, double(clusters.particle.size()), "s_per_particle");
}

// a[i] = b[i] + s c[i] over 64 MiB float arrays (see the top of the file). Args: elements, threads.
void BM_Triad(benchmark::State& state) {
  const auto threads = thread_limit(state);
  const std::size_t n = std::size_t(state.range(0));
  const auto static_split = [n](auto&& body) {
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, 1 << 16),
        [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); },
        tbb::static_partitioner());
  };
  std::unique_ptr<float[]> a(new float[n]), b(new float[n]), c(new float[n]);
  static_split([&](std::size_t i, std::size_t end) {  // first touch by the threads that use them
    for (; i < end; ++i) a[i] = 0.0f, b[i] = 1.0f, c[i] = 2.0f;
  });
  const float s = 3.0f;
  float* const pa = a.get();
  const float* const pb = b.get();
  const float* const pc = c.get();
  time_calls(state, [&] {
    static_split([&](std::size_t i, std::size_t end) {
      for (; i < end; ++i) pa[i] = pb[i] + s * pc[i];
    });
  });
  benchmark::DoNotOptimize(pa[n / 2]);
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(12 * n));
  state.counters["elements"] = double(n);
}

// Args: every size, with 1, 2, 4, ... threads and all of them.
void args(benchmark::internal::Benchmark* b, std::initializer_list<int> sizes) {
  const int all = int(std::max(1u, std::thread::hardware_concurrency()));
  for (int n : sizes) {
    for (int t = 1; t < all; t *= 2) b->Args({n, t});
    b->Args({n, all});
  }
  b->ArgNames({"n", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
}
void block_sizes(benchmark::internal::Benchmark* b) { args(b, {40, 64, 100}); }
void sheet_sizes(benchmark::internal::Benchmark* b) { args(b, {256, 512, 1024}); }
void chain_sizes(benchmark::internal::Benchmark* b) {
  args(b, {100, 1000});
  b->Unit(benchmark::kMicrosecond);
}
void triad_size(benchmark::internal::Benchmark* b) {
  args(b, {int((std::size_t(64) << 20) / sizeof(float))});  // 64 MiB per array
  b->ArgNames({"elements", "threads"});
}

}  // namespace

BENCHMARK_TEMPLATE(BM_Integrate, predict)->Name("Predict")->Apply(block_sizes);
BENCHMARK_TEMPLATE(BM_Integrate, update)->Name("UpdateVelocities")->Apply(block_sizes);
BENCHMARK_TEMPLATE(BM_Integrate, damp)->Name("DampVelocities")->Apply(block_sizes);
BENCHMARK(BM_Collisions)->Name("Collisions")->Apply(block_sizes);
BENCHMARK(BM_CollisionsDomain)->Name("CollisionsDomain")->Apply(block_sizes);
BENCHMARK_TEMPLATE(BM_Fluid, FluidPass::Xsph)->Name("XsphViscosity")->Apply(block_sizes);
BENCHMARK_TEMPLATE(BM_Fluid, FluidPass::Vorticity)->Name("Vorticity")->Apply(block_sizes);
BENCHMARK_TEMPLATE(BM_Fluid, FluidPass::Confinement)
    ->Name("VorticityConfinement")
    ->Apply(block_sizes);
BENCHMARK(BM_DistanceChains)->Name("DistanceChains")->Apply(block_sizes);
BENCHMARK_CAPTURE(BM_HeavyChain, forest, true)->Name("HeavyChainForest")->Apply(chain_sizes);
BENCHMARK_CAPTURE(BM_HeavyChain, gauss_seidel, false)->Name("HeavyChainGaussSeidel")->Apply(chain_sizes);
BENCHMARK(BM_Tethers)->Name("Tethers")->Apply(sheet_sizes);
BENCHMARK(BM_ParticleContacts)->Name("ParticleContacts")->Apply(sheet_sizes);
BENCHMARK(BM_ShapeMatching)->Name("ShapeMatching")->Apply(block_sizes);
BENCHMARK(BM_Triad)->Name("Triad")->Apply(triad_size);

BENCHMARK_MAIN();
