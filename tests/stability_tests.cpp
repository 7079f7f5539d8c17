// The stability suite (seiche/stability.hpp) at its reduced size, as CI runs it, and its judge:
// a case that makes NaN, gains energy or leaves the domain must FAIL.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "families/fluid/fluid_solver.hpp"
#include "seiche/scene_loader.hpp"
#include "seiche/simulation.hpp"
#include "seiche/stability.hpp"

using namespace seiche;

namespace {

class StabilitySuite : public ::testing::TestWithParam<std::size_t> {};

StabilityCase reduced_case(const std::string& name) {
  for (StabilityCase& c : stability_cases(SuiteSize::Reduced))
    if (c.name == name) return c;
  throw std::invalid_argument("no stability case " + name);
}

StabilityCase two_particles(const char* name) {
  StabilityCase c;
  c.name = name;
  c.scene = load_scene_text(R"({ "solver": { "gravity": [0, 0, 0] },
                                 "particles": [ { "x": [0.4, 0.5, 0.5] }, { "x": [0.6, 0.5, 0.5] } ],
                                 "distance_constraints": [ { "i": 0, "j": 1, "rest_length": 0.2 } ] })",
                            name);
  c.duration = 0.5;
  return c;
}

}  // namespace

TEST_P(StabilitySuite, CasePassesAtReducedSize) {
  const StabilityCase c = stability_cases(SuiteSize::Reduced)[GetParam()];
  const StabilityResult r = run_stability_case(c, 0);
  SCOPED_TRACE(c.name + ": " + c.description);
  EXPECT_EQ(r.frames, int(std::lround(c.duration / c.scene.solver.frame_dt)));
  EXPECT_TRUE(r.passed) << r.failure;
  EXPECT_EQ(r.non_finite, 0u);
  EXPECT_EQ(r.outside_domain, 0u);
  EXPECT_EQ(r.lost, 0u);
  EXPECT_LE(r.energy_max, r.energy_start + 0.01 * std::abs(r.energy_start));
  EXPECT_LT(r.final_error, r.error_bound);
}

INSTANTIATE_TEST_SUITE_P(Reduced, StabilitySuite, ::testing::Range<std::size_t>(0, 9),
                         [](const ::testing::TestParamInfo<std::size_t>& info) {
                           return stability_cases(SuiteSize::Reduced)[info.param].name;
                         });

TEST(StabilityJudge, TheSuiteHasTheNineCasesAtBothSizes) {
  const auto full = stability_cases(SuiteSize::Full), reduced = stability_cases(SuiteSize::Reduced);
  ASSERT_EQ(full.size(), 9u);
  ASSERT_EQ(reduced.size(), 9u);
  for (std::size_t k = 0; k < full.size(); ++k) {
    EXPECT_EQ(full[k].name, reduced[k].name);
    EXPECT_EQ(full[k].duration, reduced[k].duration);  // the same simulated time
  }
  // The far-outside case really starts outside: its particles are moved in at creation.
  const StabilityResult r = run_stability_case(reduced[5], 0);
  EXPECT_EQ(reduced[5].name, "far_outside");
  EXPECT_EQ(r.moved_into_domain, 10u);
}

TEST(StabilityJudge, NonFiniteStateFails) {
  StabilityCase c = two_particles("nan");
  c.prepare = [](Simulation& sim) {
    ParticleStore s = sim.particles();
    s.vx[0] = std::numeric_limits<float>::quiet_NaN();
    sim.restore_state(s, 0);
  };
  const StabilityResult r = run_stability_case(c, 1);
  EXPECT_FALSE(r.passed);
  EXPECT_GT(r.non_finite, 0u);
  EXPECT_NE(r.failure.find("non-finite"), std::string::npos) << r.failure;
}

TEST(StabilityJudge, EnergyGainFails) {
  // A soft spring starts compressed to half its rest length: it oscillates, making kinetic energy
  // from nothing the judge counts (E has no elastic term), as an energy-making solver would.
  StabilityCase c = two_particles("gain");
  c.scene.distance_constraints[0].rest_length = 0.4f;
  c.scene.distance_constraints[0].compliance = 0.01f;
  const StabilityResult r = run_stability_case(c, 1);
  EXPECT_FALSE(r.passed);
  EXPECT_GT(r.energy_max, r.energy_start);
  EXPECT_NE(r.failure.find("energy grew"), std::string::npos) << r.failure;
}

