// The command line as a user meets it: exit codes, error messages that name the file and the
// field, and no output written when the input is bad.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

struct Result {
  int code = -1;
  std::string out, err;
};

fs::path work_dir() {
  static const fs::path d = [] {
    fs::path p = fs::temp_directory_path() / "seiche_app_tests";
    fs::remove_all(p);
    fs::create_directories(p);
    return p;
  }();
  return d;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

Result seiche(const std::string& args) {
  const fs::path out = work_dir() / "stdout.txt", err = work_dir() / "stderr.txt";
  const std::string cmd = std::string("'") + SEICHE_EXE + "' " + args + " >'" + out.string() +
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
