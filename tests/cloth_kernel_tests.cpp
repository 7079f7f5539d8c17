// Cloth kernels: coloring, hinges and both bending models, tethers, particle contacts, the SDF
// grid, the capsule/SDF colliders and the distance forest's line search. Each against hand math,
// finite differences, physics or a plain scalar reference; raw arrays, no scene.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <numbers>
#include <random>
#include <vector>

#include "dense_distance_projection.hpp"
#include "seiche/kernels/collisions.hpp"
#include "seiche/kernels/dihedral_bending.hpp"
#include "seiche/kernels/distance_constraint.hpp"
#include "seiche/kernels/distance_tree.hpp"
#include "seiche/kernels/graph_coloring.hpp"
#include "seiche/kernels/hinges.hpp"
#include "seiche/kernels/isometric_bending.hpp"
#include "seiche/kernels/particle_contacts.hpp"
#include "seiche/kernels/sdf_grid.hpp"
#include "seiche/kernels/tethers.hpp"

using namespace seiche;
using namespace seiche::kernels;

namespace {

constexpr double kPi = std::numbers::pi;

// SoA particles, as the kernels see them.
struct Particles {
  std::vector<float> x, y, z, px, py, pz, vx, vy, vz, w;
  std::vector<float> radius;  // collision radii
  explicit Particles(std::size_t n, float r = 0.0f)
      : x(n),
        y(n),
        z(n),
        px(n),
        py(n),
        pz(n),
        vx(n),
        vy(n),
        vz(n),
        w(n, 1.0f),
        radius(n, r) {}
  std::size_t size() const { return x.size(); }
  void set(std::size_t i, double a, double b, double c) {
    x[i] = px[i] = float(a);
    y[i] = py[i] = float(b);
    z[i] = pz[i] = float(c);
  }
  std::array<double, 3> predicted(std::size_t i) const { return {px[i], py[i], pz[i]}; }
  ParticleView view() {
    return {x.size(),  x.data(),  y.data(),  z.data(),  px.data(), py.data(),
            pz.data(), vx.data(), vy.data(), vz.data(), w.data(),  radius.data()};
  }
  /// Positions at substep start become the predicted positions (for error metrics on x).
  void commit() { x = px, y = py, z = pz; }
  bool finite() const {
    for (std::size_t i = 0; i < size(); ++i)
      if (!std::isfinite(px[i]) || !std::isfinite(py[i]) || !std::isfinite(pz[i])) return false;
    return true;
  }
};

bool bit_identical(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

double wrap_angle(double a) {  // into (-pi, pi]
  while (a > kPi) a -= 2 * kPi;
  while (a <= -kPi) a += 2 * kPi;
  return a;
}

/// The dihedral angle of a hinge (a, b, c, d) from predicted positions, in double.
double hinge_angle(const Particles& p, std::uint32_t a, std::uint32_t b, std::uint32_t c,
                   std::uint32_t d) {
  const auto A = p.predicted(a), B = p.predicted(b), C = p.predicted(c), D = p.predicted(d);
  return dihedral_angle(A.data(), B.data(), C.data(), D.data());
}

/// A regular n x n vertex sheet in the xz plane (y = 0), triangles with alternating diagonals,
/// edges = the unique triangle edges, hinges = the interior edges with their wings, oriented as
/// hinges.hpp asks (triangle a, b, c and triangle b, a, d as the mesh orients them).
struct Sheet {
  std::vector<double> x, y, z;
  std::vector<std::uint32_t> edge_i, edge_j, hinges;  // hinges: 4 per hinge
  std::size_t hinge_count() const { return hinges.size() / 4; }
};

Sheet make_sheet(int n, double spacing) {
  Sheet s;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c)
      s.x.push_back(c * spacing), s.y.push_back(0.0), s.z.push_back(r * spacing);
  auto id = [n](int r, int c) { return std::uint32_t(r * n + c); };
  std::vector<std::array<std::uint32_t, 3>> tris;
  for (int r = 0; r + 1 < n; ++r)
    for (int c = 0; c + 1 < n; ++c) {
      const std::uint32_t v00 = id(r, c), v01 = id(r, c + 1), v10 = id(r + 1, c),
                          v11 = id(r + 1, c + 1);
      if ((r + c) % 2 == 0) {
        tris.push_back({v00, v10, v11}), tris.push_back({v00, v11, v01});
      } else {
        tris.push_back({v00, v10, v01}), tris.push_back({v01, v10, v11});
      }
    }
  // First triangle seen on an undirected edge: its directed edge (a, b) and third vertex c.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::array<std::uint32_t, 3>> open;
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
      const auto key = std::minmax(a, b);
      auto it = open.find(key);
      if (it == open.end()) {
        open[key] = {a, b, c};
        s.edge_i.push_back(a), s.edge_j.push_back(b);
      } else {
        const auto [a0, b0, c0] = it->second;  // this triangle runs b0 -> a0; its third is d
        s.hinges.insert(s.hinges.end(), {a0, b0, c0, c});
      }
    }
  return s;
}

Particles particles_of(const Sheet& s) {
  Particles p(s.x.size());
  for (std::size_t i = 0; i < s.x.size(); ++i) p.set(i, s.x[i], s.y[i], s.z[i]);
  return p;
}

// Checks a coloring: a permutation of the constraints, no two constraints of a color share a
// particle, input order kept inside a color, and greedy (a constraint of color k meets every
// lower color in an earlier constraint).
void expect_valid_coloring(const Coloring& col, const std::vector<std::uint32_t>& v,
                           std::size_t arity) {
  const std::size_t m = v.size() / arity;
  ASSERT_EQ(col.order.size(), m);
  ASSERT_EQ(col.color_start.front(), 0u);
  ASSERT_EQ(col.color_start.back(), m);
  std::vector<std::uint32_t> color_of(m, ~0u);
  for (std::size_t k = 0; k < col.colors(); ++k)
    for (std::uint32_t s = col.color_start[k]; s < col.color_start[k + 1]; ++s) {
      ASSERT_EQ(color_of[col.order[s]], ~0u) << "listed twice";
      color_of[col.order[s]] = std::uint32_t(k);
      if (s > col.color_start[k]) {
        EXPECT_LT(col.order[s - 1], col.order[s]) << "not stable";
      }
    }
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> seen;  // (color, particle)
  for (std::size_t c = 0; c < m; ++c)
    for (std::size_t s = 0; s < arity; ++s)
      EXPECT_EQ(seen[std::make_pair(color_of[c], v[c * arity + s])]++, 0)
          << "color " << color_of[c] << " shares a particle";
  for (std::size_t c = 0; c < m; ++c)
    for (std::uint32_t lower = 0; lower < color_of[c]; ++lower) {
      bool blocked = false;
      for (std::size_t e = 0; e < c && !blocked; ++e) {
        if (color_of[e] != lower) continue;
        for (std::size_t s = 0; s < arity && !blocked; ++s)
          for (std::size_t t = 0; t < arity; ++t) blocked |= v[e * arity + s] == v[c * arity + t];
      }
      EXPECT_TRUE(blocked) << "constraint " << c << " could take color " << lower;
    }
}

// ---- Coloring -----------------------------------------------------------------------------------

TEST(ClothColoring, NoColorSharesAParticleAndTheResultIsDeterministic) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::uint32_t> pick(0, 299);
  for (std::size_t arity : {1u, 3u, 4u}) {
    std::vector<std::uint32_t> v;
    for (int c = 0; c < 600; ++c) {
      std::array<std::uint32_t, 4> q{};
      for (std::size_t s = 0; s < arity; ++s) {
        do q[s] = pick(rng);  // distinct particles within a constraint
        while (std::find(q.begin(), q.begin() + s, q[s]) != q.begin() + s);
        v.push_back(q[s]);
      }
    }
    const Coloring a = color_constraints(v, arity, 300);
    expect_valid_coloring(a, v, arity);
    const Coloring b = color_constraints(v, arity, 300);
    EXPECT_EQ(a.order, b.order);
    EXPECT_EQ(a.color_start, b.color_start);
  }
  const Coloring none = color_constraints({}, 4, 10);
  EXPECT_EQ(none.colors(), 0u);
  EXPECT_TRUE(none.order.empty());
}

TEST(ClothColoring, MoreThan64Colors) {
  // 150 constraints that all touch particle 0 need 150 colors (three mask words).
  std::vector<std::uint32_t> v;
  for (std::uint32_t c = 0; c < 150; ++c) v.insert(v.end(), {0u, c + 1});
  v.insert(v.end(), {151u, 152u});  // independent: color 0
  const Coloring col = color_constraints(v, 2, 153);
  EXPECT_EQ(col.colors(), 150u);
  expect_valid_coloring(col, v, 2);
}

TEST(ClothColoring, HingesOfASheetAreColoredValidly) {
  const Sheet s = make_sheet(12, 0.1);
  const Coloring col = color_constraints(s.hinges, 4, s.x.size());
  expect_valid_coloring(col, s.hinges, 4);
  EXPECT_LE(col.colors(), 20u);  // a sheet's hinge graph has bounded degree
}

