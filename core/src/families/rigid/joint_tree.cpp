// The exact solve of the ball, hinge and fixed joints along spanning trees of the bodies (the
// math is in joint_tree.hpp): the forest's construction, and one iteration's elimination and back
// substitution with small dense blocks (6 x 6 bodies, m x m joints, Cholesky factors).
#include "joint_tree.hpp"

#include "portable_trig.hpp"

#include <algorithm>
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

// The same for a joint's n x n block (n <= 6, row-major with stride n), the same operations.
template <int n>
bool cholesky_block(std::array<double, 36>& a) {
  for (int j = 0; j < n; ++j) {
    double d = a[std::size_t(j * n + j)];
    for (int k = 0; k < j; ++k) d -= a[std::size_t(j * n + k)] * a[std::size_t(j * n + k)];
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    const double l = std::sqrt(d);
    a[std::size_t(j * n + j)] = l;
    for (int i = j + 1; i < n; ++i) {
      double s = a[std::size_t(i * n + j)];
      for (int k = 0; k < j; ++k) s -= a[std::size_t(i * n + k)] * a[std::size_t(j * n + k)];
      a[std::size_t(i * n + j)] = s / l;
    }
  }
  return true;
}

template <int n>
std::array<double, 6> cholesky_block_solve(const std::array<double, 36>& l, std::array<double, 6> b) {
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < i; ++k) b[std::size_t(i)] -= l[std::size_t(i * n + k)] * b[std::size_t(k)];
    b[std::size_t(i)] /= l[std::size_t(i * n + i)];
  }
  for (int i = n - 1; i >= 0; --i) {
    for (int k = i + 1; k < n; ++k) b[std::size_t(i)] -= l[std::size_t(k * n + i)] * b[std::size_t(k)];
    b[std::size_t(i)] /= l[std::size_t(i * n + i)];
  }
  return b;
}

using Rows = std::array<double, 6>;
using Jacobian = std::array<double, 36>;  // m x 6, row-major

// The directions of a joint's angular rows (joint_tree.hpp): the hinge's two t_k, the fixed
// joint's and slider's world axes, the universal joint's n.
struct AngularRows {
  int count = 0;
  Vec3d t[3];
};

AngularRows angular_rows(const TreeLink& j, const RigidBody& a, const RigidBody& b) {
  if (j.type == TreeJointType::Hinge)
    return {2, {rotate(a.q, j.normal_a), rotate(a.q, cross(j.axis_a, j.normal_a)), {}}};
  if (j.type == TreeJointType::Fixed || j.type == TreeJointType::Slider)
    return {3, {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}};
  if (j.type == TreeJointType::Universal) {
    // n = a_a x a_b / |a_a x a_b|; with the axes parallel (no direction preferred), t_1 above.
    const Vec3d axis_a = rotate(a.q, j.axis_a);
    const Vec3d c = cross(axis_a, rotate(b.q, j.axis_b));
    const double s = length(c);
    return {1, {s > 0.0 ? (1.0 / s) * c : rotate(a.q, j.normal_a), {}, {}}};
  }
  return {};
}

// The slider's positional rows: the directions t_1 = R_a s_a, t_2 = R_a (u_a x s_a) across its
// axis (none for the other types, whose three rows are the world axes).
struct AcrossRows {
  bool slider = false;
  Vec3d t[2];
};

AcrossRows across_rows(const TreeLink& j, const RigidBody& a) {
  if (j.type != TreeJointType::Slider) return {};
  return {true, {rotate(a.q, j.normal_a), rotate(a.q, cross(j.axis_a, j.normal_a))}};
}

int positional_rows(TreeJointType type) { return type == TreeJointType::Slider ? 2 : 3; }

// The joint's rows for one of its bodies: sign [I, -[r]x] (the connector point's move, times
// sign, for a body move (dp, dtheta)), or the slider's sign [t_k^T, (r x t_k)^T]; then sign
// [0, t_k^T] per angular row. r: the body's lever (for a slider's body a, to P_b: joint_tree.hpp).
Jacobian link_jacobian(double sign, Vec3d r, const AcrossRows& across, const AngularRows& angular) {
  Jacobian j{sign, 0.0,  0.0,  0.0,         sign * r.z,  -sign * r.y,  //
             0.0,  sign, 0.0,  -sign * r.z, 0.0,         sign * r.x,   //
             0.0,  0.0,  sign, sign * r.y,  -sign * r.x, 0.0};
  int first_angular = 3;
  if (across.slider) {
    j = {};
    for (int k = 0; k < 2; ++k) {
      const Vec3d t = sign * across.t[k], turn = cross(r, t);
      const double row[6] = {t.x, t.y, t.z, turn.x, turn.y, turn.z};
      for (int c = 0; c < 6; ++c) j[std::size_t(k * 6 + c)] = row[c];
    }
    first_angular = 2;
  }
  for (int k = 0; k < angular.count; ++k) {
    const Vec3d t = sign * angular.t[k];
    const int row = first_angular + k;
    j[std::size_t(row * 6 + 3)] = t.x, j[std::size_t(row * 6 + 4)] = t.y, j[std::size_t(row * 6 + 5)] = t.z;
  }
  return j;
}