TEST(StabilityJudge, LargeConstraintErrorFails) {
  // A spring so soft (1e9 m/N) that it does not pull: the pair stays 0.2 m apart against a rest
  // length of 0.05 m, |C| / l0 = 3, past the bound of 1.
  StabilityCase c = two_particles("error");
  c.scene.distance_constraints[0].rest_length = 0.05f;
  c.scene.distance_constraints[0].compliance = 1e9f;
  const StabilityResult r = run_stability_case(c, 1);
  EXPECT_FALSE(r.passed);
  EXPECT_EQ(r.error_family, "distance");
  EXPECT_GT(r.final_error, 1.0);
  EXPECT_NE(r.failure.find("distance error"), std::string::npos) << r.failure;
}

// ---- The fluid's density tolerance -------------------------------------------------------------

TEST(FluidSafeguards, TheDensityToleranceResolvesSubstepsTenTimesTooLong) {
  // The dam break at 1/48 s substeps: two fixed iterations leave the collapsing column 24 %
  // compressed, and its rebound gains 14 % energy; iterating to a 1 % mean error does not.
  StabilityCase c = reduced_case("time_step_10x");
  ASSERT_EQ(c.scene.solver.density_tolerance, 0.01f);  // the default
  const StabilityResult with_tolerance = run_stability_case(c, 0);
  EXPECT_TRUE(with_tolerance.passed) << with_tolerance.failure;
  c.scene.solver.density_tolerance = 0.0f;
  const StabilityResult fixed_iterations = run_stability_case(c, 0);
  EXPECT_FALSE(fixed_iterations.passed);
  EXPECT_GT(fixed_iterations.energy_max, 1.05 * fixed_iterations.energy_start);
}

TEST(FluidSafeguards, ExtraIterationsRunOnlyWhileTheFluidIsTooCompressed) {
  SceneDef scene = load_scene_text(default_scene_json(), "dam break",
                                   std::vector<std::string>{"fluids.0.spacing=0.05", "solver.frame_dt=0.166667"});
  Simulation sim(scene);
  const FrameMetrics first = sim.step_frame();  // the column collapses: more iterations
  EXPECT_GT(first.iterations_max, scene.solver.iterations);
  EXPECT_LE(first.iterations_max, scene.solver.max_iterations);
  EXPECT_GT(first.iterations_mean, double(scene.solver.iterations));
  // At the default 1/480 s substeps the same fluid never needs more than the fixed two.
  scene.solver.frame_dt = 1.0 / 60.0;
  Simulation calm(scene);
  for (int f = 0; f < 20; ++f) {
    const FrameMetrics m = calm.step_frame();
    EXPECT_EQ(m.iterations_max, scene.solver.iterations) << "frame " << f + 1;
  }
}

TEST(FluidSafeguards, ArtificialPressureIsTheSameForceAtMoreSubsteps) {
  // s_corr pushed per iteration whatever dt: at 32 and 48 substeps its force (1/dt^2) made two
  // colliding columns gain 9 % and 91 % energy. Scaled by (dt / (1/480 s))^2 it does not.
  SolverDef solver;
  EXPECT_EQ(tensile_substep_scale(solver), 1.0);  // the default substep is the reference
  solver.substeps = 16;
  EXPECT_NEAR(tensile_substep_scale(solver), 0.25, 1e-12);
  solver.substeps = 2;
  EXPECT_EQ(tensile_substep_scale(solver), 1.0);  // longer substeps: the paper's push, no more
  for (int substeps : {32, 48}) {
    StabilityCase c = reduced_case("columns_50ms");
    c.scene.solver.substeps = substeps;
    const StabilityResult r = run_stability_case(c, 0);
    EXPECT_TRUE(r.passed) << substeps << " substeps: " << r.failure;
  }
}

TEST(FluidSafeguards, ArtificialPressurePushesNoPairBeyondTheRestSpacing) {
  // A 6^3 block at spacing 0.05 m: nearly every particle is within a kernel radius of the free
  // surface. The paper's s_corr, still pushing at the rest spacing, lifted it (+21 % energy by
  // frame 6); s_corr shifted to 0 at the rest spacing does not, and neither does k = 0.
  StabilityCase c = reduced_case("fluid_coarse_block");
  ASSERT_EQ(c.scene.solver.tensile_k, 0.05f);  // the default
  ASSERT_EQ(c.scene.fluids[0].spacing, 0.05f);
  const StabilityResult r = run_stability_case(c, 0);
  EXPECT_TRUE(r.passed) << r.failure;
  EXPECT_LE(r.energy_max, r.energy_start);  // it only falls: no gain at all
  c.scene.solver.tensile_k = 0.0f;
  const StabilityResult without = run_stability_case(c, 0);
  EXPECT_TRUE(without.passed) << without.failure;
}
