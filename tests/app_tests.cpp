// The command line as a user meets it: exit codes, error messages that name the file and the
// field, and no output written when the input is bad. `seiche bake`: interrupted (SIGINT) and
// killed (SIGKILL) bakes resume to the same bytes as an uninterrupted one; failed writes exit 3.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "target_simd.hpp"

namespace fs = std::filesystem;

namespace {

struct Result {
  int code = -1;
  std::string out, err;
};

// One folder per test process (ctest runs the tests of this binary as parallel processes),
// removed when the process ends.
struct WorkDir {
  fs::path path = fs::temp_directory_path() / "seiche_app_tests" / std::to_string(::getpid());
  WorkDir() {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~WorkDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

fs::path work_dir() {
  static const WorkDir d;
  return d.path;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs seiche with `args` (shell words), `env` ("NAME=VALUE ...") set for it.
Result seiche(const std::string& args, const std::string& env = "") {
  const fs::path out = work_dir() / "stdout.txt", err = work_dir() / "stderr.txt";
  const std::string cmd = env + (env.empty() ? "" : " ") + "'" + SEICHE_EXE + "' " + args + " >'" + out.string() +
                          "' 2>'" + err.string() + "' </dev/null";
  const int status = std::system(cmd.c_str());
  Result r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

fs::path write_scene(const std::string& name, const std::string& text) {
  const fs::path p = work_dir() / name;
  std::ofstream(p) << text;
  return p;
}

const char* kValid = R"({ "domain": { "min": [0,0,0], "max": [1,1,1] },
  "particles": [ { "x": [0.5,0.5,0.5], "mass": 1 }, { "x": [0.6,0.5,0.5], "mass": 1 } ],
  "distance_constraints": [ { "i": 0, "j": 1 } ],
  "fluids": [ { "box": { "min": [0,0,0], "max": [0.2,0.2,0.2] }, "spacing": 0.05 } ] })";

// Runs a bad scene and checks: exit code 2, the message names the file and the field, and the
// output folder was not even created.
void expect_rejected(const std::string& name, const std::string& text, const std::string& field) {
  const fs::path scene = write_scene(name + ".json", text);
  const fs::path out = work_dir() / ("out_" + name);
  const Result r = seiche("run '" + scene.string() + "' --frames 1 --out '" + out.string() + "'");
  EXPECT_EQ(r.code, 2) << name << ": " << r.err;
  EXPECT_NE(r.err.find(scene.string()), std::string::npos) << name << ": " << r.err;
  EXPECT_NE(r.err.find(field), std::string::npos) << name << ": expected '" << field << "' in: " << r.err;
  EXPECT_FALSE(fs::exists(out)) << name << ": wrote output for bad input";
}

std::string with(const std::string& from, const std::string& to) {
  std::string s = kValid;
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return s.replace(at, from.size(), to);
}

}  // namespace

TEST(Cli, ValidSceneRunsAndWritesFrames) {
  const fs::path scene = write_scene("valid.json", kValid);
  const fs::path out = work_dir() / "out_valid";
  const Result r = seiche("run '" + scene.string() + "' --frames 2 --threads 1 --out '" + out.string() +
                          "' --report '" + (out / "r.json").string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(out / "particles.0001.ply"));
  EXPECT_TRUE(fs::exists(out / "particles.0002.ply"));
  EXPECT_FALSE(fs::exists(out / "particles.0003.ply"));
  EXPECT_TRUE(fs::exists(out / "r.json"));
  EXPECT_NE(r.err.find("frame 2/2"), std::string::npos) << r.err;  // progress line
  for (const char* s : {"fluid density", "distance", "collisions", "1 threads", "2 frames"})
    EXPECT_NE(r.out.find(s), std::string::npos) << s << " missing from the summary:\n" << r.out;
}

TEST(Cli, SetOverridesAnyKey) {
  const fs::path scene = write_scene("set.json", kValid);
  const Result r = seiche("run '" + scene.string() + "' --frames 1 --out '" + (work_dir() / "out_set").string() +
                          "' --set solver.iterations=7 --set solver.substeps=3");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("3 substeps x 7 iterations"), std::string::npos) << r.out;
  const Result typo = seiche("run '" + scene.string() + "' --frames 1 --out '" +
                             (work_dir() / "out_typo").string() + "' --set solver.iteratons=7");
  EXPECT_EQ(typo.code, 2);
  EXPECT_NE(typo.err.find("solver.iteratons"), std::string::npos) << typo.err;
  EXPECT_FALSE(fs::exists(work_dir() / "out_typo"));
}

TEST(Cli, MissingFile) {
  const Result r = seiche("run '" + (work_dir() / "no_such.json").string() + "' --out '" +
                          (work_dir() / "out_missing").string() + "'");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("no_such.json"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(work_dir() / "out_missing"));
}

// A scene path that is not a regular file is refused before it is read (/dev/zero would be read
// until memory runs out), by run and by bake, naming the file; nothing is written.
TEST(Cli, DeviceOrDirectoryIsNotAScene) {
  for (const auto& [path, kind] : {std::pair{fs::path("/dev/zero"), "character device"},
                                   std::pair{work_dir(), "directory"}}) {
    for (const char* command : {"run", "bake"}) {
      const fs::path out = work_dir() / "out_not_a_file";
      const Result r = seiche(std::string(command) + " '" + path.string() + "' --out '" + out.string() + "'");
      EXPECT_EQ(r.code, 2) << command << " " << path << ": " << r.err;
      EXPECT_NE(r.err.find(path.string() + ": (file): cannot open"), std::string::npos) << r.err;
      EXPECT_NE(r.err.find(kind), std::string::npos) << r.err;
      EXPECT_FALSE(fs::exists(out)) << command << " " << path;
    }
  }
}

TEST(Cli, MalformedJson) { expect_rejected("malformed", "{ \"solver\": { \"substeps\": 4, }", "line"); }
TEST(Cli, UnknownKey) { expect_rejected("unknown", with("\"spacing\"", "\"spacng\""), "fluids[0].spacng"); }
TEST(Cli, WrongType) { expect_rejected("type", with("\"mass\": 1 }, {", "\"mass\": \"heavy\" }, {"), "particles[0].mass"); }
TEST(Cli, Infinity) { expect_rejected("inf", with("[0.5,0.5,0.5]", "[1e39,0.5,0.5]"), "particles[0].x"); }
TEST(Cli, NegativeMass) { expect_rejected("negmass", with("\"mass\": 1 }, {", "\"mass\": -1 }, {"), "particles[0].mass"); }
TEST(Cli, SpacingNotPositive) { expect_rejected("spacing", with("\"spacing\": 0.05", "\"spacing\": 0"), "fluids[0].spacing"); }
TEST(Cli, BoxMinAboveMax) {
  expect_rejected("box", with("\"max\": [0.2,0.2,0.2]", "\"max\": [0.2,-0.2,0.2]"), "fluids[0].box");
}
TEST(Cli, IndexOutOfRange) { expect_rejected("index", with("\"j\": 1", "\"j\": 5"), "distance_constraints[0].j"); }

TEST(Cli, BadCommandLineIsBadInput) {
  EXPECT_EQ(seiche("run --frames 0").code, 2);
  EXPECT_EQ(seiche("run --threads -1").code, 2);
  EXPECT_EQ(seiche("fly").code, 2);
}

TEST(Cli, RangeErrorsAreShortAndAnUnknownSubcommandIsNamed) {
  // CLI11's own validator printed the largest double in full ("not in range 0.000000 to
  // 179769313486...", 309 digits).
  Result r = seiche("run --frames -5");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--frames: must be a number > 0, got -5"), std::string::npos) << r.err;
  r = seiche("bench --threads -1e300");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--threads: must be a number > 0, got -1e300"), std::string::npos) << r.err;
  EXPECT_LT(r.err.size(), 200u) << r.err;
  EXPECT_EQ(r.err.find("179769"), std::string::npos) << r.err;
  // "A subcommand is required" said nothing about the word that was not one.
  r = seiche("fly --frames 2");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("unknown subcommand 'fly'; the subcommands are run, bake, bench"), std::string::npos)
      << r.err;
  r = seiche("");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("A subcommand is required"), std::string::npos) << r.err;  // none given at all
}