// C_e on the bodies as they are: P_b - P_a (the slider's across its axis), then the angular rows.
Rows link_error(const TreeLink& j, const RigidBody& a, const RigidBody& b, const AcrossRows& across,
                const AngularRows& angular) {
  const Vec3d d = b.world_point(j.anchor_b) - a.world_point(j.anchor_a);
  Rows c{d.x, d.y, d.z, 0.0, 0.0, 0.0};
  if (j.type == TreeJointType::Hinge) {
    const Vec3d e = rotation_between(rotate(a.q, j.axis_a), rotate(b.q, j.axis_b));
    c[3] = dot(angular.t[0], e), c[4] = dot(angular.t[1], e);
  } else if (j.type == TreeJointType::Fixed) {
    const Vec3d e = rotation_vector(b.q * conjugate(a.q * j.rest_rotation));
    c[3] = e.x, c[4] = e.y, c[5] = e.z;
  } else if (j.type == TreeJointType::Slider) {
    const Vec3d e = rotation_vector(b.q * conjugate(a.q * j.rest_rotation));
    c = {dot(across.t[0], d), dot(across.t[1], d), e.x, e.y, e.z, 0.0};
  } else if (j.type == TreeJointType::Universal) {
    // The angle between the axes less 90 degrees (joint.hpp's off-perpendicular error along n).
    const Vec3d axis_a = rotate(a.q, j.axis_a), axis_b = rotate(b.q, j.axis_b);
    c[3] = -portable_atan2(dot(axis_a, axis_b), length(cross(axis_a, axis_b)));
  }
  return c;
}

int rows_of(TreeJointType type) {
  switch (type) {
    case TreeJointType::Ball: return 3;
    case TreeJointType::Universal: return 4;
    case TreeJointType::Hinge:
    case TreeJointType::Slider: return 5;
    case TreeJointType::Fixed: return 6;
  }
  return 3;
}

// The lever of body a's rows: r_a, but for a slider P_b - x_a (its rows across the axis turn with
// body a, so they act at P_b on both bodies: joint_tree.hpp).
Vec3d lever_a(const TreeLink& j, const RigidBody& a, const RigidBody& b, Vec3d r_a) {
  return j.type == TreeJointType::Slider ? b.world_point(j.anchor_b) - a.x : r_a;
}

// j z for an m x 6 j.
template <int m>
Rows times(const Jacobian& j, const std::array<double, 6>& z) {
  Rows out{};
  for (int i = 0; i < m; ++i) {
    out[std::size_t(i)] = 0.0;
    for (int k = 0; k < 6; ++k) out[std::size_t(i)] += j[std::size_t(i * 6 + k)] * z[std::size_t(k)];
  }
  return out;
}

// a v for an m x m a.
template <int m>
Rows times_square(const std::array<double, 36>& a, const Rows& v) {
  Rows out{};
  for (int i = 0; i < m; ++i) {
    double sum = a[std::size_t(i * m)] * v[0];
    for (int k = 1; k < m; ++k) sum += a[std::size_t(i * m + k)] * v[std::size_t(k)];
    out[std::size_t(i)] = sum;
  }
  return out;
}

double squared_norm(const Rows& v, int m) {
  double sum = v[0] * v[0];
  for (int k = 1; k < m; ++k) sum += v[std::size_t(k)] * v[std::size_t(k)];
  return sum;
}

double norm(const Rows& v, int m) { return std::sqrt(squared_norm(v, m)); }

