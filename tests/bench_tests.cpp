// `seiche bench`'s sweep (seiche/bench.hpp): one CSV row per setting plus the reference and its
// check; the error falls as substeps grow; the reference is converged well past what it judges;
// XPBD approaches the implicit-Euler reference; bad sweeps are refused before anything runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "seiche/bench.hpp"
#include "seiche/scene_loader.hpp"

using namespace seiche;

namespace {

// A chain of 12 particles hanging from a pin, swinging gently (a smooth, regular motion: a chain
// released horizontally whips chaotically, and no reference could judge it). Zero compliance.
std::string chain_scene() {
  std::string particles, constraints;
  for (int k = 0; k < 12; ++k) {
    particles += fmt::format("{}{{\"x\": [0, {}, 0], \"v\": [{}, 0, 0], \"mass\": {}}}", k ? ", " : "",
                             1.5 - 0.05 * k, 0.025 * k, k ? 0.01 : 0.0);
    if (k) constraints += fmt::format("{}{{\"i\": {}, \"j\": {}}}", k > 1 ? ", " : "", k - 1, k);
  }
  return fmt::format(R"({{ "name": "chain", "domain": {{ "min": [-1, 0, -1], "max": [1, 2, 1] }},
                           "particles": [{}], "distance_constraints": [{}] }})",
                     particles, constraints);
}

// A 12 x 12 sheet, 1 m, pinned at two corners, stiff edges, isometric bending.
std::string cloth_scene() {
  return R"({ "name": "small_cloth", "domain": { "min": [-1, -0.5, -1.5], "max": [2, 2.5, 1.5] },
              "cloths": [ { "sheet": { "origin": [0, 1.8, 0], "size": [1, 1], "resolution": [12, 12] },
                            "stretch_compliance": 1e-6, "bending": "isometric", "pins": [0, 11] } ] })";
}

SceneFactory factory(const std::string& json) {
  return [json](const std::vector<std::string>& overrides) { return load_scene_text(json, "bench test", overrides); };
}

std::vector<const BenchRun*> sweep_rows(const BenchResult& r) {
  std::vector<const BenchRun*> rows;
  for (const BenchRun& run : r.runs)
    if (run.role == BenchRun::Role::Sweep) rows.push_back(&run);
  return rows;
}

std::size_t count_lines(const std::string& text) { return std::size_t(std::count(text.begin(), text.end(), '\n')); }

}  // namespace

// The chain's reference is implicit Euler (auto: the scene has only particles and distance
// constraints), in double precision.
TEST(BenchSweep, ChainSweepHasOneRowPerSettingAndItsErrorFallsWithSubsteps) {
  BenchOptions o;
  o.sweep = {parse_sweep("substeps=1,2,4,8"), parse_sweep("iterations=2")};
  o.frames = 30;
  const BenchResult r = run_bench(factory(chain_scene()), o);

  const std::string csv = bench_csv(r);
  EXPECT_EQ(count_lines(csv), 1u + 4u + 2u);  // header, 4 settings, reference and its check
  EXPECT_EQ(csv.substr(0, csv.find(',', 5)), "role,solver.substeps");
  EXPECT_NE(csv.find("\nreference,"), std::string::npos);
  EXPECT_NE(csv.find("\nreference_check,"), std::string::npos);
  EXPECT_EQ(r.reference_run().substeps, 64);  // 4 x the largest swept, at least 64
  EXPECT_EQ(r.reference_run().iterations, 0);  // Newton to convergence
  EXPECT_EQ(r.reference_check().substeps, 128);
  EXPECT_NEAR(r.spacing, 0.05, 1e-6);

  const auto rows = sweep_rows(r);
  ASSERT_EQ(rows.size(), 4u);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    SCOPED_TRACE(fmt::format("{} substeps", rows[k]->substeps));
    EXPECT_EQ(rows[k]->substeps, 1 << k);
    EXPECT_EQ(rows[k]->iterations_run, 2.0);  // no fluid: no density tolerance, the fixed count
    EXPECT_FALSE(rows[k]->diverged);
    EXPECT_EQ(rows[k]->frames, 30);
    ASSERT_TRUE(find_error(rows[k]->constraint_errors, "distance_error") != nullptr);
    if (k > 0) {
      EXPECT_LT(rows[k]->error_rms, rows[k - 1]->error_rms);
    }
    // The reference judges only what it resolves: its own error is below every judged error.
    EXPECT_LT(r.reference_check().error_rms, rows[k]->error_rms);
    EXPECT_GE(rows[k]->error_max, rows[k]->error_rms);
  }

  // The Pareto front: none of its runs is beaten in both time and error by another run.
  int front = 0;
  for (const BenchRun* a : rows) {
    if (!a->pareto) continue;
    ++front;
    for (const BenchRun* b : rows)
      EXPECT_FALSE(b != a && b->ms_per_frame <= a->ms_per_frame && b->error_rms < a->error_rms);
  }
  EXPECT_GE(front, 1);

  std::ostringstream table;
  print_bench_table(table, r);
  EXPECT_NE(table.str().find("reference: implicit Euler, 64 steps per frame"), std::string::npos) << table.str();
  EXPECT_EQ(table.str().find("warning"), std::string::npos) << table.str();
}