TEST(Cli, UnwritableOutputIsExitCode3) {
  const fs::path scene = write_scene("io.json", kValid);
  const Result r = seiche("run '" + scene.string() + "' --frames 1 --out /dev/null/seiche");
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("/dev/null/seiche"), std::string::npos) << r.err;
}

TEST(Cli, DefaultSceneRunsWithoutAFile) {
  const fs::path out = work_dir() / "out_default";
  const Result r = seiche("run --frames 1 --set fluids.0.spacing=0.1 --out '" + out.string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("dam_break"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "particles.0001.ply"));
}

TEST(Cli, ReportDoesNotChangeTheParticleFiles) {
  // The determinism contract: writing a report changes nothing of the simulation. A dam break at
  // twice its spacing, long enough for the splash to mix the particles across grid cells.
  const std::string run = "run '" + std::string(SEICHE_SCENES_DIR) +
                          "/dam_break.json' --frames 30 --threads 2 --set fluids.0.spacing=0.054";
  const fs::path plain = work_dir() / "out_no_report", reported = work_dir() / "out_report";
  const Result a = seiche(run + " --out '" + plain.string() + "'");
  ASSERT_EQ(a.code, 0) << a.err;
  const Result b = seiche(run + " --out '" + reported.string() + "' --report '" +
                          (work_dir() / "report_of_run.json").string() + "'");
  ASSERT_EQ(b.code, 0) << b.err;
  ASSERT_TRUE(fs::exists(work_dir() / "report_of_run.json"));
  for (int f = 1; f <= 30; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "particles.%04d.ply", f);
    const std::string without = slurp(plain / name), with_report = slurp(reported / name);
    ASSERT_FALSE(without.empty()) << name;
    ASSERT_TRUE(without == with_report)
        << name << " differs between runs with and without --report";
  }
}

// ---- seiche bake ------------------------------------------------------------------------------

namespace {

// About 2400 fluid particles and a chain on distance constraints: every pass runs, a frame takes
// a few ms. Particles only (no .vdb), so the tests mean the same with and without OpenVDB; as PLY
// and as .vtp with their series particles.pvd, so the resume tests cover both.
const char* kBakeScene = R"({ "name": "small",
  "solver": { "substeps": 4, "iterations": 2 },
  "domain": { "min": [0,0,0], "max": [1,1,0.5] },
  "output": { "frames": 20, "checkpoint_every": 5, "vdb": [], "particle_formats": ["ply", "vtp"] },
  "particles": [ { "x": [0.8,0.9,0.25], "mass": 0 }, { "x": [0.85,0.9,0.25] }, { "x": [0.9,0.9,0.25] } ],
  "distance_constraints": [ { "i": 0, "j": 1 }, { "i": 1, "j": 2 } ],
  "fluids": [ { "box": { "min": [0,0,0], "max": [0.36,0.6,0.3] }, "spacing": 0.03 } ] })";

fs::path fresh_dir(const std::string& name) {
  const fs::path d = work_dir() / name;
  fs::remove_all(d);
  return d;
}

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

// Every file of a bake folder but report.json (it holds timings): name -> bytes.
std::map<std::string, std::string> bake_files(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename() != "report.json") files[e.path().filename().string()] = slurp(e.path());
  return files;
}

void expect_same_files(const fs::path& expected, const fs::path& actual) {
  const auto a = bake_files(expected), b = bake_files(actual);
  for (const auto& [name, bytes] : a) {
    ASSERT_TRUE(b.count(name)) << name << " missing from " << actual;
    EXPECT_TRUE(b.at(name) == bytes) << name << " differs between " << expected << " and " << actual;
  }
  EXPECT_EQ(a.size(), b.size());
}

void expect_no_temporary_files(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_NE(e.path().extension(), ".tmp") << "left a temporary file: " << e.path();
}

// The straight 20-frame bake the resume tests compare with (baked once).
const fs::path& straight_bake() {
  static const fs::path dir = [] {
    const fs::path d = fresh_dir("bake_straight");
    const Result r = seiche("bake " + q(write_scene("small.json", kBakeScene)) + " --out " + q(d));
    EXPECT_EQ(r.code, 0) << r.err;
    return d;
  }();
  return dir;
}

}  // namespace

TEST(CliBake, WritesEveryFrameACheckpointAndASummary) {
  const fs::path dir = straight_bake();
  for (int f = 1; f <= 20; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "particles.%04d.ply", f);
    EXPECT_TRUE(fs::exists(dir / name)) << name;
  }
  EXPECT_FALSE(fs::exists(dir / "particles.0021.ply"));
  for (const char* f : {"checkpoint.bin", "bake.json", "report.json"}) EXPECT_TRUE(fs::exists(dir / f)) << f;
  expect_no_temporary_files(dir);
  // The summary names the files and how much was written; progress goes to stderr.
  const fs::path again = fresh_dir("bake_summary");
  const Result r = seiche("bake " + q(write_scene("small.json", kBakeScene)) + " --frames 2 --threads 1 --out " + q(again));
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* s : {"particles.0001.ply .. particles.0002.ply", "checkpoint.bin (frame 2)", "written:",
                        "simulate", "export", "fluid density", "1 threads"})
    EXPECT_NE(r.out.find(s), std::string::npos) << s << " missing from the summary:\n" << r.out;
  for (const char* s : {"frame 2/2", "ms/frame", "ETA", "written"})
    EXPECT_NE(r.err.find(s), std::string::npos) << s << " missing from the progress:\n" << r.err;
}