// The greedy distance coloring as it was written before color_constraints existed: the oracle
// that the distance constraints' coloring did not change.
std::vector<std::uint32_t> old_distance_coloring(const std::vector<std::uint32_t>& i,
                                                 const std::vector<std::uint32_t>& j,
                                                 std::size_t particle_count,
                                                 std::vector<std::uint32_t>& color_start) {
  const std::size_t m = i.size();
  std::vector<std::vector<std::uint64_t>> used(particle_count);
  std::vector<std::uint32_t> color(m);
  std::uint32_t num_colors = 0;
  for (std::size_t c = 0; c < m; ++c) {
    auto& ui = used[i[c]];
    auto& uj = used[j[c]];
    std::uint32_t k = 0;
    for (;; ++k) {
      const std::size_t word = k / 64;
      const std::uint64_t bit = std::uint64_t(1) << (k % 64);
      const bool in_i = word < ui.size() && (ui[word] & bit);
      const bool in_j = word < uj.size() && (uj[word] & bit);
      if (!in_i && !in_j) break;
    }
    const std::size_t word = k / 64;
    const std::uint64_t bit = std::uint64_t(1) << (k % 64);
    if (ui.size() <= word) ui.resize(word + 1, 0);
    if (uj.size() <= word) uj.resize(word + 1, 0);
    ui[word] |= bit;
    uj[word] |= bit;
    color[c] = k;
    num_colors = std::max(num_colors, k + 1);
  }
  color_start.assign(num_colors + 1, 0);
  for (std::size_t c = 0; c < m; ++c) ++color_start[color[c] + 1];
  for (std::uint32_t k = 0; k < num_colors; ++k) color_start[k + 1] += color_start[k];
  std::vector<std::uint32_t> source(m);
  std::vector<std::uint32_t> cursor(color_start.begin(), color_start.end() - 1);
  for (std::size_t c = 0; c < m; ++c) source[cursor[color[c]]++] = std::uint32_t(c);
  return source;
}

TEST(ClothColoring, DistanceColoringIsUnchanged) {
  std::mt19937 rng(3);
  const Sheet s = make_sheet(20, 0.05);
  std::vector<std::uint32_t> i = s.edge_i, j = s.edge_j;
  std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(s.x.size() - 1));
  for (int k = 0; k < 300; ++k)
    i.push_back(pick(rng)), j.push_back(pick(rng));  // random extra pairs
  for (std::uint32_t k = 0; k < 100; ++k)
    i.push_back(5), j.push_back(k + 10);  // a hub: > 64 colors
  const std::vector<float> rest(i.size(), 0.05f), compliance(i.size(), 0.0f);
  DistanceConstraints c;
  const auto source = color_distance_constraints(i, j, rest, compliance, s.x.size(), c);
  std::vector<std::uint32_t> color_start;
  const auto expected = old_distance_coloring(i, j, s.x.size(), color_start);
  EXPECT_EQ(source, expected);
  EXPECT_EQ(c.color_start, color_start);
  for (std::size_t k = 0; k < source.size(); ++k) {
    EXPECT_EQ(c.i[k], i[source[k]]);
    EXPECT_EQ(c.j[k], j[source[k]]);
  }
}

// ---- Hinges and the dihedral angle --------------------------------------------------------------

// A hinge with edge a = (0,0,0), b = (1,0,0), wing c at angle 0 in the xy plane (c = (0.4, 1, 0))
// and wing d rotated about the edge so that the dihedral angle is theta.
void set_hinge(Particles& p, double theta, double c_along = 0.4, double d_along = 0.7) {
  p.set(0, 0, 0, 0);
  p.set(1, 1, 0, 0);
  p.set(2, c_along, 1.0, 0.0);
  // Flat, d = (d_along, -1, 0); turning it by +theta about +x gives the angle +theta (checked
  // in DihedralAngleOfKnownHinges).
  p.set(3, d_along, -std::cos(theta), -std::sin(theta));
}

TEST(Hinges, DihedralAngleOfKnownHinges) {
  Particles p(4);
  for (double theta : {0.0, 0.3, -0.3, 1.2, -2.0, 3.0, -3.1}) {
    set_hinge(p, theta);
    EXPECT_NEAR(hinge_angle(p, 0, 1, 2, 3), theta, 1e-6) << theta;
    const float a[3] = {p.px[0], p.py[0], p.pz[0]}, b[3] = {p.px[1], p.py[1], p.pz[1]},
                c[3] = {p.px[2], p.py[2], p.pz[2]}, d[3] = {p.px[3], p.py[3], p.pz[3]};
    EXPECT_NEAR(dihedral_angle(a, b, c, d), theta, 1e-5) << theta;
  }
  // Swapping the wings (c <-> d) with the edge reversed describes the same hinge.
  set_hinge(p, 0.8);
  EXPECT_NEAR(hinge_angle(p, 1, 0, 3, 2), 0.8, 1e-6);
  // Degenerate: zero-length edge, zero-area wing.
  const double o[3] = {0, 0, 0}, x1[3] = {1, 0, 0}, on_edge[3] = {0.5, 0, 0}, up[3] = {0.5, 1, 0},
               down[3] = {0.5, -1, 0.3};
  EXPECT_EQ(dihedral_angle(o, o, up, down), 0.0);
  EXPECT_EQ(dihedral_angle(o, x1, on_edge, down), 0.0);
  EXPECT_EQ(dihedral_angle(o, x1, up, on_edge), 0.0);
}

TEST(Hinges, RemapAndBendingError) {
  Particles p(4);
  set_hinge(p, 0.0);
  Hinges h;
  const std::vector<std::uint32_t> v = {0, 1, 2, 3};
  build_hinges(v, p.view(), h);
  ASSERT_EQ(h.size(), 1u);
  EXPECT_EQ(h.rest_angle[0], 0.0f);
  set_hinge(p, 0.5);
  p.commit();
  BendingError e = bending_error(p.view(), h);
  EXPECT_NEAR(e.mean, 0.5, 1e-6);
  EXPECT_NEAR(e.max, 0.5, 1e-6);
  // Across +-pi the error is the short way round.
  h.rest_angle[0] = float(-kPi + 0.1);
  set_hinge(p, kPi - 0.1);
  p.commit();
  e = bending_error(p.view(), h);
  EXPECT_NEAR(e.max, 0.2, 1e-6);
  // Remap: new_index[old] = new.
  const std::vector<std::uint32_t> new_index = {3, 2, 1, 0};
  h.remap(new_index);
  EXPECT_EQ(h.a[0], 3u);
  EXPECT_EQ(h.b[0], 2u);
  EXPECT_EQ(h.c[0], 1u);
  EXPECT_EQ(h.d[0], 0u);
}

// The bending error computes its angles lane = hinge (xsimd, double): against dihedral_angle hinge
// by hinge on random hinges, degenerate ones (a zero-length edge, a flat wing) and rest angles
// near +-pi included, over several blocks and a partial last batch; the same bits with 1 and 2
// threads.
TEST(Hinges, BendingErrorMatchesTheScalarAnglesAndIsThreadCountFree) {
  const std::size_t n = 3000, m = 9001;
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(n - 1));
  Particles p(n);
  for (std::size_t i = 0; i < n; ++i) p.set(i, u(rng), u(rng), u(rng));
  p.set(1, 0.5, 0.25, 0.0), p.set(2, 0.5, 0.25, 0.0), p.set(3, 1.5, 0.25, 0.0);  // 1-2 coincide
  Hinges h;
  for (std::size_t k = 0; k < m; ++k) {
    std::uint32_t v[4] = {pick(rng), pick(rng), pick(rng), pick(rng)};
    if (k == 5) v[0] = 1, v[1] = 2;              // zero-length edge
    if (k == 6) v[0] = 1, v[1] = 3, v[2] = 2;    // c on the edge: a flat wing
    h.a.push_back(v[0]), h.b.push_back(v[1]), h.c.push_back(v[2]), h.d.push_back(v[3]);
    h.rest_angle.push_back(float(k % 3 == 0 ? 3.1 * u(rng) : 0.5 * u(rng)));
  }
  double sum = 0.0, max = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    auto at = [&](std::uint32_t i) { return std::array<double, 3>{p.x[i], p.y[i], p.z[i]}; };
    const auto a = at(h.a[k]), b = at(h.b[k]), c = at(h.c[k]), d = at(h.d[k]);
    double err = std::abs(dihedral_angle(a.data(), b.data(), c.data(), d.data()) - double(h.rest_angle[k]));
    if (err > std::numbers::pi) err = 2.0 * std::numbers::pi - err;
    sum += err, max = std::max(max, err);
  }
  BendingError one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = bending_error(p.view(), h);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = bending_error(p.view(), h);
  }
  EXPECT_NEAR(one.mean, sum / double(m), 1e-12);
  EXPECT_NEAR(one.max, max, 1e-12);
  EXPECT_GT(one.mean, 0.1);  // the hinges are far from their rest angles: a real check
  EXPECT_EQ(std::memcmp(&one, &two, sizeof(one)), 0);
}

// ---- Dihedral bending -------------------------------------------------------------------------

// Central finite differences of the (double) dihedral angle with respect to vertex v, axis k.
double fd_angle(const std::array<std::array<double, 3>, 4>& q, int v, int k, double h = 1e-6) {
  auto plus = q, minus = q;
  plus[v][k] += h, minus[v][k] -= h;
  const double ap = dihedral_angle(plus[0].data(), plus[1].data(), plus[2].data(), plus[3].data());
  const double am =
      dihedral_angle(minus[0].data(), minus[1].data(), minus[2].data(), minus[3].data());
  return wrap_angle(ap - am) / (2 * h);
}