// diag(m I, I_world) of a movable body turned to q (R I R^T).
std::array<double, 36> generalized_mass(const RigidBody& b, Quatd q) {
  std::array<double, 36> k{};
  const double m = 1.0 / b.inverse_mass;
  k[0] = k[7] = k[14] = m;
  const auto turned = [&](Vec3d v) { return rotate(q, scale(b.inertia, rotate_back(q, v))); };
  const Vec3d columns[3] = {turned({1.0, 0.0, 0.0}), turned({0.0, 1.0, 0.0}), turned({0.0, 0.0, 1.0})};
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

// The load a joint is expected to carry, in weights of its subtree: a pendulum let go from
// horizontal pulls 3 m g at the bottom of its swing.
constexpr double kSwingLoad = 3.0;
// The largest trace(I^-1 K_geo) of a body (joint_tree.hpp) at which its tree takes the start
// directions: measured, the pendulums at 8 x 2 reach 0.03 (double) and 0.3 (triple); the trees
// whose energy must never rise start at 1.3 (the Y), 2.9 (100 links), 30 (1:1000).
constexpr double kStartDirectionsLoad = 0.6;

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

// The geometric stiffness's weight at a connector (joint_tree.hpp, start directions): the trace
// of I^-1 (I - n n^T) |r| = |r| (tr I^-1 - n^T I^-1 n), n = r / |r|, in the body frame (r the
// anchor); 0 at the centre of mass. Times |f| it is trace(I^-1 K_geo) of that connector.
double lever_weight(const RigidBody& b, Vec3d anchor) {
  const double r2 = dot(anchor, anchor);
  if (!(r2 > 0.0)) return 0.0;
  const Vec3d& inv = b.inverse_inertia;
  return (r2 * (inv.x + inv.y + inv.z) - dot(anchor, scale(inv, anchor))) / std::sqrt(r2);
}

int find_root(std::vector<int>& root, int v) {
  while (root[std::size_t(v)] != v) v = root[std::size_t(v)] = root[std::size_t(root[std::size_t(v)])];
  return v;
}

}  // namespace

Vec3d rotation_between(Vec3d u, Vec3d v) {
  const Vec3d c = cross(u, v);
  const double s = length(c);
  if (!(s > 0.0)) return {};
  return (portable_atan2(s, dot(u, v)) / s) * c;
}

JointTreeSolver::JointTreeSolver(std::span<const TreeLink> links, std::span<const RigidBody> bodies, Vec3d gravity)
    : links_(links.begin(), links.end()), in_forest_(links.size(), 0) {
  const int ground = int(bodies.size());
  const auto node_of = [&](int body) { return body < 0 || bodies[std::size_t(body)].fixed() ? ground : body; };
  std::vector<int> root(std::size_t(ground) + 1);
  std::iota(root.begin(), root.end(), 0);
  std::vector<std::vector<std::pair<int, int>>> adjacent(std::size_t(ground) + 1);  // (other node, joint)
  for (std::size_t e = 0; e < links_.size(); ++e) {
    const TreeLink& j = links_[e];
    const int a = node_of(j.body_a), b = node_of(j.body_b);
    const int root_a = find_root(root, a), root_b = find_root(root, b);
    if (root_a == root_b) continue;  // closes a loop: the iterative solve keeps it
    root[std::size_t(root_a)] = root_b;
    in_forest_[e] = 1;
    adjacent[std::size_t(a)].push_back({b, int(e)});
    adjacent[std::size_t(b)].push_back({a, int(e)});
  }
  std::vector<char> seen(std::size_t(ground) + 1, 0);
  const auto node_of_link = [&](int body, int parent, int e) {
    const TreeJointType type = links_[std::size_t(e)].type;
    return Node{body, parent, e, links_[std::size_t(e)].body_b == body, rows_of(type), positional_rows(type), {}, {}, {}};
  };
  const auto grow = [&](std::size_t from) {  // breadth first from the nodes pushed since `from`
    for (std::size_t p = from; p < nodes_.size(); ++p)
      for (const auto& [other, e] : adjacent[std::size_t(nodes_[p].body)])
        if (!seen[std::size_t(other)]) {
          seen[std::size_t(other)] = 1;
          nodes_.push_back(node_of_link(other, int(p), e));
        }
  };
  // One tree per joint to the ground (the ground is fixed, so they are independent), then one
  // per piece that does not reach it.
  seen[std::size_t(ground)] = 1;
  tree_start_.push_back(0);
  for (const auto& [other, e] : adjacent[std::size_t(ground)]) {
    if (seen[std::size_t(other)]) continue;
    seen[std::size_t(other)] = 1;
    nodes_.push_back(node_of_link(other, -1, e));
    grow(tree_start_.back());
    tree_start_.push_back(nodes_.size());
  }
  for (int v = 0; v < ground; ++v) {
    if (seen[std::size_t(v)] || adjacent[std::size_t(v)].empty()) continue;
    seen[std::size_t(v)] = 1;
    nodes_.push_back({v, -1, -1, true, 3, 3, {}, {}, {}});
    grow(tree_start_.back());
    tree_start_.push_back(nodes_.size());
  }
  work_.resize(nodes_.size());
  tree_of_body_.assign(bodies.size(), -1);
  end_directions_only_.assign(tree_start_.size() - 1, 0);
  for (std::size_t t = 0; t + 1 < tree_start_.size(); ++t)
    for (std::size_t i = tree_start_[t]; i < tree_start_[t + 1]; ++i) tree_of_body_[std::size_t(nodes_[i].body)] = int(t);
  for (Node& n : nodes_) {
    if (n.link < 0) continue;
    const TreeLink& j = links_[std::size_t(n.link)];
    const auto lever = [&](int body, Vec3d anchor) {
      return body < 0 ? 0.0 : lever_weight(bodies[std::size_t(body)], anchor);
    };
    n.lever_own = n.body_is_b ? lever(j.body_b, j.anchor_b) : lever(j.body_a, j.anchor_a);
    n.lever_parent = n.parent < 0 ? 0.0 : n.body_is_b ? lever(j.body_a, j.anchor_a) : lever(j.body_b, j.anchor_b);
  }
  // The subtrees' masses, leaves first (children after their parents).
  std::vector<double> carried(nodes_.size(), 0.0);
  for (std::size_t i = nodes_.size(); i-- > 0;) {
    carried[i] += 1.0 / bodies[std::size_t(nodes_[i].body)].inverse_mass;
    if (nodes_[i].parent >= 0) carried[std::size_t(nodes_[i].parent)] += carried[i];
    nodes_[i].swing_force = kSwingLoad * length(gravity) * carried[i];
  }
  for (std::size_t e = 0; e < links_.size(); ++e)
    if (!in_forest_[e]) keep_end_directions_at(links_[e].body_a), keep_end_directions_at(links_[e].body_b);
}