TEST(CliBake, SigintStopsWithACheckpointAndResumesToTheSameBytes) {
  const fs::path dir = fresh_dir("bake_sigint");
  const fs::path scene = write_scene("small.json", kBakeScene);
  // SIGINT right after frame 7's files: between checkpoints (every 5).
  const Result r = seiche("bake " + q(scene) + " --out " + q(dir), "SEICHE_TEST_INTERRUPT_AFTER_FRAME=7");
  EXPECT_EQ(r.code, 130) << r.err;
  EXPECT_NE(r.err.find("interrupted after frame 7 of 20; resume with: seiche bake --resume " + dir.string()),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(fs::exists(dir / "checkpoint.bin"));
  EXPECT_TRUE(fs::exists(dir / "particles.0007.ply"));
  EXPECT_FALSE(fs::exists(dir / "particles.0008.ply"));
  expect_no_temporary_files(dir);

  fs::remove(scene);  // a resume needs nothing but the folder
  std::ofstream(dir / ".particles.0009.ply.tmp") << "torn";  // as a kill mid-write leaves
  const Result resumed = seiche("bake --resume " + q(dir) + " --threads 1");
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  expect_no_temporary_files(dir);
  EXPECT_NE(resumed.err.find("resuming small from the checkpoint of frame 7"), std::string::npos) << resumed.err;
  expect_same_files(straight_bake(), dir);

  const Result done = seiche("bake --resume " + q(dir));
  EXPECT_EQ(done.code, 0) << done.err;
  EXPECT_NE(done.out.find("already complete"), std::string::npos) << done.out;
}

TEST(CliBake, KilledBakeResumesFromItsLastCheckpointToTheSameBytes) {
  const fs::path dir = fresh_dir("bake_killed");
  const fs::path scene = write_scene("small.json", kBakeScene);
  const fs::path log = work_dir() / "killed.log";
  // Slow each frame down (100 ms) so that the kill lands mid-bake, whatever the machine.
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    ::setenv("SEICHE_TEST_FRAME_DELAY_MS", "100", 1);
    const std::string out = dir.string(), scene_file = scene.string();
    ::execl(SEICHE_EXE, SEICHE_EXE, "bake", scene_file.c_str(), "--out", out.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // Frame 11's file exists once the frame-10 checkpoint is complete (files, then checkpoint).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!fs::exists(dir / "particles.0011.ply") && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(fs::exists(dir / "particles.0011.ply")) << slurp(log);
  const bool killed_mid_bake = WIFSIGNALED(status);
  EXPECT_TRUE(killed_mid_bake) << "the bake ended before the kill: " << slurp(log);
  if (killed_mid_bake) EXPECT_FALSE(fs::exists(dir / "particles.0020.ply"));
  // The series names complete frames only, 1 to k; beside them at most frame k + 1, killed between
  // its .vtp and the series' rewrite.
  auto vtp = [](int frame) {
    char name[32];
    std::snprintf(name, sizeof name, "particles.%04d.vtp", frame);
    return std::string(name);
  };
  const std::string series = slurp(dir / "particles.pvd");
  int listed = 0;
  for (std::size_t at = series.find("file=\""); at != std::string::npos; at = series.find("file=\"", at + 1)) {
    const std::string file = series.substr(at + 6, series.find('"', at + 6) - at - 6);
    EXPECT_EQ(file, vtp(++listed));
    EXPECT_TRUE(fs::exists(dir / file)) << file << " is listed but not on disk";
  }
  EXPECT_GE(listed, 10) << series;
  for (int f = listed + 2; f <= 20; ++f) EXPECT_FALSE(fs::exists(dir / vtp(f))) << f;

  const Result resumed = seiche("bake --resume " + q(dir));
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  if (killed_mid_bake)
    EXPECT_NE(resumed.err.find("from the checkpoint of frame 10"), std::string::npos) << resumed.err;
  expect_no_temporary_files(dir);  // the resume removes what the kill left
  expect_same_files(straight_bake(), dir);
}

TEST(CliBake, FrameRangeWritesExactlyThoseFrames) {
  const fs::path dir = fresh_dir("bake_range");
  const Result r = seiche("bake " + q(write_scene("small.json", kBakeScene)) + " --frames 3-5 --out " + q(dir));
  ASSERT_EQ(r.code, 0) << r.err;
  std::vector<std::string> plys;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".ply") plys.push_back(e.path().filename().string());
  std::sort(plys.begin(), plys.end());
  EXPECT_EQ(plys, (std::vector<std::string>{"particles.0003.ply", "particles.0004.ply", "particles.0005.ply"}));
  // Simulated from the start: frame 4 is frame 4 of the full bake.
  EXPECT_TRUE(slurp(dir / "particles.0004.ply") == slurp(straight_bake() / "particles.0004.ply"));
}

TEST(CliBake, BadFrameRangesAreBadInput) {
  const fs::path scene = write_scene("small.json", kBakeScene);
  for (const char* range : {"5-3", "0-4", "0", "-3", "3-", "x", "2-x", "1-2-3", "99999999999"}) {
    const fs::path dir = fresh_dir("bake_badrange");
    const Result r = seiche("bake " + q(scene) + " --frames '" + range + "' --out " + q(dir));
    EXPECT_EQ(r.code, 2) << range << ": " << r.err;
    EXPECT_NE(r.err.find("--frames"), std::string::npos) << range << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir)) << range << ": wrote output for a bad range";
  }
  // --resume takes everything from the folder.
  EXPECT_EQ(seiche("bake --resume " + q(work_dir()) + " --frames 3").code, 2);
}

TEST(CliBake, UnwritableFolderIsExitCode3NamingTheFolder) {
  const Result r = seiche("bake " + q(write_scene("small.json", kBakeScene)) + " --out /dev/null/seiche");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("/dev/null/seiche"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("frame 1/"), std::string::npos) << "simulated before checking the folder: " << r.err;
}