// One zero-compliance dihedral step on a single hinge reveals the kernel's gradient:
// dp_i = w_i grad_i C dlambda and lambda = dlambda after the first step. Compared against
// finite differences of the angle, and dlambda against -C / sum_i w_i |grad_i C|^2 with C
// wrapped into (-pi, pi].
void check_dihedral_gradient(const std::array<std::array<double, 3>, 4>& q, double rest,
                             const char* what) {
  SCOPED_TRACE(what);
  Particles p(4);
  const float w[4] = {1.0f, 0.5f, 2.0f, 0.25f};  // unequal, so that each vertex's share shows
  for (int v = 0; v < 4; ++v) p.set(v, q[v][0], q[v][1], q[v][2]), p.w[v] = w[v];
  // Positions as the kernel sees them (float), in double for the finite differences.
  std::array<std::array<double, 3>, 4> qf;
  for (int v = 0; v < 4; ++v) qf[v] = p.predicted(v);
  const double theta = dihedral_angle(qf[0].data(), qf[1].data(), qf[2].data(), qf[3].data());

  Hinges h;
  const std::vector<std::uint32_t> verts = {0, 1, 2, 3};
  build_dihedral_bending(verts, std::vector<float>{0.0f}, p.view(), h);
  h.rest_angle[0] = float(rest);
  const double C = wrap_angle(theta - double(h.rest_angle[0]));

  double grad[4][3], denom = 0.0;
  for (int v = 0; v < 4; ++v)
    for (int k = 0; k < 3; ++k) {
      grad[v][k] = fd_angle(qf, v, k);
      denom += w[v] * grad[v][k] * grad[v][k];
    }
  const double expected_dlambda = -C / denom;

  solve_dihedral_bending(p.view(), h, 1.0f / 60.0f);
  const double dlambda = h.lambda[0];
  EXPECT_NEAR(dlambda, expected_dlambda, 1e-3 * std::abs(expected_dlambda));
  double gmax = 0.0;
  for (int v = 0; v < 4; ++v)
    for (int k = 0; k < 3; ++k) gmax = std::max(gmax, std::abs(grad[v][k]));
  for (int v = 0; v < 4; ++v) {
    const auto now = p.predicted(v);
    for (int k = 0; k < 3; ++k) {
      const double kernel_grad = (now[k] - qf[v][k]) / (w[v] * dlambda);
      EXPECT_NEAR(kernel_grad, grad[v][k], 1e-2 * gmax) << "vertex " << v << " axis " << k;
    }
  }
}

TEST(DihedralBending, GradientMatchesFiniteDifferences) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0;
  while (checked < 12) {
    std::array<std::array<double, 3>, 4> q;
    for (auto& v : q)
      for (auto& c : v) c = u(rng);
    // Keep well-shaped hinges (edge and wing heights not small): the check is about the
    // formula, not conditioning.
    const double e[3] = {q[1][0] - q[0][0], q[1][1] - q[0][1], q[1][2] - q[0][2]};
    const double el = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    auto height = [&](const std::array<double, 3>& x) {
      const double r[3] = {x[0] - q[0][0], x[1] - q[0][1], x[2] - q[0][2]};
      const double c[3] = {e[1] * r[2] - e[2] * r[1], e[2] * r[0] - e[0] * r[2],
                           e[0] * r[1] - e[1] * r[0]};
      return std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / el;
    };
    if (el < 0.5 || height(q[2]) < 0.3 || height(q[3]) < 0.3) continue;
    const double theta = dihedral_angle(q[0].data(), q[1].data(), q[2].data(), q[3].data());
    check_dihedral_gradient(q, wrap_angle(theta - 0.2), "random hinge");
    ++checked;
  }
}

TEST(DihedralBending, GradientNearPlusMinusPiWrapsTheConstraint) {
  // Nearly folded shut (theta close to +pi or -pi), with a rest angle on the other side of the
  // branch cut: C must be the short way round (|C| = 0.1), not ~2 pi.
  for (double theta : {kPi - 0.05, -kPi + 0.05}) {
    Particles p(4);
    set_hinge(p, theta);
    std::array<std::array<double, 3>, 4> q;
    for (int v = 0; v < 4; ++v) q[v] = p.predicted(v);
    const double rest = theta > 0 ? -kPi + 0.05 : kPi - 0.05;
    check_dihedral_gradient(q, rest, theta > 0 ? "near +pi" : "near -pi");
  }
}

TEST(DihedralBending, BuildScalesComplianceByTheHingeShape) {
  Particles p(4);
  set_hinge(p, 0.3);
  Hinges h;
  build_dihedral_bending(std::vector<std::uint32_t>{0, 1, 2, 3}, std::vector<float>{2.0f}, p.view(),
                         h);
  // |e| = 1, A1 = A2 = 1/2 (base 1, height 1): alpha = 2 * 1 / 3.
  EXPECT_NEAR(h.compliance[0], 2.0f / 3.0f, 1e-6f);
  EXPECT_NEAR(h.rest_angle[0], 0.3f, 1e-6f);
  EXPECT_EQ(h.lambda[0], 0.0f);
  p.set(2, 0.5, 0.0, 0.0);  // wing c on the edge: degenerate rest, scaled as if |e|^2 = A1 + A2
  build_dihedral_bending(std::vector<std::uint32_t>{0, 1, 2, 3}, std::vector<float>{2.0f}, p.view(),
                         h);
  EXPECT_NEAR(h.compliance[0], 2.0f / 3.0f, 1e-6f);
  EXPECT_EQ(h.rest_angle[0], 0.0f);
}

TEST(DihedralBending, BentHingeRelaxesToItsRestAngle) {
  for (double rest : {0.0, 0.6, -2.5}) {
    Particles p(4);
    set_hinge(p, rest);
    Hinges h;
    build_dihedral_bending(std::vector<std::uint32_t>{0, 1, 2, 3}, std::vector<float>{0.0f},
                           p.view(), h);
    set_hinge(p, rest + 1.0);  // bent by 1 rad
    p.w[0] = p.w[1] = 0.0f;    // the edge pinned: only the wings turn
    for (int it = 0; it < 20; ++it) solve_dihedral_bending(p.view(), h, 1.0f / 60.0f);
    EXPECT_NEAR(hinge_angle(p, 0, 1, 2, 3), rest, 1e-4) << rest;
    // Free edge, too.
    set_hinge(p, rest - 0.8);
    p.w[0] = p.w[1] = 1.0f;
    for (int it = 0; it < 20; ++it) solve_dihedral_bending(p.view(), h, 1.0f / 60.0f);
    EXPECT_NEAR(hinge_angle(p, 0, 1, 2, 3), rest, 1e-4) << rest;
  }
}

TEST(DihedralBending, BentSheetRelaxesToFlat) {
  const Sheet s = make_sheet(10, 0.1);
  Particles p = particles_of(s);
  Hinges h;
  build_dihedral_bending(s.hinges, std::vector<float>(s.hinge_count(), 0.0f), p.view(), h);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-0.02f, 0.02f);
  for (std::size_t i = 0; i < p.size(); ++i) p.py[i] += u(rng);
  p.commit();
  const double before = bending_error(p.view(), h).max;
  // Gauss-Seidel over hinges alone: the smooth modes converge slowly (1.6e-4 rad at 1000).
  for (int it = 0; it < 1000; ++it) solve_dihedral_bending(p.view(), h, 1.0f / 60.0f);
  p.commit();
  const BendingError after = bending_error(p.view(), h);
  EXPECT_GT(before, 0.2);
  EXPECT_LT(after.max, 1e-3);
  EXPECT_TRUE(p.finite());
}

TEST(DihedralBending, DegenerateHingesStayFiniteAndUntouched) {
  Particles p(4);
  set_hinge(p, 0.5);
  Hinges h;
  build_dihedral_bending(std::vector<std::uint32_t>{0, 1, 2, 3}, std::vector<float>{0.0f}, p.view(),
                         h);
  h.rest_angle[0] = 0.0f;
  auto expect_untouched = [&](const char* what) {
    const Particles before = p;
    solve_dihedral_bending(p.view(), h, 1.0f / 60.0f);
    EXPECT_TRUE(p.finite()) << what;
    EXPECT_TRUE(bit_identical(p.px, before.px) && bit_identical(p.py, before.py) &&
                bit_identical(p.pz, before.pz))
        << what;
    EXPECT_EQ(h.lambda[0], 0.0f) << what;
  };
  p.set(1, 0, 0, 0);  // a == b: zero-length edge
  expect_untouched("coincident edge");
  set_hinge(p, 0.5);
  p.set(2, 0.5, 0, 0);  // c on the edge: zero-area wing
  expect_untouched("flat wing c");
  set_hinge(p, 0.5);
  p.set(3, 1, 0, 0);  // d == b
  expect_untouched("wing d on b");
  set_hinge(p, 0.5);
  for (int v = 0; v < 4; ++v) p.w[v] = 0.0f;  // all pinned
  expect_untouched("all pinned");
  for (int v = 0; v < 4; ++v) p.set(v, 0.3, 0.3, 0.3), p.w[v] = 1.0f;  // all coincident
  expect_untouched("all coincident");
}

// ---- Isometric bending --------------------------------------------------------------------------

// sum_ij Q_ij x_i . x_j in double from the stored float Q (relative to x0: Q's rows sum to 0),
// and the same sum with |Q_ij| |x_i| |x_j|: the scale its rounding is measured against.
std::pair<double, double> isometric_energy(const IsometricBending& b, std::size_t k,
                                           const Particles& p) {
  const Hinges& h = b.hinges;
  const std::uint32_t v[4] = {h.a[k], h.b[k], h.c[k], h.d[k]};
  double r[4][3];
  for (int s = 0; s < 4; ++s) {
    const auto x = p.predicted(v[s]), x0 = p.predicted(v[0]);
    for (int c = 0; c < 3; ++c) r[s][c] = x[c] - x0[c];
  }
  double Q[4][4];
  int entry = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i; j < 4; ++j) Q[i][j] = Q[j][i] = b.q[entry++][k];
  double e = 0.0, scale = 0.0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      const double d = r[i][0] * r[j][0] + r[i][1] * r[j][1] + r[i][2] * r[j][2];
      e += Q[i][j] * d;
      scale += std::abs(Q[i][j]) *
               std::sqrt((r[i][0] * r[i][0] + r[i][1] * r[i][1] + r[i][2] * r[i][2]) *
                         (r[j][0] * r[j][0] + r[j][1] * r[j][1] + r[j][2] * r[j][2]));
    }
  return {e, scale};
}