void JointTreeSolver::keep_end_directions_at(int body) {
  if (body < 0 || std::size_t(body) >= tree_of_body_.size() || tree_of_body_[std::size_t(body)] < 0) return;
  end_directions_only_[std::size_t(tree_of_body_[std::size_t(body)])] = 1;
}

bool JointTreeSolver::start_directions(std::size_t t, double h) {
  if (end_directions_only_[t]) return false;
  const std::size_t begin = tree_start_[t], end = tree_start_[t + 1];
  for (std::size_t i = begin; i < end; ++i) work_[i].load = 0.0;
  for (std::size_t i = begin; i < end; ++i) {
    const Node& n = nodes_[i];
    const double force = std::max(length(n.previous_lambda), n.swing_force * h * h);
    work_[i].load += force * n.lever_own;
    if (n.parent >= 0) work_[std::size_t(n.parent)].load += force * n.lever_parent;
  }
  double worst = 0.0;
  for (std::size_t i = begin; i < end; ++i) worst = std::max(worst, work_[i].load);
  return worst < kStartDirectionsLoad;
}

Vec3d JointTreeSolver::positional_impulse(const Node& n) {
  return n.positional == 2 ? n.impulse : Vec3d{n.lambda[0], n.lambda[1], n.lambda[2]};
}

void JointTreeSolver::reset_multipliers() {
  for (Node& n : nodes_) n.previous_lambda = positional_impulse(n), n.impulse = {}, n.lambda = {};
}

std::vector<Vec3d> JointTreeSolver::multipliers() const {
  std::vector<Vec3d> lambdas;
  for (const Node& n : nodes_) lambdas.push_back(positional_impulse(n));
  for (const Node& n : nodes_) {
    const std::size_t first = std::size_t(n.positional);  // the first angular row
    if (n.rows > 3) lambdas.push_back({n.lambda[first], n.lambda[first + 1], n.lambda[first + 2]});
  }
  return lambdas;
}