TEST(CliBake, FailedFrameWriteIsExitCode3AndKeepsTheLastCompleteFrame) {
  const fs::path dir = fresh_dir("bake_failed_write");
  // A folder in the way of frame 8's file: its rename fails mid-bake, as on a full disk.
  fs::create_directories(dir / "particles.0008.ply" / "x");
  const Result r = seiche("bake " + q(write_scene("small.json", kBakeScene)) + " --out " + q(dir));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find((dir / "particles.0008.ply").string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("frames up to 7 are complete"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("checkpoint of frame 5 is kept"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(dir / "particles.0007.ply"));
  expect_no_temporary_files(dir);
  fs::remove_all(dir / "particles.0008.ply");
  const Result resumed = seiche("bake --resume " + q(dir));
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  expect_same_files(straight_bake(), dir);
}

TEST(Cli, FailedFrameWriteIsExitCode3AndKeepsTheFramesBefore) {
  // seiche run writes a frame's files (PLY, then each cloth's OBJ) in the background while it
  // simulates the next frame. A failed write must still stop the run with the file's name,
  // before anything of a later frame is recorded or written, and every frame before it must be
  // complete: the same bytes as an undisturbed run's.
  const fs::path flag = fs::path(SEICHE_SCENES_DIR) / "flag.json";
  const fs::path clean = fresh_dir("run_clean"), dir = fresh_dir("run_failed_write");
  ASSERT_EQ(seiche("run " + q(flag) + " --frames 2 --out " + q(clean)).code, 0);
  fs::create_directories(dir / "particles.0003.ply" / "x");  // its rename fails, as on a full disk
  const Result r = seiche("run " + q(flag) + " --frames 6 --out " + q(dir) + " --report " + q(dir / "report.json"));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find((dir / "particles.0003.ply").string()), std::string::npos) << r.err;
  for (const char* name : {"particles.0001.ply", "particles.0002.ply", "flag.0001.obj", "flag.0002.obj"}) {
    ASSERT_TRUE(fs::exists(dir / name)) << name;
    EXPECT_TRUE(slurp(dir / name) == slurp(clean / name)) << name << " differs from the undisturbed run's";
  }
  // Frame 3's OBJ was queued after its PLY and is dropped with it; nothing of frames 4-6 exists.
  for (const char* name : {"flag.0003.obj", "particles.0004.ply", "flag.0004.obj", "particles.0005.ply"})
    EXPECT_FALSE(fs::exists(dir / name)) << name;
  expect_no_temporary_files(dir);
  // The report says so, and lists the frames up to the failed one (as a synchronous write did).
  const std::string report = slurp(dir / "report.json");
  EXPECT_NE(report.find("\"status\": \"error\""), std::string::npos) << report.substr(0, 200);
  EXPECT_NE(report.find("particles.0003.ply"), std::string::npos);
  EXPECT_NE(report.find("\"frame\": 3,"), std::string::npos);
  EXPECT_EQ(report.find("\"frame\": 4,"), std::string::npos);
}

TEST(CliBake, FileSizeLimitActsLikeAFullDisk) {
  const fs::path dir = fresh_dir("bake_full_disk");
  // ulimit -f (512-byte blocks in /bin/sh): 92 KB holds a frame's PLY (68 KB) but not the
  // frame-5 checkpoint (115 KB), so the bake runs out of room mid-way, as on a full disk.
  const Result r = seiche("bake " + q(write_scene("small.json", kBakeScene)) + " --out " + q(dir),
                          "ulimit -f 180;");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find((dir / "checkpoint.bin").string() + ": cannot write: File too large"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("frames up to 5 are complete"), std::string::npos) << r.err;
  for (const char* f : {"particles.0005.ply", "bake.json"}) EXPECT_TRUE(fs::exists(dir / f)) << f;
  EXPECT_FALSE(fs::exists(dir / "particles.0006.ply"));
  EXPECT_FALSE(fs::exists(dir / "checkpoint.bin"));
  expect_no_temporary_files(dir);
  // With room again, a resume starts over and writes the same bytes as a straight bake.
  const Result resumed = seiche("bake --resume " + q(dir));
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  expect_same_files(straight_bake(), dir);
}

TEST(CliBake, ResumeOfAMissingFolderOrDamagedCheckpointIsBadInput) {
  const fs::path missing = work_dir() / "no_such_bake";
  const Result r = seiche("bake --resume " + q(missing));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(missing.string()), std::string::npos) << r.err;

  const fs::path not_a_bake = fresh_dir("bake_not_a_bake");
  fs::create_directories(not_a_bake);
  const Result r2 = seiche("bake --resume " + q(not_a_bake));
  EXPECT_EQ(r2.code, 2) << r2.err;
  EXPECT_NE(r2.err.find((not_a_bake / "bake.json").string()), std::string::npos) << r2.err;

  // A checkpoint cut short (as a crash of a non-atomic writer would leave it).
  const fs::path dir = fresh_dir("bake_corrupt");
  fs::copy(straight_bake(), dir);
  const std::string cp = slurp(dir / "checkpoint.bin");
  std::ofstream(dir / "checkpoint.bin", std::ios::binary | std::ios::trunc).write(cp.data(), std::streamsize(cp.size() / 2));
  const Result r3 = seiche("bake --resume " + q(dir));
  EXPECT_EQ(r3.code, 2) << r3.err;
  EXPECT_NE(r3.err.find((dir / "checkpoint.bin").string()), std::string::npos) << r3.err;
  EXPECT_NE(r3.err.find("corrupt"), std::string::npos) << r3.err;

  // The checkpoint of another scene (same particles, another solver setting).
  const fs::path other = fresh_dir("bake_other_scene");
  ASSERT_EQ(seiche("bake " + q(write_scene("small.json", kBakeScene)) + " --frames 2 --set solver.iterations=3 --out " +
                   q(other)).code, 0);
  fs::copy_file(other / "checkpoint.bin", dir / "checkpoint.bin", fs::copy_options::overwrite_existing);
  const Result r4 = seiche("bake --resume " + q(dir));
  EXPECT_EQ(r4.code, 2) << r4.err;
  EXPECT_NE(r4.err.find("another scene"), std::string::npos) << r4.err;
}

TEST(CliBake, VdbWithoutFluidWarnsAndWritesParticles) {
  const fs::path dir = fresh_dir("bake_no_fluid");
  const Result r = seiche("bake " + q(write_scene("nofluid.json", R"({ "particles": [ { "x": [0.5,0.5,0.5] } ],
                                                                      "output": { "vdb": ["surface"], "mesh": true } })")) +
                          " --frames 2 --out " + q(dir));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: the scene asks for output.vdb = [surface] and output.mesh = true but has no fluid"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(fs::exists(dir / "particles.0002.ply"));
}

TEST(CliBake, VoxelSizeErrorNamesTheSceneFile) {
  // The exporter's check once named the scene ("scene \"small\"") instead of its file.
  const std::string text = std::string(kBakeScene).replace(std::string(kBakeScene).find("\"vdb\": []"), 9,
                                                           "\"vdb\": [\"density\"], \"voxel_size\": 1");
  const fs::path scene = write_scene("coarse_voxels.json", text);
  const fs::path out = fresh_dir("bake_coarse_voxels");
  const Result r = seiche("bake " + q(scene) + " --frames 1 --out " + q(out));
  EXPECT_EQ(r.code, 2) << r.err;
  if (r.err.find("-DSEICHE_WITH_OPENVDB=ON") != std::string::npos) GTEST_SKIP() << "built without OpenVDB";
  EXPECT_NE(r.err.find(scene.string() + ": output.voxel_size: 1 m is coarser than the fluid spacing"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(out / "bake.json"));
}

TEST(CliBake, VdbOutputNeedsOpenVdbAndResumesToTheSameBytes) {
  // The scene's default output asks for surface and density grids.
  const std::string text = std::string(kBakeScene).replace(std::string(kBakeScene).find("\"vdb\": []"), 9,
                                                           "\"vdb\": [\"surface\", \"density\", \"points\"], \"mesh\": true");
  const fs::path scene = write_scene("small_vdb.json", text);
  const fs::path straight = fresh_dir("bake_vdb_straight"), stopped = fresh_dir("bake_vdb_stopped");
  const Result r = seiche("bake " + q(scene) + " --frames 6 --out " + q(straight));
  if (r.code == 2) {  // a build without OpenVDB says how to go on
    EXPECT_NE(r.err.find("-DSEICHE_WITH_OPENVDB=ON"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("--set output.vdb=[] --set output.mesh=false"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(straight));
    const Result particles_only =
        seiche("bake " + q(scene) + " --frames 1 --set output.vdb=[] --set output.mesh=false --out " + q(straight));
    EXPECT_EQ(particles_only.code, 0) << particles_only.err;
    GTEST_SKIP() << "built without OpenVDB";
  }
  ASSERT_EQ(r.code, 0) << r.err;
  const Result stop = seiche("bake " + q(scene) + " --frames 6 --out " + q(stopped), "SEICHE_TEST_INTERRUPT_AFTER_FRAME=3");
  ASSERT_EQ(stop.code, 130) << stop.err;
  ASSERT_EQ(seiche("bake --resume " + q(stopped)).code, 0);
  expect_same_files(straight, stopped);  // .vdb and .obj too, byte for byte
}

// ---- Cloth ------------------------------------------------------------------------------------

namespace {

// A cloth read from an OBJ next to the scene (a relative path) and a sheet that falls onto it.
const char* kClothScene = R"({ "name": "cloths",
  "solver": { "substeps": 4, "iterations": 2 },
  "domain": { "min": [-1,0,-1], "max": [1,1.5,1] },
  "output": { "frames": 8, "checkpoint_every": 3 },
  "cloths": [ { "name": "patch", "mesh": { "file": "quad.obj", "translate": [0, 0.6, 0] }, "pins": [0, 1] },
              { "name": "sheet", "sheet": { "origin": [-0.3,0.9,-0.3], "size": [0.6,0.6], "resolution": [12,12] },
                "self_collision": true, "thickness": 0.04 } ] })";

// A 2 x 2 quad of 9 vertices (4 quads as polygons, as an OBJ exporter writes them).
const char* kQuadObj = R"(v -0.5 0 -0.5
v 0.5 0 -0.5
v -0.5 0 0
v 0.5 0 0
v -0.5 0 0.5
v 0 0 0.5
v 0.5 0 0.5
v 0 0 -0.5
v 0 0 0
f 1 8 9 3
f 8 2 4 9
f 3 9 6 5
f 9 4 7 6
)";

}  // namespace