TEST(IsometricBending, FlatHingesHaveZeroEnergy) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles p(4);
  for (int trial = 0; trial < 20; ++trial) {
    // A random hinge in the plane z = 0, then rotated and moved away from the origin.
    const double along_c = u(rng), along_d = u(rng), hc = 0.3 + std::abs(u(rng)),
                 hd = 0.3 + std::abs(u(rng));
    const double local[4][3] = {{0, 0, 0}, {1, 0, 0}, {along_c, hc, 0}, {along_d, -hd, 0}};
    const double angle = 3 * u(rng), offset[3] = {5 * u(rng), 5 * u(rng), 5 * u(rng)};
    for (int v = 0; v < 4; ++v) {
      const double x = local[v][0], y = local[v][1];
      p.set(v, offset[0] + x, offset[1] + std::cos(angle) * y, offset[2] + std::sin(angle) * y);
    }
    IsometricBending b;
    build_isometric_bending(std::vector<std::uint32_t>{0, 1, 2, 3}, std::vector<float>{0.0f},
                            p.view(), b);
    const auto [e, scale] = isometric_energy(b, 0, p);
    EXPECT_LT(std::abs(e), 1e-5 * scale) << trial;
    EXPECT_GT(scale, 1.0);
    // And Q x itself vanishes (the bending force of a flat hinge), row by row.
    double Q[4][4];
    int entry = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i; j < 4; ++j) Q[i][j] = Q[j][i] = b.q[entry++][0];
    for (int i = 0; i < 4; ++i) {
      double qx[3] = {0, 0, 0}, row_scale = 0.0;
      for (int j = 0; j < 4; ++j) {
        const auto xj = p.predicted(j), x0 = p.predicted(0);
        for (int c = 0; c < 3; ++c) qx[c] += Q[i][j] * (xj[c] - x0[c]);
        row_scale += std::abs(Q[i][j]) * std::hypot(xj[0] - x0[0], xj[1] - x0[1], xj[2] - x0[2]);
      }
      EXPECT_LT(std::hypot(qx[0], qx[1], qx[2]), 1e-5 * row_scale) << trial << " row " << i;
    }
  }
}

TEST(IsometricBending, SmallAngleEnergyMatchesTheDihedralModel) {
  // A wing turned about the edge by theta: x^T Q x = 3 |e|^2 (2 sin(theta / 2))^2 / (A1 + A2),
  // which is 3 |e|^2 theta^2 / (A1 + A2) for small theta. So the isometric energy
  // k_b / 2 x^T Q x equals the dihedral model's k_b 3 |e|^2 / (A1 + A2) theta^2 / 2
  // (dihedral_bending.hpp) to first order: one bend compliance means the same in both models.
  // From the stored float Q (rounding ~1e-7 |Q| |x|^2: not at tiny angles) and from k, where
  // Q = k k^T, down to small angles.
  for (const auto& [along_c, along_d] : {std::pair{0.4, 0.7}, std::pair{-0.3, 1.4}}) {
    Particles p(4);
    set_hinge(p, 0.0, along_c, along_d);
    IsometricBending b;
    build_isometric_bending(std::vector<std::uint32_t>{0, 1, 2, 3}, std::vector<float>{0.0f},
                            p.view(), b);
    int entry = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i; j < 4; ++j, ++entry)
        EXPECT_NEAR(b.q[entry][0], b.k[i][0] * b.k[j][0], 1e-6 * std::abs(b.q[0][0]) + 1e-6)
            << i << j;
    const double e2 = 1.0, areas = 0.5 + 0.5;  // |e| = 1; both wings have height 1
    for (double theta : {0.1, -0.2, 0.3}) {
      set_hinge(p, theta, along_c, along_d);
      const double exact = 3.0 * e2 * 4.0 * std::pow(std::sin(theta / 2), 2) / areas;
      EXPECT_NEAR(isometric_energy(b, 0, p).first / exact, 1.0, 1e-3) << theta;
    }
    for (double theta : {1e-3, -0.01, 0.05}) {
      set_hinge(p, theta, along_c, along_d);
      double v[3] = {0, 0, 0};
      for (int i = 0; i < 4; ++i) {
        const auto x = p.predicted(i), x0 = p.predicted(0);
        for (int c = 0; c < 3; ++c) v[c] += b.k[i][0] * (x[c] - x0[c]);
      }
      const double small_angle = 3.0 * e2 * theta * theta / areas;
      EXPECT_NEAR((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / small_angle, 1.0, 1e-3) << theta;
    }
  }
}

TEST(IsometricBending, BentHingeFlattensAndFlatSheetStaysFlat) {
  Particles p(4);
  set_hinge(p, 0.0);
  IsometricBending b;
  build_isometric_bending(std::vector<std::uint32_t>{0, 1, 2, 3}, std::vector<float>{0.0f},
                          p.view(), b);
  set_hinge(p, 0.7);
  for (int it = 0; it < 10; ++it) solve_isometric_bending(p.view(), b, 1.0f / 60.0f);
  EXPECT_NEAR(hinge_angle(p, 0, 1, 2, 3), 0.0, 1e-4);

  // A flat sheet is at rest: zero-compliance iterations must not move it (rounding of Q and of
  // the positions must not be mistaken for a bend).
  const Sheet s = make_sheet(16, 0.02);
  Particles q = particles_of(s);
  for (std::size_t i = 0; i < q.size(); ++i)
    q.set(i, s.x[i] + 3.0, 1.5, s.z[i] - 2.0);  // away from 0
  IsometricBending sb;
  build_isometric_bending(s.hinges, std::vector<float>(s.hinge_count(), 0.0f), q.view(), sb);
  const Particles before = q;
  for (int it = 0; it < 10; ++it) solve_isometric_bending(q.view(), sb, 1.0f / 60.0f);
  double moved = 0.0;
  for (std::size_t i = 0; i < q.size(); ++i)
    moved = std::max({moved, std::abs(double(q.px[i]) - before.px[i]),
                      std::abs(double(q.py[i]) - before.py[i]),
                      std::abs(double(q.pz[i]) - before.pz[i])});
  EXPECT_LT(moved, 1e-5 * 0.02);
}

TEST(IsometricBending, BentSheetFlattens) {
  const Sheet s = make_sheet(10, 0.1);
  Particles p = particles_of(s);
  IsometricBending b;
  build_isometric_bending(s.hinges, std::vector<float>(s.hinge_count(), 0.0f), p.view(), b);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-0.02f, 0.02f);
  for (std::size_t i = 0; i < p.size(); ++i) p.py[i] += u(rng);
  p.commit();
  const double before = bending_error(p.view(), b.hinges).max;
  for (int it = 0; it < 1000; ++it) solve_isometric_bending(p.view(), b, 1.0f / 60.0f);
  p.commit();
  EXPECT_GT(before, 0.2);
  EXPECT_LT(bending_error(p.view(), b.hinges).max, 1e-3);
  EXPECT_TRUE(p.finite());
}

TEST(IsometricBending, ComplianceSoftensAndDegenerateHingesStayFinite) {
  // With compliance, one iteration moves the hinge less than a stiff one does.
  Particles stiff(4), soft(4);
  set_hinge(stiff, 0.0);
  set_hinge(soft, 0.0);
  IsometricBending bs, bf;
  build_isometric_bending(std::vector<std::uint32_t>{0, 1, 2, 3}, std::vector<float>{0.0f},
                          stiff.view(), bs);
  build_isometric_bending(std::vector<std::uint32_t>{0, 1, 2, 3}, std::vector<float>{1e-3f},
                          soft.view(), bf);
  set_hinge(stiff, 0.5);
  set_hinge(soft, 0.5);
  solve_isometric_bending(stiff.view(), bs, 1.0f / 60.0f);
  solve_isometric_bending(soft.view(), bf, 1.0f / 60.0f);
  const double a_stiff = std::abs(hinge_angle(stiff, 0, 1, 2, 3)),
               a_soft = std::abs(hinge_angle(soft, 0, 1, 2, 3));
  EXPECT_LT(a_stiff, 0.05);
  EXPECT_GT(a_soft, a_stiff + 0.05);
  EXPECT_LT(a_soft, 0.5);

  // A degenerate rest hinge has Q = 0 and never moves anything.
  Particles p(4);
  set_hinge(p, 0.0);
  p.set(2, 0.5, 0, 0);
  IsometricBending b;
  build_isometric_bending(std::vector<std::uint32_t>{0, 1, 2, 3}, std::vector<float>{0.0f},
                          p.view(), b);
  for (const auto& column : b.q) EXPECT_EQ(column[0], 0.0f);
  set_hinge(p, 1.0);
  const Particles before = p;
  solve_isometric_bending(p.view(), b, 1.0f / 60.0f);
  EXPECT_TRUE(bit_identical(p.px, before.px) && bit_identical(p.py, before.py) &&
              bit_identical(p.pz, before.pz));
}

// ---- Tethers
// -------------------------------------------------------------------------------------

TEST(Tethers, PullBackToTheMaximumLengthOnly) {
  Particles p(4);
  p.set(0, 0, 0, 0), p.w[0] = 0.0f;  // anchors
  p.set(1, 0, 5, 0), p.w[1] = 0.0f;
  p.set(2, 3, 4, 0);        // 5 from anchor 0, ~3.16 from anchor 1
  p.set(3, 0.5, 0.5, 0.5);  // within reach of both
  Tethers t;
  t.particle = {2, 3};
  t.start = {0, 2, 4};
  t.anchor = {0, 1, 0, 1};
  t.max_length = {2.0f, 10.0f, 2.0f, 10.0f};
  solve_tethers(p.view(), t);
  const double len = std::hypot(double(p.px[2]), double(p.py[2]), double(p.pz[2]));
  EXPECT_NEAR(len, 2.0, 2e-7 * 2.0);
  EXPECT_NEAR(p.px[2] / len, 0.6, 1e-6);  // along the line to the anchor
  EXPECT_NEAR(p.py[2] / len, 0.8, 1e-6);
  EXPECT_EQ(p.px[3], 0.5f);  // untouched, bit for bit
  EXPECT_EQ(p.py[3], 0.5f);
  EXPECT_EQ(p.pz[3], 0.5f);
  EXPECT_EQ(p.px[0], 0.0f);  // anchors never move
  EXPECT_EQ(p.py[1], 5.0f);

  // Remap follows the store's reorder.
  t.remap(std::vector<std::uint32_t>{1, 0, 3, 2});
  EXPECT_EQ(t.particle, (std::vector<std::uint32_t>{3, 2}));
  EXPECT_EQ(t.anchor, (std::vector<std::uint32_t>{1, 0, 1, 0}));
}

