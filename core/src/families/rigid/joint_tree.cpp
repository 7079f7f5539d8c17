// The exact solve of the ball joints along spanning trees of the bodies (the math is in
// joint_tree.hpp): the forest's construction, and one iteration's elimination and back
// substitution with small dense blocks (6 x 6 bodies, 3 x 3 joints, Cholesky factors).
#include "joint_tree.hpp"

#include <cmath>
#include <numeric>
#include <utility>

namespace seiche::rigid {

namespace {

// Cholesky factor L of the SPD n x n matrix a (row-major, lower triangle in place); false when
// a pivot is not positive (or not finite), a untouched above it.
template <int N>
bool cholesky(std::array<double, N * N>& a) {
  for (int j = 0; j < N; ++j) {
    double d = a[j * N + j];
    for (int k = 0; k < j; ++k) d -= a[j * N + k] * a[j * N + k];
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    const double l = std::sqrt(d);
    a[j * N + j] = l;
    for (int i = j + 1; i < N; ++i) {
      double s = a[i * N + j];
      for (int k = 0; k < j; ++k) s -= a[i * N + k] * a[j * N + k];
      a[i * N + j] = s / l;
    }
  }
  return true;
}

// (L L^T)^-1 b.
template <int N>
std::array<double, N> cholesky_solve(const std::array<double, N * N>& l, std::array<double, N> b) {
  for (int i = 0; i < N; ++i) {
    for (int k = 0; k < i; ++k) b[i] -= l[i * N + k] * b[k];
    b[i] /= l[i * N + i];
  }
  for (int i = N - 1; i >= 0; --i) {
    for (int k = i + 1; k < N; ++k) b[i] -= l[k * N + i] * b[k];
    b[i] /= l[i * N + i];
  }
  return b;
}

using Jacobian = std::array<double, 18>;  // 3 x 6, row-major

// sign [I, -[r]x]: the connector point's move (times sign) for a body move (dp, dtheta).
Jacobian connector_jacobian(double sign, Vec3d r) {
  return {sign, 0.0,  0.0,  0.0,         sign * r.z,  -sign * r.y,  //
          0.0,  sign, 0.0,  -sign * r.z, 0.0,         sign * r.x,   //
          0.0,  0.0,  sign, sign * r.y,  -sign * r.x, 0.0};
}

Vec3d times(const Jacobian& j, const std::array<double, 6>& z) {
  double out[3];
  for (int i = 0; i < 3; ++i) {
    out[i] = 0.0;
    for (int k = 0; k < 6; ++k) out[i] += j[i * 6 + k] * z[k];
  }
  return {out[0], out[1], out[2]};
}

Vec3d times(const std::array<double, 9>& m, Vec3d v) {
  return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
          m[6] * v.x + m[7] * v.y + m[8] * v.z};
}

// diag(m I, I_world) of a movable body.
std::array<double, 36> generalized_mass(const RigidBody& b) {
  std::array<double, 36> k{};
  const double m = 1.0 / b.inverse_mass;
  k[0] = k[7] = k[14] = m;
  const Vec3d columns[3] = {b.world_inertia({1.0, 0.0, 0.0}), b.world_inertia({0.0, 1.0, 0.0}),
                            b.world_inertia({0.0, 0.0, 1.0})};
  for (int c = 0; c < 3; ++c) {
    const double column[3] = {columns[c].x, columns[c].y, columns[c].z};
    for (int row = 0; row < 3; ++row) k[(3 + row) * 6 + 3 + c] = column[row];
  }
  return k;
}

// The line search (joint_tree.hpp): at most kHalvings halvings of the step, and a step must
// realize kArmijo of the merit's first-order decrease.
constexpr int kHalvings = 4;
constexpr double kArmijo = 0.1;

// The tension part of the geometric stiffness of a body pulled by the impulse f at its lever r
// (joint_tree.hpp): k (I - r r^T / |r|^2) on the rotation block, k = max(f . r, 0).
void add_geometric_stiffness(std::array<double, 36>& k, Vec3d r, Vec3d f) {
  const double r2 = dot(r, r);
  const double stiffness = dot(f, r);
  if (!(r2 > 0.0) || !(stiffness > 0.0)) return;
  const double v[3] = {r.x, r.y, r.z};
  for (int row = 0; row < 3; ++row)
    for (int c = 0; c < 3; ++c)
      k[std::size_t((3 + row) * 6 + 3 + c)] += stiffness * ((row == c ? 1.0 : 0.0) - v[row] * v[c] / r2);
}

int find_root(std::vector<int>& root, int v) {
  while (root[std::size_t(v)] != v) v = root[std::size_t(v)] = root[std::size_t(root[std::size_t(v)])];
  return v;
}

}  // namespace