void JointTreeSolver::restore_multipliers(std::span<const Vec3d> lambdas) {
  std::size_t next = 0;
  for (Node& n : nodes_)
    if (next < lambdas.size()) {
      n.impulse = lambdas[next++];
      if (n.positional == 3) n.lambda[0] = n.impulse.x, n.lambda[1] = n.impulse.y, n.lambda[2] = n.impulse.z;
    }
  for (Node& n : nodes_) {
    const std::size_t first = std::size_t(n.positional);
    if (n.rows > 3 && next < lambdas.size())
      n.lambda[first] = lambdas[next].x, n.lambda[first + 1] = lambdas[next].y, n.lambda[first + 2] = lambdas[next].z, ++next;
  }
}

template <int m>
bool JointTreeSolver::eliminate(std::size_t i, const RigidBody& a, const RigidBody& b, double inverse_h2, bool start) {
  const Node& n = nodes_[i];
  Work& w = work_[i];
  const TreeLink& j = links_[std::size_t(n.link)];
  // The rows' directions: at the start of the substep (the bodies turned back to q_prev), or as
  // the bodies are now.
  RigidBody a_start, b_start;
  if (start) a_start = a, b_start = b, a_start.q = a.q_prev, b_start.q = b.q_prev;
  const RigidBody& da = start ? a_start : a;
  const RigidBody& db = start ? b_start : b;
  const Vec3d r_a = lever_a(j, da, db, rotate(da.q, j.anchor_a)), r_b = rotate(db.q, j.anchor_b);
  const AcrossRows across = across_rows(j, da);
  const AngularRows angular = angular_rows(j, da, db);
  w.across[0] = across.t[0], w.across[1] = across.t[1];
  const Jacobian own = n.body_is_b ? link_jacobian(1.0, r_b, across, angular) : link_jacobian(-1.0, r_a, across, angular);
  w.jp = n.parent < 0                ? Jacobian{}
         : n.body_is_b ? link_jacobian(-1.0, r_a, across, angular) : link_jacobian(1.0, r_b, across, angular);
  for (int c = 0; c < m; ++c) {  // G = K^-1 J_ev^T, column by column
    const Vec6 column = cholesky_solve<6>(w.k, {own[std::size_t(c * 6)], own[std::size_t(c * 6 + 1)], own[std::size_t(c * 6 + 2)],
                                                own[std::size_t(c * 6 + 3)], own[std::size_t(c * 6 + 4)], own[std::size_t(c * 6 + 5)]});
    for (int k = 0; k < 6; ++k) w.g[std::size_t(k * m + c)] = column[std::size_t(k)];
  }
  const double alpha = j.compliance * inverse_h2;
  std::array<double, 36> d{};
  for (int row = 0; row < m; ++row)
    for (int c = 0; c < m; ++c) {
      double sum = row == c ? alpha : 0.0;
      for (int k = 0; k < 6; ++k) sum += own[std::size_t(row * 6 + k)] * w.g[std::size_t(k * m + c)];
      d[std::size_t(row * m + c)] = sum;
    }
  if (!cholesky_block<m>(d)) return false;
  for (int c = 0; c < m; ++c) {
    Rows unit{};
    unit[std::size_t(c)] = 1.0;
    const Rows column = cholesky_block_solve<m>(d, unit);
    for (int row = 0; row < m; ++row) w.d_inv[std::size_t(row * m + c)] = column[std::size_t(row)];
  }
  w.alpha = alpha;
  const Rows error = start ? link_error(j, a, b, across_rows(j, a), angular_rows(j, a, b)) : link_error(j, a, b, across, angular);
  const Rows moved = times<m>(own, w.u);
  Rows rest{};
  for (int row = 0; row < m; ++row) {
    w.b[std::size_t(row)] = -error[std::size_t(row)] - alpha * n.lambda[std::size_t(row)];
    rest[std::size_t(row)] = w.b[std::size_t(row)] - moved[std::size_t(row)];
  }
  w.s = times_square<m>(w.d_inv, rest);
  if (n.parent < 0) return true;
  // The parent's K += J_ep^T D^-1 J_ep, r += J_ep^T s.
  Work& p = work_[std::size_t(n.parent)];
  std::array<double, 36> x{};  // D^-1 J_ep
  for (int row = 0; row < m; ++row)
    for (int k = 0; k < 6; ++k)
      for (int l = 0; l < m; ++l)
        x[std::size_t(row * 6 + k)] += w.d_inv[std::size_t(row * m + l)] * w.jp[std::size_t(l * 6 + k)];
  for (int row = 0; row < 6; ++row) {
    for (int c = 0; c < 6; ++c)
      for (int l = 0; l < m; ++l)
        p.k[std::size_t(row * 6 + c)] += w.jp[std::size_t(l * 6 + row)] * x[std::size_t(l * 6 + c)];
    double sum = w.jp[std::size_t(row)] * w.s[0];
    for (int l = 1; l < m; ++l) sum += w.jp[std::size_t(l * 6 + row)] * w.s[std::size_t(l)];
    p.r[std::size_t(row)] += sum;
  }
  return true;
}