TEST(CliCloth, BakeWritesAnObjPerClothAndFrameAndResumesToTheSameBytes) {
  const fs::path scene_dir = work_dir() / "cloth_scene";
  fs::create_directories(scene_dir);
  std::ofstream(scene_dir / "quad.obj") << kQuadObj;
  std::ofstream(scene_dir / "cloths.json") << kClothScene;
  const fs::path straight = fresh_dir("cloth_straight"), resumed = fresh_dir("cloth_resumed");
  // Run from another working directory: the OBJ is found next to the scene.
  const Result r = seiche("bake " + q(scene_dir / "cloths.json") + " --out " + q(straight));
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* f : {"patch.0001.obj", "patch.0008.obj", "sheet.0008.obj", "particles.0008.ply"})
    EXPECT_TRUE(fs::exists(straight / f)) << f;
  // The OBJ keeps the input's faces: 4 quads.
  const std::string patch = slurp(straight / "patch.0008.obj");
  std::size_t quads = 0;
  for (std::size_t at = patch.find("\nf "); at != std::string::npos; at = patch.find("\nf ", at + 1)) {
    const std::string line = patch.substr(at + 1, patch.find('\n', at + 1) - at - 1);
    quads += std::count(line.begin(), line.end(), ' ') == 4 ? 1 : 0;
  }
  EXPECT_EQ(quads, 4u) << patch;

  const Result stopped = seiche("bake " + q(scene_dir / "cloths.json") + " --out " + q(resumed),
                                "SEICHE_TEST_INTERRUPT_AFTER_FRAME=4");
  EXPECT_EQ(stopped.code, 130) << stopped.err;
  const Result again = seiche("bake --resume " + q(resumed) + " --threads 1");
  ASSERT_EQ(again.code, 0) << again.err;
  expect_same_files(straight, resumed);
}

TEST(CliCloth, MissingObjIsBadInputNamingSceneFieldAndFile) {
  const fs::path scene = write_scene("missing_obj.json", R"({ "cloths": [ { "mesh": { "file": "nowhere.obj" } } ] })");
  const Result r = seiche("run " + q(scene) + " --frames 1 --out " + q(work_dir() / "out_missing_obj"));
  EXPECT_EQ(r.code, 2) << r.err;
  for (const std::string s : {scene.string(), std::string("cloths[0].mesh.file"), std::string("nowhere.obj")})
    EXPECT_NE(r.err.find(s), std::string::npos) << s << " missing from: " << r.err;
  EXPECT_FALSE(fs::exists(work_dir() / "out_missing_obj"));
}

// A rigid body's OBJ wound inward (negative volume) is bad input: exit 2 naming the OBJ and the
// field, and no output.
TEST(CliRigid, InwardMeshBodyIsBadInputNamingObjAndField) {
  const fs::path obj = work_dir() / "inward_body.obj";
  std::ofstream(obj) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n";
  const fs::path scene = write_scene("inward_body.json", R"({ "domain": { "min": [0,0,0], "max": [2,2,2] },
    "rigid_bodies": [ { "name": "t", "shape": "mesh", "mesh": { "file": "inward_body.obj" }, "position": [1, 1, 1] } ] })");
  const Result r = seiche("run " + q(scene) + " --frames 1 --out " + q(work_dir() / "out_inward_body"));
  EXPECT_EQ(r.code, 2) << r.err;
  for (const std::string s : {obj.string(), std::string("rigid_bodies[0].mesh.file"), std::string("wound inward")})
    EXPECT_NE(r.err.find(s), std::string::npos) << s << " missing from: " << r.err;
  EXPECT_FALSE(fs::exists(work_dir() / "out_inward_body"));
}

TEST(CliCloth, NonManifoldObjIsBadInput) {
  const fs::path dir = work_dir() / "nonmanifold";
  fs::create_directories(dir);
  // Three triangles on the edge 1-2.
  std::ofstream(dir / "fan.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n";
  std::ofstream(dir / "fan.json") << R"({ "domain": { "min": [-2,-2,-2], "max": [2,2,2] },
    "cloths": [ { "mesh": { "file": "fan.obj" } } ] })";
  const Result r = seiche("run " + q(dir / "fan.json") + " --frames 1");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("fan.obj"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("non-manifold"), std::string::npos) << r.err;
}

// ---- names and output locations ----------------------------------------------------------------

namespace {

// Two small sheets (names given by the test) and a block of fluid: 2 frames take milliseconds.
std::string named_scene(const std::string& first_cloth, const std::string& second_cloth) {
  return R"({ "name": "named", "domain": { "min": [-1,0,-1], "max": [1,1.5,1] },
  "output": { "frames": 2, "vdb": [] },
  "fluids": [ { "box": { "min": [-1,0,-1], "max": [-0.8,0.2,-0.8] }, "spacing": 0.05 } ],
  "cloths": [ { "name": ")" + first_cloth + R"(", "sheet": { "origin": [-0.3,0.9,-0.3], "size": [0.6,0.6], "resolution": [4,4] } },
              { "name": ")" + second_cloth + R"(", "sheet": { "origin": [-0.3,1.1,-0.3], "size": [0.6,0.6], "resolution": [4,4] } } ] })";
}

// Every file under `dir` (recursively), for "nothing was written" checks.
std::vector<std::string> files_under(const fs::path& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& e : fs::recursive_directory_iterator(dir, ec))
    if (!e.is_directory()) files.push_back(e.path().string());
  return files;
}

}  // namespace

