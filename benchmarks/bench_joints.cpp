// One iteration of the rigid joints' solve on a chain of n links on ball joints hanging from
// the world (Müller et al. 2020's chain; Bender's PositionBasedDynamics ChainDemo): the exact
// tree solve (core/src/families/rigid/joint_tree.hpp) or Gauss-Seidel over the joints in order
// (solver.joint_trees false). Links are 0.1 x 0.02 x 0.02 m boxes of 4 g, the chain starts
// horizontal and is predicted one substep (1/480 s) under gravity, then every call solves one
// iteration from that state with multipliers 0 (restored untimed). Serial: the joints' solve
// runs on one thread at any thread count. Args: n links. Reported: ns per joint solve
// (s_per_joint: the call's time / n).
#include <benchmark/benchmark.h>

#include <vector>

#include "families/rigid/joint.hpp"
#include "families/rigid/rigid_body.hpp"

using namespace seiche::rigid;

namespace {

constexpr double kSubstep = 1.0 / 480.0;

struct Chain {
  std::vector<RigidBody> bodies;
  std::vector<Joint> joints;
};

Chain make_chain(int links) {
  Chain c;
  const double mass = 0.004, length = 0.1, width = 0.02;
  const Vec3d inertia{mass * (2 * width * width) / 12.0, mass * (length * length + width * width) / 12.0,
                      mass * (length * length + width * width) / 12.0};
  for (int k = 0; k < links; ++k) {
    c.bodies.push_back(make_body({length * (k + 0.5), 0.0, 0.0}, {}, {}, {}, mass, inertia, false));
    Joint j;
    j.body_a = k - 1;  // -1: the world
    j.body_b = k;
    j.anchor_a = k == 0 ? Vec3d{0.0, 0.0, 0.0} : Vec3d{0.5 * length, 0.0, 0.0};
    j.anchor_b = {-0.5 * length, 0.0, 0.0};
    c.joints.push_back(j);
  }
  for (RigidBody& b : c.bodies) predict_body(b, {0.0, -9.81, 0.0}, kSubstep);
  return c;
}

void BM_ChainJointSolve(benchmark::State& state, bool trees) {
  const Chain setup = make_chain(int(state.range(0)));
  std::vector<RigidBody> bodies = setup.bodies;
  JointSolver solver(setup.joints, bodies, trees);
  for (auto _ : state) {
    state.PauseTiming();
    bodies = setup.bodies;
    solver.reset_multipliers();
    state.ResumeTiming();
    solver.solve(bodies, kSubstep);
    benchmark::ClobberMemory();
  }
  const double joints = double(setup.joints.size());
  state.counters["joints"] = joints;
  state.counters["tree_joints"] = double(solver.tree_joints());
  state.counters["s_per_joint"] =
      benchmark::Counter(joints, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK_CAPTURE(BM_ChainJointSolve, tree, true)->Arg(20)->Arg(100)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_ChainJointSolve, gauss_seidel, false)->Arg(20)->Arg(100)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