// The XPBD reference (what fluid scenes get): XPBD far past the swept settings, in float32 like
// them. (Past about 64 substeps per 1/60 s frame, float32 rounding of positions near 1 m makes
// XPBD itself noisy; the reference check shows it, and the bench warns.)
TEST(BenchSweep, XpbdReferenceIsConvergedPastWhatItJudges) {
  BenchOptions o;
  o.sweep = {parse_sweep("substeps=1,2,4"), parse_sweep("iterations=2")};
  o.frames = 30;
  o.reference = ReferenceKind::Xpbd;
  o.reference_substeps = 16;
  const BenchResult r = run_bench(factory(chain_scene()), o);
  EXPECT_EQ(r.reference_run().substeps, 16);
  EXPECT_EQ(r.reference_run().iterations, 16);  // 2 x the largest swept, at least 16
  EXPECT_EQ(r.reference_check().substeps, 32);
  ASSERT_TRUE(find_error(r.reference_run().constraint_errors, "distance_error") != nullptr);
  const auto rows = sweep_rows(r);
  ASSERT_EQ(rows.size(), 3u);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    if (k > 0) {
      EXPECT_LT(rows[k]->error_rms, rows[k - 1]->error_rms);
    }
    EXPECT_LT(r.reference_check().error_rms, rows[k]->error_rms);
  }
  std::ostringstream table;
  print_bench_table(table, r);
  EXPECT_NE(table.str().find("reference: XPBD, 16 substeps x 16 iterations"), std::string::npos) << table.str();
}

TEST(BenchSweep, XpbdApproachesTheImplicitEulerReferenceAsSubstepsGrow) {
  BenchOptions o;
  o.sweep = {parse_sweep("substeps=4,16"), parse_sweep("iterations=1")};
  o.frames = 20;
  const BenchResult r = run_bench(factory(cloth_scene()), o);  // auto: implicit Euler
  EXPECT_EQ(r.reference_run().iterations, 0);
  EXPECT_NE(r.reference.find("implicit Euler"), std::string::npos);
  EXPECT_EQ(r.reference.find("stopped short"), std::string::npos) << r.reference;  // every Newton solve converged
  const auto rows = sweep_rows(r);
  ASSERT_EQ(rows.size(), 2u);
  ASSERT_TRUE(find_error(rows[0]->constraint_errors, "cloth_strain") != nullptr);
  // The error at least halves from 4 to 16 substeps.
  EXPECT_LE(rows[1]->error_rms, 0.5 * rows[0]->error_rms)
      << "4 substeps: " << rows[0]->error_rms << ", 16: " << rows[1]->error_rms;
  EXPECT_LT(r.reference_check().error_rms, rows[1]->error_rms);
}