TEST(CliNames, NamesThatWouldWriteOutsideTheFolderAreBadInputAndWriteNothing) {
  // Each case: the cloth names (or an override), and what the message must say. A scene is data
  // from others: none of these may write a file, inside the output folder or outside it.
  const fs::path land = fresh_dir("names_land");  // where the escaping names point
  fs::create_directories(land / "out");
  const std::string absolute = (land / "abs").string();
  const struct {
    std::string first, second, set, path, problem;
  } cases[] = {
      {absolute, "b", "", "cloths[0].name", "contains '/', a path separator, at character 1"},
      {"../escape", "b", "", "cloths[0].name", "contains '/'"},
      {"a/b", "b", "", "cloths[0].name", "contains '/', a path separator, at character 2"},
      {"c", "./c", "", "cloths[1].name", "contains '/'"},
      {"c", "C", "", "cloths[1].name", "\"C\" writes the same files as cloths[0].name (\"c\")"},
      {"a\\nb", "b", "", "cloths[0].name", "contains a newline at character 2"},
      {std::string(300, 'n'), "b", "", "cloths[0].name", "is 300 characters long, more than 64"},
      {"a", "b", "name=../esc", "name", "contains '/', a path separator, at character 3"},
      {"a", "b", "name=a/b", "name", "contains '/'"},
      {"a", "b", "cloths.1.name=" + absolute, "cloths[1].name", "contains '/'"},
  };
  int k = 0;
  for (const auto& c : cases) {
    const fs::path scene = write_scene("named_" + std::to_string(k++) + ".json", named_scene(c.first, c.second));
    const fs::path out = land / "out" / "frames";
    const std::string set = c.set.empty() ? "" : " --set " + q(c.set);
    for (const std::string command : {"run", "bake"}) {
      const Result r = seiche(command + " " + q(scene) + " --out " + q(out) + set);
      EXPECT_EQ(r.code, 2) << command << " " << c.first << " " << c.second << c.set << ": " << r.err;
      for (const std::string& s : {scene.string(), c.path + ": ", c.problem})
        EXPECT_NE(r.err.find(s), std::string::npos) << command << ": '" << s << "' missing from: " << r.err;
      EXPECT_EQ(r.err.find("frame 1/"), std::string::npos) << "simulated a scene with a bad name: " << r.err;
      EXPECT_EQ(files_under(land), std::vector<std::string>{}) << command << " " << c.first << c.set;
    }
  }
  // The defaults out/<name> follow the name: `--set name=../esc` without --out writes nothing
  // either (run from inside `land`, whose parent would receive ../esc).
  const fs::path scene = write_scene("named_ok.json", named_scene("a", "b"));
  const Result r = seiche("run " + q(scene) + " --set name=../esc", "cd " + q(land / "out") + " &&");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(files_under(land), std::vector<std::string>{});
  EXPECT_FALSE(fs::exists(land / "esc"));
  // Within the rule, the names are the files.
  const fs::path good = fresh_dir("names_good");
  const Result ok = seiche("run " + q(scene) + " --out " + q(good) + " --set cloths.0.name=Sail-2.v1");
  ASSERT_EQ(ok.code, 0) << ok.err;
  for (const char* f : {"Sail-2.v1.0001.obj", "b.0002.obj", "particles.0002.ply"})
    EXPECT_TRUE(fs::exists(good / f)) << f;
}

TEST(CliNames, UnwritableReportFailsBeforeSimulatingAndWritesNoFrame) {
  const fs::path scene = write_scene("report_scene.json", named_scene("a", "b"));
  const fs::path taken = fresh_dir("report_is_a_folder");
  fs::create_directories(taken);
  for (const std::string report : {std::string("/proc/seiche_report.json"), std::string("."), taken.string(),
                                   taken.string() + "/"}) {
    const fs::path out = fresh_dir("report_out");
    const Result r = seiche("run " + q(scene) + " --frames 2 --out " + q(out) + " --report " + q(report));
    EXPECT_EQ(r.code, 3) << report << ": " << r.err;
    EXPECT_NE(r.err.find(report), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("frame 1/"), std::string::npos) << report << ": simulated before checking: " << r.err;
    EXPECT_EQ(files_under(out), std::vector<std::string>{}) << report;
    EXPECT_EQ(files_under(taken), std::vector<std::string>{}) << report;
  }
  EXPECT_FALSE(fs::exists("/proc/seiche_report.json"));
  // A bake's report and checkpoint: a folder in the way of either is found before frame 1.
  for (const char* in_the_way : {"report.json", "checkpoint.bin"}) {
    const fs::path dir = fresh_dir("bake_blocked");
    fs::create_directories(dir / in_the_way / "x");
    const Result r = seiche("bake " + q(scene) + " --out " + q(dir));
    EXPECT_EQ(r.code, 3) << in_the_way << ": " << r.err;
    EXPECT_NE(r.err.find((dir / in_the_way).string()), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("frame 1/"), std::string::npos) << in_the_way << ": simulated before checking: " << r.err;
    EXPECT_EQ(files_under(dir), std::vector<std::string>{}) << in_the_way;  // the folder x only
  }
}

TEST(CliBake, ShorterRebakeIntoAUsedFolderLeavesNoFrameOfTheEarlierBake) {
  const fs::path dir = fresh_dir("bake_rebake");
  const fs::path scene = write_scene("rebake.json", named_scene("sail", "flag"));
  ASSERT_EQ(seiche("bake " + q(scene) + " --frames 6 --out " + q(dir)).code, 0);
  // Frames 1 and 4-6 (a PLY and two OBJs each) lie outside the new range 2-3.
  std::ofstream(dir / "notes.0005.txt") << "not a frame of the bake";
  std::ofstream(dir / "other.0005.obj") << "not a file this bake writes";
  const Result r = seiche("bake " + q(scene) + " --frames 2-3 --out " + q(dir));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("removed 12 frame files of the earlier bake"), std::string::npos) << r.err;
  std::vector<std::string> frames;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".ply" || e.path().extension() == ".obj") frames.push_back(e.path().filename());
  std::sort(frames.begin(), frames.end());
  EXPECT_EQ(frames, (std::vector<std::string>{"flag.0002.obj", "flag.0003.obj", "other.0005.obj", "particles.0002.ply",
                                              "particles.0003.ply", "sail.0002.obj", "sail.0003.obj"}));
  EXPECT_TRUE(fs::exists(dir / "notes.0005.txt"));
  // What is left is the new bake, the same as a bake into an empty folder.
  const fs::path clean = fresh_dir("bake_rebake_clean");
  ASSERT_EQ(seiche("bake " + q(scene) + " --frames 2-3 --out " + q(clean)).code, 0);
  fs::remove(dir / "notes.0005.txt");
  fs::remove(dir / "other.0005.obj");
  expect_same_files(clean, dir);
}

// ---- bench ---------------------------------------------------------------------------------------

namespace {

// A two-particle pendulum: a bench of it takes a fraction of a second.
const char* kPendulum = R"({ "name": "pendulum", "domain": { "min": [-1,-1,-1], "max": [1,1,1] },
  "output": { "frames": 5 },
  "particles": [ { "x": [0,0.5,0], "mass": 0 }, { "x": [0.3,0.5,0], "mass": 1 } ],
  "distance_constraints": [ { "i": 0, "j": 1 } ] })";

std::size_t lines(const std::string& s) { return std::size_t(std::count(s.begin(), s.end(), '\n')); }

}  // namespace