JointTreeSolver::JointTreeSolver(std::span<const BallLink> links, std::span<const RigidBody> bodies)
    : links_(links.begin(), links.end()), in_forest_(links.size(), 0) {
  const int ground = int(bodies.size());
  const auto node_of = [&](int body) { return body < 0 || bodies[std::size_t(body)].fixed() ? ground : body; };
  std::vector<int> root(std::size_t(ground) + 1);
  std::iota(root.begin(), root.end(), 0);
  std::vector<std::vector<std::pair<int, int>>> adjacent(std::size_t(ground) + 1);  // (other node, joint)
  for (std::size_t e = 0; e < links_.size(); ++e) {
    const BallLink& j = links_[e];
    const int a = node_of(j.body_a), b = node_of(j.body_b);
    const int root_a = find_root(root, a), root_b = find_root(root, b);
    if (root_a == root_b) continue;  // closes a loop: the iterative solve keeps it
    root[std::size_t(root_a)] = root_b;
    in_forest_[e] = 1;
    adjacent[std::size_t(a)].push_back({b, int(e)});
    adjacent[std::size_t(b)].push_back({a, int(e)});
  }
  std::vector<char> seen(std::size_t(ground) + 1, 0);
  const auto grow = [&](std::size_t from) {  // breadth first from the nodes pushed since `from`
    for (std::size_t p = from; p < nodes_.size(); ++p)
      for (const auto& [other, e] : adjacent[std::size_t(nodes_[p].body)])
        if (!seen[std::size_t(other)]) {
          seen[std::size_t(other)] = 1;
          nodes_.push_back({other, int(p), e, links_[std::size_t(e)].body_b == other, {}, {}});
        }
  };
  // One tree per joint to the ground (the ground is fixed, so they are independent), then one
  // per piece that does not reach it.
  seen[std::size_t(ground)] = 1;
  tree_start_.push_back(0);
  for (const auto& [other, e] : adjacent[std::size_t(ground)]) {
    if (seen[std::size_t(other)]) continue;
    seen[std::size_t(other)] = 1;
    nodes_.push_back({other, -1, e, links_[std::size_t(e)].body_b == other, {}, {}});
    grow(tree_start_.back());
    tree_start_.push_back(nodes_.size());
  }
  for (int v = 0; v < ground; ++v) {
    if (seen[std::size_t(v)] || adjacent[std::size_t(v)].empty()) continue;
    seen[std::size_t(v)] = 1;
    nodes_.push_back({v, -1, -1, true, {}, {}});
    grow(tree_start_.back());
    tree_start_.push_back(nodes_.size());
  }
  work_.resize(nodes_.size());
}

void JointTreeSolver::reset_multipliers() {
  for (Node& n : nodes_) n.previous_lambda = n.lambda, n.lambda = {};
}

std::vector<Vec3d> JointTreeSolver::multipliers() const {
  std::vector<Vec3d> lambdas;
  for (const Node& n : nodes_) lambdas.push_back(n.lambda);
  return lambdas;
}

void JointTreeSolver::restore_multipliers(std::span<const Vec3d> lambdas) {
  for (std::size_t i = 0; i < nodes_.size() && i < lambdas.size(); ++i) nodes_[i].lambda = lambdas[i];
}