// ---- Particle contacts --------------------------------------------------------------------------

// Contact candidates within `radius` (brute force, all pairs listed from both sides).
ParticleContacts brute_contacts(const Particles& p, float radius) {
  ParticleContacts c;
  c.clear();
  for (std::uint32_t i = 0; i < p.size(); ++i) {
    bool any = false;
    for (std::uint32_t j = 0; j < p.size(); ++j) {
      if (i == j) continue;
      const float dx = p.px[i] - p.px[j], dy = p.py[i] - p.py[j], dz = p.pz[i] - p.pz[j];
      if (dx * dx + dy * dy + dz * dz < 4 * radius * radius) {
        c.partner.push_back(j), c.distance.push_back(radius);
        any = true;
      }
    }
    if (any) c.particle.push_back(i), c.start.push_back(std::uint32_t(c.partner.size()));
  }
  return c;
}

TEST(ParticleContacts, OverlappingPairSeparatesByInverseMassShares) {
  std::vector<float> scratch;
  for (const auto& [w0, w1] :
       {std::pair{1.0f, 1.0f}, std::pair{1.0f, 3.0f}, std::pair{0.0f, 2.0f}}) {
    Particles p(2);
    p.set(0, 0, 0, 0), p.set(1, 0.06, 0.0, 0.0);
    p.w[0] = w0, p.w[1] = w1;
    const ParticleContacts c = brute_contacts(p, 0.1f);
    ASSERT_EQ(c.size(), 2u);
    solve_particle_contacts(p.view(), c, 0.0f, scratch);
    EXPECT_NEAR(p.px[1] - p.px[0], 0.1f, 1e-6f);
    EXPECT_NEAR(p.px[0], -0.04 * w0 / (w0 + w1), 1e-7);
    EXPECT_NEAR(p.px[1], 0.06 + 0.04 * w1 / (w0 + w1), 1e-7);
    EXPECT_EQ(p.py[0], 0.0f);
    EXPECT_EQ(p.pz[1], 0.0f);
    if (w0 == 0.0f) {
      EXPECT_EQ(p.px[0], 0.0f);  // pinned: not moved at all
    }
  }
}

TEST(ParticleContacts, FrictionRemovesRelativeSlidingAndCoincidentStaysFinite) {
  std::vector<float> scratch;
  // Particle 1 slid by 0.01 along z this substep, particle 0 stood still; they overlap by 0.04
  // along x. With mu = 1 the relative tangential motion (0.01 < mu * 0.04) is removed, each
  // side taking its inverse-mass share.
  Particles p(2);
  p.set(0, 0, 0, 0), p.set(1, 0.06, 0.0, 0.0);
  p.z[1] = -0.01f;  // moved +0.01 in z from x to p
  p.w[1] = 3.0f;
  const ParticleContacts c = brute_contacts(p, 0.1f);
  solve_particle_contacts(p.view(), c, 1.0f, scratch);
  const double rel = (double(p.pz[1]) - p.z[1]) - (double(p.pz[0]) - p.z[0]);
  EXPECT_NEAR(rel, 0.0, 1e-8);
  EXPECT_NEAR(p.pz[0], 0.0025, 1e-8);  // 1/4 of the 0.01
  EXPECT_NEAR(p.px[1] - p.px[0], 0.1f, 1e-6f);

  Particles q(3);
  q.set(0, 0.5, 0.5, 0.5), q.set(1, 0.5, 0.5, 0.5), q.set(2, 0.5, 0.55, 0.5);
  const ParticleContacts cq = brute_contacts(q, 0.1f);
  solve_particle_contacts(q.view(), cq, 0.5f, scratch);
  EXPECT_TRUE(q.finite());
  EXPECT_NEAR(q.py[2] - q.py[0], 0.1f, 1e-6f);  // 0 and 1 both pushed from 2, not from each other
  EXPECT_EQ(q.py[0], q.py[1]);
}

// Fluid-shape contacts (solve_sided_contacts): a fluid particle (w 1) overlapping two shape
// particles (w 2) by 0.04 each, along x and along y: its corrections are averaged over its two
// contacts, lambda = 0.04 / (1 + 2) / 2 each, and each shape particle gets its pair's whole
// reaction, so the momentum sum of m dp is 0; a pair out of reach does nothing.
TEST(ParticleContacts, SidedContactsKeepEveryPairsMomentum) {
  Particles p(4);
  p.set(0, 0, 0, 0), p.set(1, 0.06, 0, 0), p.set(2, 0, 0.06, 0), p.set(3, 0, 0, 0.2);
  p.w[0] = 1.0f, p.w[1] = 2.0f, p.w[2] = 2.0f, p.w[3] = 2.0f;
  SidedContacts c;
  c.clear();
  c.first.particle = {0};
  c.first.partner = {1, 2, 3};
  c.first.distance = {0.1f, 0.1f, 0.1f};
  c.first.start = {0, 3};
  c.second = {1, 2, 3};
  c.second_entry = {0, 1, 2};
  c.second_start = {0, 1, 2, 3};
  std::vector<float> scratch;
  solve_sided_contacts(p.view(), c, 0.0f, scratch);
  const double lambda = 0.04 / 3.0 / 2.0;
  EXPECT_NEAR(p.px[0], -1.0 * lambda, 1e-7);
  EXPECT_NEAR(p.py[0], -1.0 * lambda, 1e-7);
  EXPECT_NEAR(p.px[1], 0.06 + 2.0 * lambda, 1e-7);
  EXPECT_NEAR(p.py[2], 0.06 + 2.0 * lambda, 1e-7);
  EXPECT_EQ(p.pz[3], 0.2f);  // out of reach
  for (int a = 0; a < 2; ++a) {
    const float* x = a == 0 ? p.px.data() : p.py.data();
    const double momentum = (x[0] - 0.0) / 1.0 + (x[1] - (a == 0 ? 0.06 : 0.0)) / 2.0 + (x[2] - (a == 0 ? 0.0 : 0.06)) / 2.0;
    EXPECT_NEAR(momentum, 0.0, 1e-8) << "axis " << a;
  }
}

// Friction of the fluid-shape contacts: a fluid particle (w 1) slid 0.01 along z over a shape
// particle (w 2) that stood still, overlapping it by 0.04 along x. mu = 1: the slip (0.01 <=
// mu 0.04) is removed, the fluid taking 1/3 of it and the shape 2/3; mu = 0.1: it is cut by
// mu 0.04 = 0.004 (to 0.006). Either way m dp sums to 0 along z, and the normal separation is
// the frictionless one.
TEST(ParticleContacts, SidedContactsHaveFrictionAndKeepMomentum) {
  for (const auto& [mu, slip_after] : {std::pair{1.0f, 0.0}, std::pair{0.1f, 0.006}}) {
    Particles p(2);
    p.set(0, 0, 0, 0), p.set(1, 0.06, 0, 0);
    p.z[0] = -0.01f;  // the fluid particle moved +0.01 in z from x to p
    p.w[0] = 1.0f, p.w[1] = 2.0f;
    SidedContacts c;
    c.clear();
    c.first.particle = {0};
    c.first.partner = {1};
    c.first.distance = {0.1f};
    c.first.start = {0, 1};
    c.second = {1};
    c.second_entry = {0};
    c.second_start = {0, 1};
    std::vector<float> scratch;
    solve_sided_contacts(p.view(), c, mu, scratch);
    const double slip = (double(p.pz[0]) - p.z[0]) - (double(p.pz[1]) - p.z[1]);
    EXPECT_NEAR(slip, slip_after, 1e-8) << mu;
    EXPECT_NEAR(double(p.pz[0]) / 1.0 + double(p.pz[1]) / 2.0, 0.0, 1e-9) << mu;
    EXPECT_NEAR(p.px[1] - p.px[0], 0.1, 1e-7) << mu;
    EXPECT_NEAR(p.px[0], -0.04 / 3.0, 1e-7) << mu;
  }
}

TEST(ParticleContacts, ThreadCountDoesNotChangeResults) {
  // A random cloud of 3000 particles with many overlaps, friction on, three iterations.
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  Particles init(3000);
  for (std::size_t i = 0; i < init.size(); ++i) {
    init.set(i, u(rng), u(rng), u(rng));
    init.px[i] += 0.01f * (u(rng) - 0.5f);  // some motion within the substep
    init.w[i] = i % 17 == 0 ? 0.0f : 0.5f + u(rng);
  }
  const ParticleContacts c = brute_contacts(init, 0.05f);
  ASSERT_GT(c.partner.size(), 3000u);
  auto run = [&](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    Particles p = init;
    std::vector<float> scratch;
    for (int it = 0; it < 3; ++it) solve_particle_contacts(p.view(), c, 0.4f, scratch);
    return p;
  };
  const Particles one = run(1), two = run(2);
  EXPECT_TRUE(bit_identical(one.px, two.px));
  EXPECT_TRUE(bit_identical(one.py, two.py));
  EXPECT_TRUE(bit_identical(one.pz, two.pz));
  EXPECT_FALSE(bit_identical(one.px, init.px));  // something happened
}

// ---- SDF grid and the capsule / SDF colliders
// -----------------------------------------------------

struct SphereSdf {
  std::vector<float> values;
  SdfGrid grid;
  SphereSdf(const float center[3], float radius, float lo, int n, float voxel) {
    values.resize(std::size_t(n) * n * n);
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const double x = lo + i * voxel - center[0], y = lo + j * voxel - center[1],
                       z = lo + k * voxel - center[2];
          values[(std::size_t(k) * n + j) * n + i] =
              float(std::sqrt(x * x + y * y + z * z) - radius);
        }
    grid.origin[0] = grid.origin[1] = grid.origin[2] = lo;
    grid.voxel = voxel;
    grid.dims[0] = grid.dims[1] = grid.dims[2] = n;
    grid.values = values.data();
  }
};

