// pba-solve as users and the server call it: every example solves, bad input
// exits 2 naming the field, and an interrupted solve leaves nothing behind.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "integration/subprocess.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;

std::vector<fs::path> Examples() {
  std::vector<fs::path> out;
  for (const auto& entry : fs::directory_iterator(PBA_EXAMPLES_DIR)) {
    if (entry.path().extension() == ".yaml") out.push_back(entry.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

class ExampleTest : public ::testing::TestWithParam<fs::path> {};

TEST_P(ExampleTest, Solves) {
  TempDir dir;
  const fs::path out = dir.path() / "result";
  const RunResult run =
      RunProcess({PBA_SOLVE_BIN, GetParam().string(), "--out", out.string(), "--progress", "json"},
                 std::chrono::seconds(800));  // the atlas scenes take minutes on two cores
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  for (const char* name : {"result.h5", "result.xdmf", "summary.json"}) {
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  // Machine-readable progress: one JSON object per line, ending with DONE.
  std::istringstream lines(run.out);
  std::string line, last;
  int count = 0;
  while (std::getline(lines, line)) {
    EXPECT_EQ(line.front(), '{') << line;
    EXPECT_EQ(line.back(), '}') << line;
    last = line;
    ++count;
  }
  EXPECT_GT(count, 3);
  EXPECT_NE(last.find("\"DONE\""), std::string::npos) << last;
}

INSTANTIATE_TEST_SUITE_P(Examples, ExampleTest, ::testing::ValuesIn(Examples()),
                         [](const ::testing::TestParamInfo<fs::path>& info) {
                           std::string name = info.param.stem().string();
                           for (char& c : name) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return name;
                         });

TEST(PbaSolveTest, InvalidSceneExitsTwoAndWritesNothing) {
  TempDir dir;
  const fs::path scene = dir.path() / "bad.yaml";
  std::ofstream(scene)
      << "geometry: {box: {size_mm: [10, 10, 10]}}\n"
         "material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.7}}\n"
         "boundary_conditions: [{set: bottom, fixed: {}}]\n";
  const fs::path out = dir.path() / "result";
  const RunResult run =
      RunProcess({PBA_SOLVE_BIN, scene.string(), "--out", out.string(), "--progress", "json"});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("material.linear_elastic.poissons_ratio"), std::string::npos) << run.err;
  EXPECT_NE(run.out.find("\"ERROR\""), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("INVALID_ARGUMENT"), std::string::npos) << run.out;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

TEST(PbaSolveTest, UnknownFieldNamesPathAndLine) {
  TempDir dir;
  const fs::path scene = dir.path() / "typo.yaml";
  std::ofstream(scene) << "name: x\nmaterial:\n  linear_elastic:\n    young: 3000\n";
  const RunResult run =
      RunProcess({PBA_SOLVE_BIN, scene.string(), "--out", (dir.path() / "r").string()});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("typo.yaml:4"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("material.linear_elastic.young"), std::string::npos) << run.err;
}

TEST(PbaSolveTest, SigtermStopsCleanlyAndWritesNothing) {
  TempDir dir;
  const fs::path scene = dir.path() / "long.yaml";
  std::ofstream(scene)
      << "geometry: {box: {size_mm: [50, 50, 50]}}\nmesh: {element_size_mm: 1}\n"
         "material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}\n"
         "boundary_conditions: [{set: bottom, fixed: {}}, {set: top, displacement: {z_mm: -1}}]\n";
  const fs::path out = dir.path() / "result";
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::freopen("/dev/null", "w", stdout);
    ::execl(PBA_SOLVE_BIN, PBA_SOLVE_BIN, scene.c_str(), "--out", out.c_str(), "--progress", "json",
            static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ::kill(pid, SIGTERM);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 5);  // cancelled
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1)
      << "a partial result was left behind";
}

TEST(PbaSolveTest, ExportOnlyWritesAnAbaqusDeck) {
  TempDir dir;
  const fs::path inp = dir.path() / "model.inp";
  const RunResult run =
      RunProcess({PBA_SOLVE_BIN, std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml", "--export-inp",
                  inp.string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::ifstream in(inp);
  std::stringstream text;
  text << in.rdbuf();
  for (const char* keyword : {"*NODE, NSET=NALL", "*ELEMENT, TYPE=C3D4", "*NSET, NSET=TOP",
                              "*ELASTIC", "*BOUNDARY", "*END STEP"}) {
    EXPECT_NE(text.str().find(keyword), std::string::npos) << keyword;
  }
  // Nothing but the deck was written.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

TEST(PbaSolveTest, NeitherOutNorExportIsAUsageError) {
  const RunResult run =
      RunProcess({PBA_SOLVE_BIN, std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml"});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--out"), std::string::npos) << run.err;
}

// A small QUASI_STATIC hold of a viscoelastic cube, held until `end_s`,
// meshed at `size_mm`.
std::string HoldScene(double end_s, double size_mm = 5) {
  std::ostringstream s;
  s << "name: hold\n"
       "geometry: {box: {size_mm: [10, 10, 10]}}\n"
       "mesh: {element: TET4_ANP, element_size_mm: "
    << size_mm
    << "}\n"
       "material:\n"
       "  neo_hookean: {shear_modulus_pa: 2200, bulk_modulus_pa: 2.2e6}\n"
       "  viscoelastic: {prony: {g: [0.5], tau_s: [2]}}\n"
       "boundary_conditions:\n"
       "  - {set: bottom, symmetry: {}}\n"
       "  - {set: x_min, symmetry: {}}\n"
       "  - {set: y_min, symmetry: {}}\n"
       "  - {set: top, displacement: {z_mm: -1}}\n"
       "analysis:\n"
       "  type: QUASI_STATIC\n"
       "  time:\n"
       "    end_time_s: "
    << end_s
    << "\n"
       "    curve: [{time_s: 0, amplitude: 0}, {time_s: 1, amplitude: 1}, {time_s: "
    << end_s
    << ", amplitude: 1}]\n"
       "outputs: {reaction_sets: [top]}\n";
  return s.str();
}

TEST(PbaSolveTest, CheckpointThenRestartExtendsTheHold) {
  TempDir dir;
  const fs::path first = dir.path() / "first.yaml", longer = dir.path() / "longer.yaml",
                 finer = dir.path() / "finer.yaml";
  std::ofstream(first) << HoldScene(10);
  std::ofstream(longer) << HoldScene(20);
  std::ofstream(finer) << HoldScene(20, 2.5);
  const fs::path checkpoints = dir.path() / "checkpoints";
  RunResult run = RunProcess({PBA_SOLVE_BIN, first.string(), "--out", (dir.path() / "r1").string(),
                              "--progress", "none", "--checkpoint", checkpoints.string(),
                              "--checkpoint-every", "0"});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  const fs::path checkpoint = checkpoints / "checkpoint.h5";
  ASSERT_TRUE(fs::exists(checkpoint));

  // The same hold, twice as long, from the checkpoint at 10 s.
  const fs::path r2 = dir.path() / "r2";
  run = RunProcess({PBA_SOLVE_BIN, longer.string(), "--out", r2.string(), "--progress", "none",
                    "--restart", checkpoint.string()});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  std::ifstream summary(r2 / "summary.json");
  const std::string text((std::istreambuf_iterator<char>(summary)),
                         std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("restarted from a checkpoint at t = 10 s"), std::string::npos) << text;
  std::ifstream history(r2 / "history.csv");
  std::string line, last;
  while (std::getline(history, line)) {
    if (!line.empty()) last = line;
  }
  EXPECT_EQ(last.rfind("20,", 0), 0u) << last;

  // Another mesh: refused, naming it, and no result written.
  const fs::path r3 = dir.path() / "r3";
  run = RunProcess({PBA_SOLVE_BIN, finer.string(), "--out", r3.string(), "--progress", "none",
                    "--restart", checkpoint.string()});
  EXPECT_EQ(run.exit_code, 3) << run.out << run.err;
  EXPECT_NE(run.err.find("its mesh has"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(r3));
}

}  // namespace
}  // namespace pba::testing