void JointTreeSolver::solve(std::span<RigidBody> bodies, double h) {
  if (nodes_.empty()) return;
  const double inverse_h2 = 1.0 / (h * h);
  const RigidBody world;
  const auto body = [&](int k) -> const RigidBody& { return k < 0 ? world : bodies[std::size_t(k)]; };
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    work_[i].k = generalized_mass(bodies[std::size_t(nodes_[i].body)]);
    work_[i].r = {};
  }
  // Geometric stiffness: each body pulled at its connector by the previous substep's impulse.
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const Node& n = nodes_[i];
    if (n.link < 0) continue;
    const BallLink& j = links_[std::size_t(n.link)];
    const RigidBody &a = body(j.body_a), &b = body(j.body_b);
    const Vec3d r_a = rotate(a.q, j.anchor_a), r_b = rotate(b.q, j.anchor_b);
    // The impulse on b is +lambda, on a -lambda.
    add_geometric_stiffness(work_[i].k, n.body_is_b ? r_b : r_a, n.body_is_b ? n.previous_lambda : -n.previous_lambda);
    if (n.parent >= 0)
      add_geometric_stiffness(work_[std::size_t(n.parent)].k, n.body_is_b ? r_a : r_b,
                              n.body_is_b ? -n.previous_lambda : n.previous_lambda);
  }
  // Leaves to roots. Nothing moves before every factor exists, so a failed one (a body gone
  // non-finite) leaves the bodies as they are.
  for (std::size_t i = nodes_.size(); i-- > 0;) {
    const Node& n = nodes_[i];
    Work& w = work_[i];
    if (!cholesky<6>(w.k)) return;
    w.u = cholesky_solve<6>(w.k, w.r);
    if (n.link < 0) continue;  // a free root
    const BallLink& j = links_[std::size_t(n.link)];
    const RigidBody &a = body(j.body_a), &b = body(j.body_b);
    const Vec3d r_a = rotate(a.q, j.anchor_a), r_b = rotate(b.q, j.anchor_b);
    const Jacobian own = n.body_is_b ? connector_jacobian(1.0, r_b) : connector_jacobian(-1.0, r_a);
    w.jp = n.parent < 0 ? Jacobian{} : n.body_is_b ? connector_jacobian(-1.0, r_a) : connector_jacobian(1.0, r_b);
    for (int c = 0; c < 3; ++c) {  // G = K^-1 J_ev^T, column by column
      const Vec6 column = cholesky_solve<6>(w.k, {own[c * 6], own[c * 6 + 1], own[c * 6 + 2], own[c * 6 + 3],
                                                  own[c * 6 + 4], own[c * 6 + 5]});
      for (int k = 0; k < 6; ++k) w.g[std::size_t(k * 3 + c)] = column[std::size_t(k)];
    }
    const double alpha = j.compliance * inverse_h2;
    std::array<double, 9> d{};
    for (int row = 0; row < 3; ++row)
      for (int c = 0; c < 3; ++c) {
        double sum = row == c ? alpha : 0.0;
        for (int k = 0; k < 6; ++k) sum += own[std::size_t(row * 6 + k)] * w.g[std::size_t(k * 3 + c)];
        d[std::size_t(row * 3 + c)] = sum;
      }
    if (!cholesky<3>(d)) return;
    for (int c = 0; c < 3; ++c) {
      std::array<double, 3> unit{};
      unit[std::size_t(c)] = 1.0;
      const std::array<double, 3> column = cholesky_solve<3>(d, unit);
      for (int row = 0; row < 3; ++row) w.d_inv[std::size_t(row * 3 + c)] = column[std::size_t(row)];
    }
    w.alpha = alpha;
    w.b = -((b.x + r_b) - (a.x + r_a)) - alpha * n.lambda;
    w.s = times(w.d_inv, w.b - times(own, w.u));
    if (n.parent < 0) continue;
    // The parent's K += J_ep^T D^-1 J_ep, r += J_ep^T s.
    Work& p = work_[std::size_t(n.parent)];
    std::array<double, 18> x{};  // D^-1 J_ep
    for (int row = 0; row < 3; ++row)
      for (int k = 0; k < 6; ++k)
        for (int m = 0; m < 3; ++m)
          x[std::size_t(row * 6 + k)] += w.d_inv[std::size_t(row * 3 + m)] * w.jp[std::size_t(m * 6 + k)];
    for (int row = 0; row < 6; ++row) {
      for (int c = 0; c < 6; ++c)
        for (int m = 0; m < 3; ++m)
          p.k[std::size_t(row * 6 + c)] += w.jp[std::size_t(m * 6 + row)] * x[std::size_t(m * 6 + c)];
      p.r[std::size_t(row)] += w.jp[std::size_t(row)] * w.s.x + w.jp[std::size_t(6 + row)] * w.s.y +
                               w.jp[std::size_t(12 + row)] * w.s.z;
    }
  }
  // Roots to leaves.
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const Node& n = nodes_[i];
    Work& w = work_[i];
    if (n.link < 0) {
      w.dx = w.u;
      continue;
    }
    const Vec3d across = n.parent < 0 ? Vec3d{} : times(w.jp, work_[std::size_t(n.parent)].dx);
    w.dlambda = w.s - times(w.d_inv, across);
    for (int k = 0; k < 6; ++k)
      w.dx[std::size_t(k)] = w.u[std::size_t(k)] + w.g[std::size_t(k * 3)] * w.dlambda.x +
                             w.g[std::size_t(k * 3 + 1)] * w.dlambda.y + w.g[std::size_t(k * 3 + 2)] * w.dlambda.z;
  }
  for (std::size_t t = 0; t + 1 < tree_start_.size(); ++t) line_search(tree_start_[t], tree_start_[t + 1], bodies);
}