TEST(SdfGrid, TrilinearSampleAndGradient) {
  // A linear field is reproduced exactly by trilinear interpolation, gradient included.
  const int n = 5;
  std::vector<float> values(n * n * n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        values[(k * n + j) * n + i] = 0.5f * i - 1.0f * j + 2.0f * k - 1.0f;
  SdfGrid g;
  g.origin[0] = 1.0f, g.origin[1] = 2.0f, g.origin[2] = 3.0f;
  g.voxel = 0.5f;
  g.dims[0] = g.dims[1] = g.dims[2] = n;
  g.values = values.data();
  float d = 0.0f, nrm[3];
  ASSERT_TRUE(g.sample(1.3f, 2.7f, 4.1f, d, nrm));
  // Cell coordinates u = (0.6, 1.4, 2.2): 0.5 u - u_y + 2 u_z - 1.
  EXPECT_NEAR(d, 0.5f * 0.6f - 1.4f + 2.0f * 2.2f - 1.0f, 1e-5f);
  const float len = std::sqrt(0.25f + 1.0f + 4.0f);
  EXPECT_NEAR(nrm[0], 0.5f / len, 1e-6f);
  EXPECT_NEAR(nrm[1], -1.0f / len, 1e-6f);
  EXPECT_NEAR(nrm[2], 2.0f / len, 1e-6f);
  // The box edges are inside; beyond them, or without values, nothing is known.
  EXPECT_TRUE(g.sample(1.0f, 2.0f, 3.0f, d, nrm));
  EXPECT_NEAR(d, -1.0f, 1e-6f);
  EXPECT_TRUE(g.sample(3.0f, 4.0f, 5.0f, d, nrm));
  EXPECT_NEAR(d, 0.5f * 4 - 4 + 8 - 1, 1e-5f);
  EXPECT_FALSE(g.sample(0.99f, 3.0f, 4.0f, d, nrm));
  EXPECT_FALSE(g.sample(2.0f, 4.01f, 4.0f, d, nrm));
  EXPECT_FALSE(g.sample(2.0f, 3.0f, NAN, d, nrm));
  SdfGrid empty = g;
  empty.values = nullptr;
  EXPECT_FALSE(empty.sample(2.0f, 3.0f, 4.0f, d, nrm));
  // A flat field has no gradient: the documented fallback (0, 1, 0).
  std::vector<float> flat(n * n * n, 0.25f);
  g.values = flat.data();
  ASSERT_TRUE(g.sample(1.3f, 2.7f, 4.1f, d, nrm));
  EXPECT_EQ(nrm[1], 1.0f);

  // A sphere's field: distance and normal close to the exact ones between samples.
  const float c[3] = {0.1f, -0.05f, 0.02f};
  const SphereSdf s(c, 0.5f, -1.0f, 41, 0.05f);
  ASSERT_TRUE(s.grid.sample(0.43f, 0.31f, -0.2f, d, nrm));
  const double rx = 0.43 - c[0], ry = 0.31 - c[1], rz = -0.2 - c[2],
               r = std::sqrt(rx * rx + ry * ry + rz * rz);
  EXPECT_NEAR(d, r - 0.5, 2e-3);
  EXPECT_NEAR(nrm[0] * rx / r + nrm[1] * ry / r + nrm[2] * rz / r, 1.0, 1e-3);
}

TEST(ClothCollisions, CapsulePushesOutToItsSurfacePlusTheParticleRadius) {
  Particles p(4);
  p.radius = {0.01f, 0.02f, 0.03f, 0.0f};  // two cloths' vertices, a fluid particle, a raw one
  p.set(0, 0.5, 0.55, 0.5);   // over the middle of the axis, cloth 0 (radius 0.01)
  p.set(1, 0.1, 0.5, 0.52);   // beyond end a: the end cap, cloth 1 (radius 0.02)
  p.set(2, 0.55, 0.45, 0.5);  // fluid (radius 0.03)
  p.set(3, 0.5, 0.5, 0.5);    // exactly on the axis: pushed up
  CollisionShape capsule;
  capsule.kind = CollisionShape::Kind::Capsule;
  capsule.a[0] = 0.3f, capsule.a[1] = 0.5f, capsule.a[2] = 0.5f;
  capsule.b[0] = 0.7f, capsule.b[1] = 0.5f, capsule.b[2] = 0.5f;
  capsule.radius = 0.2f;
  CollisionParams params;
  solve_collisions(p.view(), params, std::span<const CollisionShape>(&capsule, 1));
  auto axis_distance = [&](int i) {
    const double t = std::clamp((double(p.px[i]) - 0.3) / 0.4, 0.0, 1.0);
    return std::hypot(p.px[i] - (0.3 + 0.4 * t), p.py[i] - 0.5, p.pz[i] - 0.5);
  };
  EXPECT_NEAR(axis_distance(0), 0.21, 1e-6);
  EXPECT_NEAR(p.px[0], 0.5f, 1e-7f);  // straight out, along the normal
  EXPECT_NEAR(axis_distance(1), 0.22, 1e-6);
  EXPECT_NEAR((0.3 - p.px[1]) / (0.5 - p.pz[1]), (0.3 - 0.1) / (0.5 - 0.52),
              1e-4);  // radial from a
  EXPECT_NEAR(axis_distance(2), 0.23, 1e-6);
  EXPECT_NEAR(axis_distance(3), 0.2, 1e-6);
  EXPECT_NEAR(p.py[3], 0.7f, 1e-6f);

  // A zero-length capsule is a sphere; a particle outside is untouched.
  Particles q(2, 0.01f);
  q.set(0, 0.5, 0.6, 0.5), q.set(1, 0.5, 0.9, 0.5);
  capsule.b[0] = capsule.a[0] = 0.5f;
  solve_collisions(q.view(), params, std::span<const CollisionShape>(&capsule, 1));
  EXPECT_NEAR(q.py[0], 0.71f, 1e-6f);
  EXPECT_EQ(q.py[1], 0.9f);
}

TEST(ClothCollisions, SdfPushesOutAlongTheFieldsNormal) {
  const float center[3] = {0.5f, 0.4f, 0.5f};
  const SphereSdf sphere(center, 0.2f, 0.0f, 41, 0.025f);
  CollisionShape shape;
  shape.kind = CollisionShape::Kind::Sdf;
  shape.sdf = &sphere.grid;
  CollisionParams params;
  // Particle 0 starts 2 cm deep (a step's worth of penetration), along dir from the center.
  const double dir[3] = {0.05, 0.05, 0.02}, len = std::hypot(dir[0], dir[1], dir[2]);
  Particles p(3, 0.01f);  // a cloth's vertices: half its thickness
  p.set(0, center[0] + 0.18 * dir[0] / len, center[1] + 0.18 * dir[1] / len,
        center[2] + 0.18 * dir[2] / len);
  p.set(1, 0.5, 0.605, 0.5);  // outside the sphere but within the cloth radius
  p.set(2, 0.5, 0.9, 0.5);    // far outside: untouched
  solve_collisions(p.view(), params, std::span<const CollisionShape>(&shape, 1));
  // Trilinear interpolation of |x - center| - R errs by at most h^2 / 8 times the sum of its
  // second derivatives (2 / r): 0.8 mm here. Both the field's value and the true distance at
  // the pushed particle must be that close to the particle radius.
  const double interpolation_error = 0.025 * 0.025 / 8.0 * 2.0 / 0.2;
  for (int i = 0; i < 2; ++i) {
    float d, n[3];
    ASSERT_TRUE(sphere.grid.sample(p.px[i], p.py[i], p.pz[i], d, n));
    EXPECT_NEAR(d, 0.01, interpolation_error) << i;  // on the field's surface grown by the radius
    const double r = std::hypot(p.px[i] - center[0], p.py[i] - center[1], p.pz[i] - center[2]);
    EXPECT_NEAR(r, 0.21, interpolation_error) << i;  // and on the true sphere's
  }
  // Pushed along the radius through its start point.
  EXPECT_NEAR(p.px[0] - center[0], 0.21 * dir[0] / len, 2e-3);
  EXPECT_NEAR(p.pz[0] - center[2], 0.21 * dir[2] / len, 2e-3);
  EXPECT_EQ(p.py[2], 0.9f);
  // Without a field the shape is inert.
  shape.sdf = nullptr;
  Particles q = p;
  q.set(0, 0.5, 0.4, 0.5);
  solve_collisions(q.view(), params, std::span<const CollisionShape>(&shape, 1));
  EXPECT_EQ(q.py[0], 0.4f);
}

// ---- Vectorized solves against plain scalar references
// -------------------------------------------

// One iteration of each family, one constraint at a time in stored (color) order, written
// straight from the headers' formulas: the oracle for the batched, vectorized kernels.
void reference_distance(Particles& p, DistanceConstraints& c, float dt) {
  for (std::size_t k = 0; k < c.size(); ++k) {
    const std::uint32_t a = c.i[k], b = c.j[k];
    const double alpha = c.compliance[k] / (double(dt) * dt);
    const double d[3] = {double(p.px[a]) - p.px[b], double(p.py[a]) - p.py[b],
                         double(p.pz[a]) - p.pz[b]};
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const double denom = p.w[a] + p.w[b] + alpha;
    if (denom <= 0.0 || len <= 1e-9) continue;
    const double dlambda = (-(len - c.rest_length[k]) - alpha * c.lambda[k]) / denom;
    c.lambda[k] += float(dlambda);
    float* pos[3] = {p.px.data(), p.py.data(), p.pz.data()};
    for (int i = 0; i < 3; ++i) {
      pos[i][a] = float(pos[i][a] + p.w[a] * dlambda * d[i] / len);
      pos[i][b] = float(pos[i][b] - p.w[b] * dlambda * d[i] / len);
    }
  }
}

// grad[v] of a hinge's signed angle (the closed form of dihedral_bending.cpp, in double); false
// for a degenerate hinge.
bool dihedral_gradient(const std::array<std::array<double, 3>, 4>& q, double grad[4][3]) {
  auto sub = [](const std::array<double, 3>& u, const std::array<double, 3>& v) {
    return std::array<double, 3>{u[0] - v[0], u[1] - v[1], u[2] - v[2]};
  };
  auto cross = [](const std::array<double, 3>& u, const std::array<double, 3>& v) {
    return std::array<double, 3>{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                                 u[0] * v[1] - u[1] * v[0]};
  };
  auto dot = [](const std::array<double, 3>& u, const std::array<double, 3>& v) {
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  };
  const auto e = sub(q[1], q[0]), n1 = cross(e, sub(q[2], q[0])), n2 = cross(sub(q[3], q[1]), e);
  const double e2 = dot(e, e), n1sq = dot(n1, n1), n2sq = dot(n2, n2);
  if (e2 <= kHingeMinEdge2 || n1sq <= kHingeMinWing * e2 * e2 || n2sq <= kHingeMinWing * e2 * e2)
    return false;
  const double len = std::sqrt(e2), sc = dot(sub(q[2], q[0]), e) / e2,
               sd = dot(sub(q[3], q[0]), e) / e2;
  for (int k = 0; k < 3; ++k) {
    grad[2][k] = -len * n1[k] / n1sq;
    grad[3][k] = -len * n2[k] / n2sq;
    grad[0][k] = (sc - 1) * grad[2][k] + (sd - 1) * grad[3][k];
    grad[1][k] = -sc * grad[2][k] - sd * grad[3][k];
  }
  return true;
}

// Applies dp_v = w_v grad_v dlambda to a hinge's vertices.
void apply_hinge(Particles& p, const std::uint32_t v[4], const double grad[4][3], double dlambda) {
  float* pos[3] = {p.px.data(), p.py.data(), p.pz.data()};
  for (int s = 0; s < 4; ++s)
    for (int k = 0; k < 3; ++k)
      pos[k][v[s]] = float(pos[k][v[s]] + p.w[v[s]] * grad[s][k] * dlambda);
}

void reference_dihedral(Particles& p, Hinges& h, float dt) {
  for (std::size_t k = 0; k < h.size(); ++k) {
    const std::uint32_t v[4] = {h.a[k], h.b[k], h.c[k], h.d[k]};
    std::array<std::array<double, 3>, 4> q;
    for (int s = 0; s < 4; ++s) q[s] = p.predicted(v[s]);
    double grad[4][3];
    const double wsum = p.w[v[0]] + p.w[v[1]] + p.w[v[2]] + p.w[v[3]];
    if (wsum <= 0.0 || !dihedral_gradient(q, grad)) continue;
    const double alpha = h.compliance[k] / (double(dt) * dt);
    const double C = wrap_angle(dihedral_angle(q[0].data(), q[1].data(), q[2].data(), q[3].data()) -
                                h.rest_angle[k]);
    double denom = alpha;
    for (int s = 0; s < 4; ++s)
      denom +=
          p.w[v[s]] * (grad[s][0] * grad[s][0] + grad[s][1] * grad[s][1] + grad[s][2] * grad[s][2]);
    const double dlambda = (-C - alpha * h.lambda[k]) / denom;
    h.lambda[k] += float(dlambda);
    apply_hinge(p, v, grad, dlambda);
  }
}

// From the factor k of Q = k k^T (checked against the stored Q in
// SmallAngleEnergyMatchesTheDihedralModel), in double: C = |v|, v = sum_i k_i (x_i - x0),
// grad_i C = k_i v / |v|. (Summing the stored Q_ij x_i . x_j instead is no oracle: its float
// rounding swamps nearly flat hinges; see isometric_bending.hpp.)
void reference_isometric(Particles& p, IsometricBending& b, float dt) {
  Hinges& h = b.hinges;
  for (std::size_t k = 0; k < h.size(); ++k) {
    const std::uint32_t v[4] = {h.a[k], h.b[k], h.c[k], h.d[k]};
    const auto x0 = p.predicted(v[0]);
    double vec[3] = {0, 0, 0};
    for (int i = 1; i < 4; ++i) {
      const auto xi = p.predicted(v[i]);
      for (int c = 0; c < 3; ++c) vec[c] += b.k[i][k] * (xi[c] - x0[c]);
    }
    const double C = std::sqrt(vec[0] * vec[0] + vec[1] * vec[1] + vec[2] * vec[2]);
    const double wsum = p.w[v[0]] + p.w[v[1]] + p.w[v[2]] + p.w[v[3]];
    if (C <= 1e-9 || wsum <= 0.0) continue;
    const double alpha = h.compliance[k] / (double(dt) * dt);
    double grad[4][3], denom = alpha;
    for (int i = 0; i < 4; ++i) {
      for (int c = 0; c < 3; ++c) grad[i][c] = b.k[i][k] * vec[c] / C;
      denom += p.w[v[i]] * double(b.k[i][k]) * b.k[i][k];
    }
    const double dlambda = (-C - alpha * h.lambda[k]) / denom;
    h.lambda[k] += float(dlambda);
    apply_hinge(p, v, grad, dlambda);
  }
}

double max_difference(const Particles& a, const Particles& b) {
  double d = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
    d = std::max({d, std::abs(double(a.px[i]) - b.px[i]), std::abs(double(a.py[i]) - b.py[i]),
                  std::abs(double(a.pz[i]) - b.pz[i])});
  return d;
}

TEST(ClothSolveReference, VectorizedSolvesMatchScalarReferences) {
  // A 3 x 3 sheet (colors of fewer constraints than a batch: padding lanes) and a 64 x 64 one
  // (full batches and a partial one per color), 1 cm spacing, perturbed by up to 3 mm, some
  // vertices pinned; one iteration of each family from the same state.
  for (int n : {3, 64}) {
    SCOPED_TRACE(n);
    const Sheet s = make_sheet(n, 0.01);
    Particles init = particles_of(s);
    DistanceConstraints dc;
    std::vector<float> rest(s.edge_i.size()), compliance(s.edge_i.size(), 1e-7f);
    for (std::size_t k = 0; k < rest.size(); ++k)
      rest[k] = float(
          std::hypot(s.x[s.edge_i[k]] - s.x[s.edge_j[k]], s.z[s.edge_i[k]] - s.z[s.edge_j[k]]));
    color_distance_constraints(s.edge_i, s.edge_j, rest, compliance, init.size(), dc);
    Hinges dihedral;
    build_dihedral_bending(s.hinges, std::vector<float>(s.hinge_count(), 1e-3f), init.view(),
                           dihedral);
    IsometricBending iso;
    build_isometric_bending(s.hinges, std::vector<float>(s.hinge_count(), 1e-3f), init.view(), iso);
    std::mt19937 rng(8);
    std::uniform_real_distribution<float> u(-0.003f, 0.003f);
    for (std::size_t i = 0; i < init.size(); ++i) {
      init.px[i] += u(rng), init.py[i] += u(rng), init.pz[i] += u(rng);
      if (i % 23 == 0) init.w[i] = 0.0f;
    }
    const float dt = 1.0f / 600.0f;
    {
      Particles fast = init, slow = init;
      DistanceConstraints a = dc, b = dc;
      solve_distance_constraints(fast.view(), a, dt);
      reference_distance(slow, b, dt);
      EXPECT_LT(max_difference(fast, slow), 2e-7);  // a few float ulps of 0.6 m coordinates
      EXPECT_GT(max_difference(fast, init), 1e-4);
    }
    {
      Particles fast = init, slow = init;
      Hinges a = dihedral, b = dihedral;
      solve_dihedral_bending(fast.view(), a, dt);
      reference_dihedral(slow, b, dt);
      EXPECT_LT(max_difference(fast, slow), 2e-7);
      EXPECT_GT(max_difference(fast, init), 1e-4);
    }
    {
      Particles fast = init, slow = init;
      IsometricBending a = iso, b = iso;
      solve_isometric_bending(fast.view(), a, dt);
      reference_isometric(slow, b, dt);
      EXPECT_LT(max_difference(fast, slow), 2e-7);
      EXPECT_GT(max_difference(fast, init), 1e-4);
    }
  }
}

// ---- Determinism of the colored solves
// ------------------------------------------------------------

// A 64 x 64 sheet (1 cm) with its three colored families, predicted positions perturbed by up to
// 4 mm, two corners pinned.
struct SheetFamilies {
  Particles init;
  DistanceConstraints dc;
  Hinges dihedral;
  IsometricBending iso;
};
SheetFamilies make_sheet_families() {
  const Sheet s = make_sheet(64, 0.01);
  SheetFamilies f{particles_of(s), {}, {}, {}};
  std::vector<float> rest(s.edge_i.size()), compliance(s.edge_i.size(), 1e-6f);
  for (std::size_t k = 0; k < rest.size(); ++k)
    rest[k] =
        float(std::hypot(s.x[s.edge_i[k]] - s.x[s.edge_j[k]], s.z[s.edge_i[k]] - s.z[s.edge_j[k]]));
  color_distance_constraints(s.edge_i, s.edge_j, rest, compliance, f.init.size(), f.dc);
  build_dihedral_bending(s.hinges, std::vector<float>(s.hinge_count(), 1e-2f), f.init.view(),
                         f.dihedral);
  build_isometric_bending(s.hinges, std::vector<float>(s.hinge_count(), 1e-2f), f.init.view(),
                          f.iso);
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> u(-0.004f, 0.004f);
  for (std::size_t i = 0; i < f.init.size(); ++i)
    f.init.px[i] += u(rng), f.init.py[i] += u(rng), f.init.pz[i] += u(rng);
  f.init.w[0] = f.init.w[63] = 0.0f;
  return f;
}

TEST(ClothSolveDeterminism, ThreadCountDoesNotChangeAnySolve) {
  const SheetFamilies f = make_sheet_families();
  const Particles& init = f.init;
  const DistanceConstraints& dc = f.dc;
  const Hinges& dihedral = f.dihedral;
  const IsometricBending& iso = f.iso;

  enum Solve { Distance, Dihedral, Isometric };
  auto run = [&](Solve which, int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    Particles p = init;
    Hinges h = dihedral;
    IsometricBending b = iso;
    DistanceConstraints d = dc;
    for (int it = 0; it < 4; ++it) {
      if (which == Distance) solve_distance_constraints(p.view(), d, 1.0f / 240.0f);
      if (which == Dihedral) solve_dihedral_bending(p.view(), h, 1.0f / 240.0f);
      if (which == Isometric) solve_isometric_bending(p.view(), b, 1.0f / 240.0f);
    }
    return p;
  };
  for (Solve which : {Distance, Dihedral, Isometric}) {
    const Particles one = run(which, 1), two = run(which, 2);
    EXPECT_TRUE(bit_identical(one.px, two.px) && bit_identical(one.py, two.py) &&
                bit_identical(one.pz, two.pz))
        << "solve " << which;
    EXPECT_FALSE(bit_identical(one.py, init.py)) << "solve " << which;
    EXPECT_TRUE(one.finite());
  }
}

TEST(ClothSolveDeterminism, PackedOnceAndRestartedIsTheSameAsPackedPerFamilyAfterAReset) {
  // What the cloth solver does (one PackedPositions for all three families per iteration, the
  // substep's first solves with Multipliers::Restart on stale multipliers) against the
  // ParticleView entry points (each family packs its own range) after the multipliers were reset
  // to 0: the same positions and multipliers, bit for bit, over 3 iterations. 2 threads.
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
  const SheetFamilies f = make_sheet_families();
  const Particles& init = f.init;
  const DistanceConstraints& dc = f.dc;
  const Hinges& dihedral = f.dihedral;
  const IsometricBending& iso = f.iso;
  const float dt = 1.0f / 240.0f;

  Particles a = init;
  DistanceConstraints da = dc;
  Hinges ha = dihedral;
  IsometricBending ia = iso;
  for (int it = 0; it < 3; ++it) {
    solve_distance_constraints(a.view(), da, dt);
    solve_dihedral_bending(a.view(), ha, dt);
    solve_isometric_bending(a.view(), ia, dt);
  }

  Particles b = init;
  DistanceConstraints db = dc;
  Hinges hb = dihedral;
  IsometricBending ib = iso;
  for (auto* lambda : {&db.lambda, &hb.lambda, &ib.hinges.lambda})
    std::fill(lambda->begin(), lambda->end(), 12.5f);  // a previous substep's, never read
  PackedPositions packed;
  packed.reset(index_range({db.i, db.j, hb.a, hb.b, hb.c, hb.d}));
  for (int it = 0; it < 3; ++it) {
    const Multipliers start = it == 0 ? Multipliers::Restart : Multipliers::Accumulate;
    packed.pack(b.view());
    solve_distance_constraints(packed, db, dt, start);
    solve_dihedral_bending(packed, hb, dt, start);
    solve_isometric_bending(packed, ib, dt, start);
    packed.unpack(b.view());
  }
  EXPECT_TRUE(bit_identical(a.px, b.px) && bit_identical(a.py, b.py) && bit_identical(a.pz, b.pz));
  EXPECT_TRUE(bit_identical(da.lambda, db.lambda));
  EXPECT_TRUE(bit_identical(ha.lambda, hb.lambda));
  EXPECT_TRUE(bit_identical(ia.hinges.lambda, ib.hinges.lambda));
  EXPECT_FALSE(bit_identical(a.py, init.py));
  EXPECT_TRUE(a.finite());
}

// ---- Distance forest: the line search (distance_tree.hpp, safeguard 2) --------------------------

using test::Positions;

// A chain pin 0 - 1 - 2 as one tree of the forest: edge k joins particle k + 1 to its parent k,
// rest length 1, multipliers 0. The positions given are the predicted ones (what the solve moves).
struct Chain {
  Particles p{3};
  DistanceConstraints c;
  DistanceForest forest;
  Chain(const Positions& x, float w1, float w2, float compliance) {
    for (std::size_t v = 0; v < 3; ++v) p.set(v, x[v][0], x[v][1], x[v][2]);
    p.w = {0.0f, w1, w2};
    c.i = {1, 2}, c.j = {0, 1};
    c.rest_length = {1.0f, 1.0f}, c.compliance = {compliance, compliance}, c.lambda = {0.0f, 0.0f};
    const std::uint32_t particle[] = {0, 1, 2}, parent[] = {DistanceForest::kRoot, 0, 1},
                        edge[] = {0, 0, 1};
    forest = make_distance_forest(particle, parent, edge);
  }
  Positions predicted() const { return {p.predicted(0), p.predicted(1), p.predicted(2)}; }
  // The nonlinear violation sum_e |C_e| = sum_e | |x_i - x_j| - rest_e |, in double.
  double violation(const Positions& x) const {
    double sum = 0.0;
    for (std::size_t e = 0; e < c.size(); ++e) {
      const auto &a = x[c.i[e]], &b = x[c.j[e]];
      sum += std::abs(std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]) - double(c.rest_length[e]));
    }
    return sum;
  }
};