TEST(CliBench, SweepWritesACsvRowPerRunAndThePlot) {
  const fs::path scene = write_scene("pendulum.json", kPendulum), out = work_dir() / "bench_ok";
  const Result r = seiche("bench '" + scene.string() + "' --sweep substeps=1,2,4 --sweep iterations=1,2 --out '" +
                          out.string() + "' --reference-substeps 16");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string csv = slurp(out / "bench.csv");
  EXPECT_EQ(lines(csv), 1u + 6u + 2u) << csv;  // header, 3 x 2 settings, reference and check
  EXPECT_EQ(csv.rfind("role,solver.substeps,solver.iterations,", 0), 0u) << csv;
  EXPECT_NE(r.out.find("reference: implicit Euler, 16 steps per frame"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("run 8/8"), std::string::npos) << r.err;  // progress, one line per run
  const std::string png = slurp(out / "bench.png");
  ASSERT_GT(png.size(), 8u) << r.err;
  EXPECT_EQ(png.substr(1, 3), "PNG");
  EXPECT_FALSE(fs::exists(out / "bench.png.tmp"));
}

TEST(CliBench, BadSweepIsBadInputAndWritesNothing) {
  const fs::path scene = write_scene("pendulum.json", kPendulum), out = work_dir() / "bench_bad";
  for (const std::string& args : {std::string("--sweep substeps"), std::string("--sweep substeps=1,0"),
                                  std::string("--sweep substeps=1 --sweep solver.substeps=2"),
                                  std::string("--reference exact")}) {
    const Result r = seiche("bench '" + scene.string() + "' " + args + " --out '" + out.string() + "'");
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    EXPECT_NE(r.err.find("error"), std::string::npos) << args;
    EXPECT_FALSE(fs::exists(out)) << args;
  }
  const Result fluid = seiche("bench --reference implicit --out '" + out.string() + "'");
  EXPECT_EQ(fluid.code, 2);
  EXPECT_NE(fluid.err.find("the scene has fluid"), std::string::npos) << fluid.err;
  const Result zero = seiche("bench '" + scene.string() + "' --sweep substeps=1,0 --out '" + out.string() + "'");
  EXPECT_NE(zero.err.find("solver.substeps"), std::string::npos) << zero.err;
  const Result size = seiche("bench --stability --size huge");
  EXPECT_EQ(size.code, 2) << size.err;
  EXPECT_NE(size.err.find("--size"), std::string::npos) << size.err;
}

TEST(CliBench, PlotThatCannotBeDrawnIsExitCode3AndKeepsTheCsv) {
  const fs::path scene = write_scene("pendulum.json", kPendulum), out = work_dir() / "bench_noplot";
  const Result r = seiche("bench '" + scene.string() + "' --sweep substeps=1 --sweep iterations=1 --out '" +
                              out.string() + "' --reference-substeps 4",
                          "SEICHE_PLOT_SCRIPT=/nonexistent/plot.py");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("/nonexistent/plot.py"), std::string::npos) << r.err;
  EXPECT_EQ(lines(slurp(out / "bench.csv")), 4u);
  EXPECT_FALSE(fs::exists(out / "bench.png"));
}

// ---- seiche --version -------------------------------------------------------------------------

// What this build's -march allows (this test compiles with the kernels' -march,
// SEICHE_ARCH_FLAGS): tests/target_simd.hpp.
using target_simd::kTargetFma;
using target_simd::kTargetLanes;
using target_simd::kTargetSimd;

// `seiche --version` says which SIMD the kernels were built for, and it is the widest the
// build's -march allows: an AVX-512 build whose kernels ran 8 lanes would fail here. It also says
// the compiler and the flags.
TEST(CliVersion, PrintsTheSimdWidthCompilerAndFlagsOfTheBuild) {
  const Result r = seiche("--version");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.rfind(std::string("seiche ") + SEICHE_VERSION + "\n", 0), 0u) << r.out;

  // "simd: avx512bw, 16 float lanes, fused multiply-add"
  const auto simd_at = r.out.find("\nsimd: ");
  ASSERT_NE(simd_at, std::string::npos) << r.out;
  const std::string simd = r.out.substr(simd_at + 7, r.out.find('\n', simd_at + 1) - simd_at - 7);
  const std::string expected_lanes = ", " + std::to_string(kTargetLanes) + " float lanes, ";
  const std::string expected_fma = kTargetFma ? "fused multiply-add" : "unfused multiply-add";
  const std::string arch = simd.substr(0, simd.find(','));  // xsimd's name: "fma3+avx2", "sse2"...
  EXPECT_NE(arch.find(kTargetSimd), std::string::npos)
      << "the build's " << SEICHE_ARCH_FLAGS << " allows " << kTargetSimd
      << "; seiche says: " << simd;
  EXPECT_NE(simd.find(expected_lanes), std::string::npos)
      << "expected \"" << expected_lanes << "\" in: " << simd;
  EXPECT_TRUE(simd.ends_with(", " + expected_fma)) << "expected " << expected_fma << ": " << simd;

#if defined(__GNUC__) && !defined(__clang__)
  const std::string compiler = "\ncompiler: GNU " + std::to_string(__GNUC__) + "." +
                               std::to_string(__GNUC_MINOR__) + "." +
                               std::to_string(__GNUC_PATCHLEVEL__) + "\n";
  EXPECT_NE(r.out.find(compiler), std::string::npos) << r.out;
#endif
  EXPECT_NE(r.out.find("\nbuild type: "), std::string::npos) << r.out;
  const auto flags = r.out.find("\nflags: ");
  ASSERT_NE(flags, std::string::npos) << r.out;
  EXPECT_NE(r.out.find(SEICHE_ARCH_FLAGS, flags), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find(" -W", flags), std::string::npos) << "warnings are not build flags:\n"
                                                         << r.out;
}

// ---- Input fingerprints, memory and work bounds -------------------------------------------------

namespace {

// Two particles dropping onto a mesh collider (a 0.4 m cube read from the OBJ next to the scene).
const char* kMeshColliderScene = R"({ "name": "onto_cube",
  "solver": { "substeps": 4, "iterations": 2 },
  "domain": { "min": [-1,0,-1], "max": [1,2,1] },
  "output": { "frames": 20, "checkpoint_every": 3 },
  "colliders": [ { "mesh": { "file": "cube.obj", "scale": 0.4, "translate": [0,0.2,0] } } ],
  "particles": [ { "x": [0,0.5,0] }, { "x": [0.1,0.5,0] } ] })";

}  // namespace