double JointTreeSolver::merit_penalty(std::size_t begin, std::size_t end, std::span<const RigidBody> bodies,
                                      double beta) const {
  const RigidBody world;
  const auto body = [&](int k) -> const RigidBody& { return k < 0 ? world : bodies[std::size_t(k)]; };
  double penalty = 0.0;
  for (std::size_t i = begin; i < end; ++i) {
    const Node& n = nodes_[i];
    if (n.link < 0) continue;
    const Work& w = work_[i];
    const BallLink& j = links_[std::size_t(n.link)];
    const RigidBody &a = body(j.body_a), &b = body(j.body_b);
    const Vec3d error = b.world_point(j.anchor_b) - a.world_point(j.anchor_a);
    penalty += length(w.dlambda) * length(error + w.alpha * (n.lambda + beta * w.dlambda));
  }
  return penalty;
}

void JointTreeSolver::line_search(std::size_t begin, std::size_t end, std::span<RigidBody> bodies) {
  double decrease = 0.0, quadratic = 0.0;  // phi(0) = -phi'(0), and the step's M norm squared
  for (std::size_t i = begin; i < end; ++i) {
    Work& w = work_[i];
    const RigidBody& b = bodies[std::size_t(nodes_[i].body)];
    const Vec3d dp{w.dx[0], w.dx[1], w.dx[2]}, dtheta{w.dx[3], w.dx[4], w.dx[5]};
    quadratic += dot(dp, dp) / b.inverse_mass + dot(dtheta, b.world_inertia(dtheta));
    if (nodes_[i].link >= 0) {
      decrease += length(w.dlambda) * length(w.b);
      quadratic += w.alpha * dot(w.dlambda, w.dlambda);
    }
    w.x0 = b.x, w.q0 = b.q;
  }
  if (!(decrease > 0.0)) return;  // the tree's joints are satisfied (b = 0)
  double beta = 1.0;
  for (int k = 0;; ++k) {
    for (std::size_t i = begin; i < end; ++i) {
      const Work& w = work_[i];
      RigidBody& b = bodies[std::size_t(nodes_[i].body)];
      b.x = w.x0 + beta * Vec3d{w.dx[0], w.dx[1], w.dx[2]};
      b.q = rotate_by_small(w.q0, beta * Vec3d{w.dx[3], w.dx[4], w.dx[5]});
    }
    const double phi = 0.5 * beta * beta * quadratic + merit_penalty(begin, end, bodies, beta);
    if (phi <= decrease * (1.0 - kArmijo * beta)) break;
    if (k == kHalvings) {  // no step along this direction helps: the tree stays as it is
      for (std::size_t i = begin; i < end; ++i) {
        RigidBody& b = bodies[std::size_t(nodes_[i].body)];
        b.x = work_[i].x0, b.q = work_[i].q0;
      }
      return;
    }
    beta *= 0.5;
  }
  for (std::size_t i = begin; i < end; ++i) nodes_[i].lambda += beta * work_[i].dlambda;
}

}  // namespace seiche::rigid
