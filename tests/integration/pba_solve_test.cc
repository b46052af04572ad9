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
      RunProcess({PBA_SOLVE_BIN, GetParam().string(), "--out", out.string(), "--progress", "json"});
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

}  // namespace
}  // namespace pba::testing