// The full, unguarded linearized XPBD step at the predicted positions (the dense reference of
// tests/dense_distance_projection.hpp, as Cloth.ForestSolveMatchesTheDenseLinearizedProjection
// uses it).
using LinearizedStep = test::DenseProjection;
LinearizedStep linearized_step(const Chain& ch, float dt) {
  return test::dense_distance_projection(ch.c, ch.predicted(), ch.p.w, ch.c.lambda, dt);
}

Positions step_by(const Positions& x, const LinearizedStep& s, double beta) {
  Positions y = x;
  for (std::size_t v = 0; v < x.size(); ++v)
    for (int a = 0; a < 3; ++a) y[v][a] += beta * s.dx[v][a];
  return y;
}

TEST(DistanceForest, LineSearchShortensAStepThatWouldSwingALightBeadFarOffItsEdge) {
  // A rigid chain pin (origin) - light bead 1 (mass 0.1, at (1, 0, 0)) - particle 2 (mass 1)
  // whose predicted position has swung round to (-1, 0.5, 0): edge 1-2 is 2.06 long for a rest
  // length of 1. To first order edge 0-1 does not resist a sideways move of the bead, so the
  // linearized step moves the bead 1.6 across it and stretches it to 1.9: sum |C| grows from
  // 1.06 to 1.77. Asserted: the solve takes that step's direction shortened by one of the
  // halvings 1/2 .. 1/16 (positions and multipliers alike, to float rounding of the elimination),
  // and ends with less violation than the full step and than before it. With beta = 1 always
  // accepted the result is the full step, which fails all of these.
  const float dt = 1.0f / 60.0f;
  Chain ch({{0, 0, 0}, {1, 0, 0}, {-1, 0.5, 0}}, 10.0f, 1.0f, 0.0f);
  const Positions x0 = ch.predicted();
  const LinearizedStep full = linearized_step(ch, dt);
  const Positions x_full = step_by(x0, full, 1.0);
  ASSERT_GT(ch.violation(x_full), ch.violation(x0) + 0.5);  // the premise: the full step overshoots

  solve_distance_forest(ch.p.view(), ch.c, ch.forest, dt, nullptr);
  const Positions x1 = ch.predicted();
  double num = 0.0, den = 0.0;  // the step length taken, along the full step
  for (std::size_t v = 0; v < 3; ++v)
    for (int a = 0; a < 3; ++a)
      num += (x1[v][a] - x0[v][a]) * full.dx[v][a], den += full.dx[v][a] * full.dx[v][a];
  const double beta = std::exp2(std::round(std::log2(num / den)));
  EXPECT_NEAR(num / den, beta, 1e-6);
  EXPECT_GE(beta, 1.0 / 16.0);
  EXPECT_LE(beta, 0.5);
  const Positions expected = step_by(x0, full, beta);
  for (std::size_t v = 0; v < 3; ++v)
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(x1[v][a], expected[v][a], 1e-6) << "vertex " << v;
  for (std::size_t e = 0; e < 2; ++e)
    EXPECT_NEAR(ch.c.lambda[e], beta * full.dlambda[e], 1e-6) << "edge " << e;
  EXPECT_LT(ch.violation(x1), ch.violation(x_full) - 0.5);
  EXPECT_LT(ch.violation(x1), ch.violation(x0));
}