TEST(BenchSweep, SweepKeysAndValuesAreParsedAndCheckedBeforeAnythingRuns) {
  const SweepAxis a = parse_sweep("substeps = 1, 2 ,4");
  EXPECT_EQ(a.key, "solver.substeps");
  EXPECT_EQ(a.values, (std::vector<std::string>{"1", "2", "4"}));
  EXPECT_EQ(parse_sweep("fluids.0.viscosity=0,0.01").key, "fluids.0.viscosity");
  EXPECT_THROW(parse_sweep("substeps"), BenchError);
  EXPECT_THROW(parse_sweep("=1,2"), BenchError);
  EXPECT_THROW(parse_sweep("substeps=1,,2"), BenchError);
  EXPECT_EQ(parse_reference_kind("auto"), ReferenceKind::Auto);
  EXPECT_EQ(parse_reference_kind("xpbd"), ReferenceKind::Xpbd);
  EXPECT_EQ(parse_reference_kind("implicit"), ReferenceKind::ImplicitEuler);
  EXPECT_THROW(parse_reference_kind("Implicit"), BenchError);

  BenchOptions o;
  o.frames = 1;
  o.sweep = {parse_sweep("substeps=1,2"), parse_sweep("solver.substeps=4")};
  EXPECT_THROW(run_bench(factory(chain_scene()), o), BenchError);  // swept twice
  o.sweep = {parse_sweep("substeps=1,-3")};
  try {
    run_bench(factory(chain_scene()), o);
    ADD_FAILURE() << "a negative substep count was accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.json_path(), "solver.substeps");
  }
}

TEST(BenchSweep, ImplicitReferenceOfAFluidSceneIsRefusedWithTheReason) {
  BenchOptions o;
  o.frames = 1;
  o.sweep = {parse_sweep("substeps=1")};
  o.reference = ReferenceKind::ImplicitEuler;
  try {
    run_bench([](const std::vector<std::string>& ov) {
      return load_scene_text(default_scene_json(), "<default scene>", ov);
    }, o);
    ADD_FAILURE() << "no error";
  } catch (const BenchError& e) {
    EXPECT_NE(std::string(e.what()).find("fluid"), std::string::npos) << e.what();
  }
}

// A setting's time is the median of several runs after a warm-up: the order of the sweep does
// not move the Pareto front. On the small cloth, 1, 4 and 16 substeps are 4x apart in time and
// their errors fall with the substeps, so all three are on the front whichever runs first.
TEST(BenchSweep, TheOrderOfTheSweepDoesNotChangeTheFront) {
  auto front = [](const char* substeps) {
    BenchOptions o;
    o.sweep = {parse_sweep(substeps), parse_sweep("iterations=2")};
    o.frames = 10;
    o.reference = ReferenceKind::Xpbd;
    o.reference_substeps = 64;
    const BenchResult r = run_bench(factory(cloth_scene()), o);
    std::vector<int> on_front;
    for (const BenchRun* run : sweep_rows(r)) {
      EXPECT_GE(run->timed_runs, 3);
      EXPECT_LE(run->ms_per_frame_min, run->ms_per_frame_q1);
      EXPECT_LE(run->ms_per_frame_q1, run->ms_per_frame);
      EXPECT_LE(run->ms_per_frame, run->ms_per_frame_q3);
      EXPECT_LE(run->ms_per_frame_q3, run->ms_per_frame_max);
      if (run->pareto) on_front.push_back(run->substeps);
    }
    std::sort(on_front.begin(), on_front.end());
    return on_front;
  };
  const std::vector<int> ascending = front("substeps=1,4,16");
  EXPECT_EQ(ascending, (std::vector<int>{1, 4, 16}));
  EXPECT_EQ(front("substeps=16,4,1"), ascending);
}