// A collider mesh moved mid-bake (its bytes changed) or deleted: the resume is refused (exit 2)
// naming the file and its field; with --accept-changed-inputs it continues with the new mesh.
TEST(CliBake, ResumeWithAChangedOrMissingMeshIsRefusedUnlessAccepted) {
  const fs::path scene_dir = work_dir() / "mesh_inputs";
  fs::create_directories(scene_dir);
  const fs::path obj = scene_dir / "cube.obj";
  const std::string cube = slurp(fs::path(SEICHE_SCENES_DIR) / "meshes" / "cube.obj");
  std::ofstream(obj, std::ios::binary) << cube;
  const fs::path scene = scene_dir / "onto_cube.json";
  std::ofstream(scene) << kMeshColliderScene;
  const fs::path straight = fresh_dir("mesh_straight"), dir = fresh_dir("mesh_resumed");
  ASSERT_EQ(seiche("bake " + q(scene) + " --out " + q(straight)).code, 0);
  const Result stopped = seiche("bake " + q(scene) + " --out " + q(dir), "SEICHE_TEST_INTERRUPT_AFTER_FRAME=4");
  ASSERT_EQ(stopped.code, 130) << stopped.err;
  EXPECT_NE(slurp(dir / "bake.json").find("colliders[0].mesh.file"), std::string::npos);
  const auto frames_before = bake_files(dir);

  // The cube's top moved up by 0.1 m in the file (0.04 m in the scene).
  std::string moved = cube;
  for (std::size_t at = moved.find(" 0.5 "); at != std::string::npos; at = moved.find(" 0.5 ", at + 1))
    moved.replace(at, 5, " 0.6 ");
  ASSERT_NE(moved, cube);
  std::ofstream(obj, std::ios::binary | std::ios::trunc) << moved;
  const Result changed = seiche("bake --resume " + q(dir));
  EXPECT_EQ(changed.code, 2) << changed.err;
  for (const std::string s : {obj.string(), std::string("colliders[0].mesh.file"), std::string("changed"),
                              std::string("--accept-changed-inputs")})
    EXPECT_NE(changed.err.find(s), std::string::npos) << s << " missing from: " << changed.err;
  EXPECT_TRUE(bake_files(dir) == frames_before) << "a refused resume wrote into the bake";

  fs::remove(obj);
  for (const char* flags : {"", " --accept-changed-inputs"}) {
    const Result missing = seiche("bake --resume " + q(dir) + flags);
    EXPECT_EQ(missing.code, 2) << missing.err;
    for (const std::string s : {obj.string(), std::string("colliders[0].mesh.file"), std::string("missing")})
      EXPECT_NE(missing.err.find(s), std::string::npos) << s << " missing from: " << missing.err;
  }
  EXPECT_TRUE(bake_files(dir) == frames_before) << "a refused resume wrote into the bake";

  // Accepted: the bake finishes with the moved cube, so the particles come to rest 0.04 m higher
  // than in the unbroken bake (the frames before the checkpoint are the unbroken bake's).
  std::ofstream(obj, std::ios::binary) << moved;
  const Result accepted = seiche("bake --resume " + q(dir) + " --accept-changed-inputs");
  ASSERT_EQ(accepted.code, 0) << accepted.err;
  EXPECT_NE(accepted.err.find("warning"), std::string::npos) << accepted.err;
  EXPECT_EQ(slurp(dir / "particles.0004.ply"), slurp(straight / "particles.0004.ply"));
  EXPECT_NE(slurp(dir / "particles.0020.ply"), slurp(straight / "particles.0020.ply"));
  // bake.json now records the moved cube: a further resume of the complete bake passes.
  EXPECT_EQ(seiche("bake --resume " + q(dir)).code, 0);
}

// --max-memory below the estimate: exit 2 before anything is written, naming the estimate and the
// limit; the 4096 x 4096 sheet (the largest resolution) is refused by its estimate, not by
// std::bad_alloc, even without a limit here: it needs more than 30 GiB.
TEST(Cli, SceneOverTheMemoryLimitIsRefusedWithItsEstimate) {
  const fs::path scene = fs::path(SEICHE_SCENES_DIR) / "cloth_drape.json";
  const fs::path out = fresh_dir("out_memory");
  const Result r = seiche("run " + q(scene) + " --frames 1 --max-memory 40M --out " + q(out));
  EXPECT_EQ(r.code, 2) << r.err;
  for (const char* s : {"cloth_drape.json", "needs about", "MiB", "--max-memory limit of 40 MiB", "cloths[0]"})
    EXPECT_NE(r.err.find(s), std::string::npos) << s << " missing from: " << r.err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(seiche("run " + q(scene) + " --frames 1 --max-memory 200M --out " + q(out)).code, 0);
  EXPECT_EQ(seiche("run " + q(scene) + " --frames 1 --max-memory lots --out " + q(out)).code, 2);

  const Result big = seiche("bake " + q(scene) + " --frames 1 --max-memory 8G --set 'cloths[0].sheet.resolution=[4096,4096]' --out " +
                            q(fresh_dir("out_big")));
  EXPECT_EQ(big.code, 2) << big.err;
  for (const char* s : {"cloths[0].sheet.resolution", "16777216 vertices", "GiB"})
    EXPECT_NE(big.err.find(s), std::string::npos) << s << " missing from: " << big.err;
  EXPECT_EQ(big.err.find("bad_alloc"), std::string::npos) << big.err;
}

// A body whose fluid boundary is over --max-memory (a 1.6 m box sampled at the fluid's 0.01 m:
// 300k sites, 22 MB with its grid) is refused before it is sampled: exit 2, naming the file and
// the box's size, nothing written.
TEST(Cli, BodyBoundaryOverTheMemoryLimitIsRefusedNamingTheBody) {
  const fs::path scene = write_scene("big_boundary.json", R"({"domain": {"min": [0, 0, 0], "max": [2, 2, 2]},
    "fluids": [{"box": {"min": [0, 0, 0], "max": [0.1, 0.1, 0.1]}, "spacing": 0.01}],
    "rigid_bodies": [{"name": "slab", "size": [1.6, 1.6, 1.6], "position": [1, 1, 1]}]})");
  const fs::path out = fresh_dir("out_big_boundary");
  const Result r = seiche("run " + q(scene) + " --frames 1 --max-memory 40M --out " + q(out));
  EXPECT_EQ(r.code, 2) << r.err;
  for (const char* s : {"big_boundary.json", "rigid_bodies[0].size", "fluid boundary", "--max-memory limit of 40 MiB"})
    EXPECT_NE(r.err.find(s), std::string::npos) << s << " missing from: " << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// substeps 10000 x iterations 10000 (1e8 solver iterations per frame, past the bound of 1e5) is
// refused naming solver.substeps; --allow-huge-work runs it (here 1000 x 101, a fraction of a
// second for two particles).
TEST(Cli, HugeWorkIsRefusedUnlessAllowed) {
  const fs::path scene = fs::path(SEICHE_SCENES_DIR) / "seed_example.json";
  const fs::path out = fresh_dir("out_huge");
  const Result r = seiche("run " + q(scene) + " --frames 1 --set solver.substeps=10000 --set solver.iterations=10000 --out " + q(out));
  EXPECT_EQ(r.code, 2) << r.err;
  for (const char* s : {"solver.substeps", "1e+08", "--allow-huge-work"})
    EXPECT_NE(r.err.find(s), std::string::npos) << s << " missing from: " << r.err;
  EXPECT_FALSE(fs::exists(out));
  const std::string over = " --frames 1 --set solver.substeps=1000 --set solver.iterations=101 --out " + q(out);
  EXPECT_EQ(seiche("run " + q(scene) + over).code, 2);
  const Result allowed = seiche("run " + q(scene) + over + " --allow-huge-work");
  EXPECT_EQ(allowed.code, 0) << allowed.err;
  EXPECT_TRUE(fs::exists(out / "particles.0001.ply"));
}

// An allocation that fails anyway (here under a 700 MB address-space limit that the machine's
// available memory does not show) exits 1 saying what was being done, for which scene and size.
TEST(Cli, OutOfMemoryNamesTheStageSceneAndSize) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer reserves more address space than the limit";
#else
  const fs::path scene = fs::path(SEICHE_SCENES_DIR) / "dam_break.json";
  const Result r = seiche("run " + q(scene) + " --frames 1 --threads 2 --set 'fluids[0].spacing=0.008' --out " +
                              q(fresh_dir("out_oom")),
                          "ulimit -v 700000;");
  EXPECT_EQ(r.code, 1) << r.err;
  for (const char* s : {"out of memory while building and simulating scene dam_break", "1953125 particles",
                        "estimated"})
    EXPECT_NE(r.err.find(s), std::string::npos) << s << " missing from: " << r.err;
#endif
}
