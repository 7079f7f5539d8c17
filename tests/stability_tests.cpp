// The stability suite (seiche/stability.hpp) at its reduced size, as CI runs it, and its judge:
// a case that makes NaN, gains energy or leaves the domain must FAIL.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <string>

#include "seiche/scene_loader.hpp"
#include "seiche/simulation.hpp"
#include "seiche/stability.hpp"

using namespace seiche;

namespace {

// Cases that fail today, with the reason (see the issue note); each must keep failing the same
// way until it is fixed, when it leaves this list.
const std::set<std::string> kKnownFailures = {"columns_50ms", "time_step_10x"};

class StabilitySuite : public ::testing::TestWithParam<std::size_t> {};

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
  if (kKnownFailures.count(c.name)) {
    EXPECT_FALSE(r.passed) << "fixed: remove " << c.name << " from kKnownFailures";
    return;
  }
  EXPECT_TRUE(r.passed) << r.failure;
  EXPECT_EQ(r.non_finite, 0u);
  EXPECT_EQ(r.outside_domain, 0u);
  EXPECT_EQ(r.lost, 0u);
  EXPECT_LE(r.energy_max, r.energy_start + 0.01 * std::abs(r.energy_start));
  EXPECT_LT(r.final_error, r.error_bound);
}

INSTANTIATE_TEST_SUITE_P(Reduced, StabilitySuite, ::testing::Range<std::size_t>(0, 8),
                         [](const ::testing::TestParamInfo<std::size_t>& info) {
                           return stability_cases(SuiteSize::Reduced)[info.param].name;
                         });

TEST(StabilityJudge, TheSuiteHasTheEightCasesAtBothSizes) {
  const auto full = stability_cases(SuiteSize::Full), reduced = stability_cases(SuiteSize::Reduced);
  ASSERT_EQ(full.size(), 8u);
  ASSERT_EQ(reduced.size(), 8u);
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