template <int m>
void JointTreeSolver::substitute(std::size_t i) {
  const Node& n = nodes_[i];
  Work& w = work_[i];
  const Rows across = n.parent < 0 ? Rows{} : times<m>(w.jp, work_[std::size_t(n.parent)].dx);
  const Rows pulled = times_square<m>(w.d_inv, across);
  for (int row = 0; row < m; ++row) w.dlambda[std::size_t(row)] = w.s[std::size_t(row)] - pulled[std::size_t(row)];
  for (int k = 0; k < 6; ++k) {
    double sum = w.u[std::size_t(k)];
    for (int c = 0; c < m; ++c) sum += w.g[std::size_t(k * m + c)] * w.dlambda[std::size_t(c)];
    w.dx[std::size_t(k)] = sum;
  }
}

void JointTreeSolver::solve(std::span<RigidBody> bodies, double h) {
  if (nodes_.empty()) return;
  const double inverse_h2 = 1.0 / (h * h);
  const RigidBody world;
  const auto body = [&](int k) -> const RigidBody& { return k < 0 ? world : bodies[std::size_t(k)]; };
  for (std::size_t t = 0; t + 1 < tree_start_.size(); ++t) {
    const bool start = start_directions(t, h);
    for (std::size_t i = tree_start_[t]; i < tree_start_[t + 1]; ++i) work_[i].start = start;
  }
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const RigidBody& v = bodies[std::size_t(nodes_[i].body)];
    work_[i].k = generalized_mass(v, work_[i].start ? v.q_prev : v.q);
    work_[i].r = {};
  }
  // Geometric stiffness: each body pulled at its connector by the previous substep's impulse.
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const Node& n = nodes_[i];
    if (n.link < 0 || work_[i].start) continue;
    const TreeLink& j = links_[std::size_t(n.link)];
    const RigidBody &a = body(j.body_a), &b = body(j.body_b);
    const Vec3d r_a = lever_a(j, a, b, rotate(a.q, j.anchor_a)), r_b = rotate(b.q, j.anchor_b);
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
    const TreeLink& j = links_[std::size_t(n.link)];
    const RigidBody &a = body(j.body_a), &b = body(j.body_b);
    const bool factored = n.rows == 3   ? eliminate<3>(i, a, b, inverse_h2, w.start)
                          : n.rows == 4 ? eliminate<4>(i, a, b, inverse_h2, w.start)
                          : n.rows == 5 ? eliminate<5>(i, a, b, inverse_h2, w.start)
                                        : eliminate<6>(i, a, b, inverse_h2, w.start);
    if (!factored) return;
  }
  // Roots to leaves.
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const Node& n = nodes_[i];
    if (n.link < 0) {
      work_[i].dx = work_[i].u;
      continue;
    }
    if (n.rows == 3) substitute<3>(i);
    else if (n.rows == 4) substitute<4>(i);
    else if (n.rows == 5) substitute<5>(i);
    else substitute<6>(i);
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
    const TreeLink& j = links_[std::size_t(n.link)];
    const RigidBody &a = body(j.body_a), &b = body(j.body_b);
    const Rows error = link_error(j, a, b, across_rows(j, a), angular_rows(j, a, b));
    Rows residual{};
    for (int row = 0; row < n.rows; ++row)
      residual[std::size_t(row)] = error[std::size_t(row)] + w.alpha * (n.lambda[std::size_t(row)] + beta * w.dlambda[std::size_t(row)]);
    penalty += norm(w.dlambda, n.rows) * norm(residual, n.rows);
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
      decrease += norm(w.dlambda, nodes_[i].rows) * norm(w.b, nodes_[i].rows);
      quadratic += w.alpha * squared_norm(w.dlambda, nodes_[i].rows);
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
  for (std::size_t i = begin; i < end; ++i) {
    Node& n = nodes_[i];
    for (int row = 0; row < n.rows; ++row) n.lambda[std::size_t(row)] += beta * work_[i].dlambda[std::size_t(row)];
    if (n.positional == 2) n.impulse = n.lambda[0] * work_[i].across[0] + n.lambda[1] * work_[i].across[1];
  }
}

}  // namespace seiche::rigid