TEST(DistanceForest, NearlyLinearStepIsTakenInFull) {
  // The same chain, compliant, with edges off their rest length by at most 1 %: the step moves
  // the particles by about 1e-2 and turns the edges by under a degree, the linearization holds,
  // so the line search accepts beta = 1 and the solve is the full linearized step. Asserted:
  // positions and multipliers equal the dense double solution to float rounding (1e-6), where a
  // halved step would be off by over 5e-3.
  const float dt = 1.0f / 60.0f;
  Chain ch({{0, 0, 0}, {1.01, 0.02, 0}, {1.99, 0.22, 0.03}}, 10.0f, 1.0f, 1e-4f);
  const Positions x0 = ch.predicted();
  const LinearizedStep full = linearized_step(ch, dt);
  const Positions x_full = step_by(x0, full, 1.0);
  double largest = 0.0;
  for (const auto& d : full.dx) largest = std::max(largest, std::hypot(d[0], d[1], d[2]));
  ASSERT_GT(largest, 1e-2);

  solve_distance_forest(ch.p.view(), ch.c, ch.forest, dt, nullptr);
  const Positions x1 = ch.predicted();
  for (std::size_t v = 0; v < 3; ++v)
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(x1[v][a], x_full[v][a], 1e-6) << "vertex " << v;
  for (std::size_t e = 0; e < 2; ++e)
    EXPECT_NEAR(ch.c.lambda[e], full.dlambda[e], 1e-6) << "edge " << e;
}

}  // namespace
