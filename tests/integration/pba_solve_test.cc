// pba-solve as users and the server call it: every example solves, bad input
// exits 5 naming the field and a bad command line 2 (core/exit_codes.h), an
// interrupted solve leaves nothing behind, and --out replaces only an
// earlier result, with --force.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/subprocess.h"
#include "common/yaml_bombs.h"
#include "integration/block_scene.h"

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

// mesh.adapt: the result files are the last cycle's mesh, and the summary
// holds every cycle, the first on the scene's own mesh.
TEST(PbaSolveTest, AnAdaptiveSceneWritesItsLastMeshAndEveryCycle) {
  TempDir dir;
  const fs::path out = dir.path() / "result";
  const RunResult run =
      RunProcess({PBA_SOLVE_BIN, (fs::path(PBA_EXAMPLES_DIR) / "adaptive_block.yaml").string(),
                  "--out", out.string(), "--progress", "json"},
                 std::chrono::seconds(300));
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("mesh.adapt cycle 2: "), std::string::npos) << run.out;
  // An export alone writes the first mesh, and says so.
  const RunResult exported =
      RunProcess({PBA_SOLVE_BIN, (fs::path(PBA_EXAMPLES_DIR) / "adaptive_block.yaml").string(),
                  "--export-inp", (dir.path() / "first.inp").string()});
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  EXPECT_NE(exported.err.find("the deck holds the scene's first mesh"), std::string::npos)
      << exported.err;
  const std::string summary = ReadFile(out / "summary.json");
  std::vector<std::string> elements;
  const std::regex pattern("\"elements\": \"([0-9]+)\"");
  for (auto it = std::sregex_iterator(summary.begin(), summary.end(), pattern);
       it != std::sregex_iterator(); ++it) {
    elements.push_back((*it)[1]);
  }
  // modelled.elements, then one per cycle: the scene's 8 x 8 x 4 grid of
  // 6 tetrahedra first, the last cycle's the result's.
  ASSERT_GE(elements.size(), 4u) << summary;
  EXPECT_EQ(elements[1], "1536");
  EXPECT_EQ(elements.back(), elements[0]);
  EXPECT_NE(summary.find("\"reached\": true"), std::string::npos) << summary;
  EXPECT_NE(summary.find("within the target of 20 %"), std::string::npos) << summary;
  const std::string xdmf = ReadFile(out / "result.xdmf");
  EXPECT_NE(xdmf.find("NumberOfElements=\"" + elements[0] + "\""), std::string::npos) << xdmf;
}

TEST(PbaSolveTest, InvalidSceneExitsFiveAndWritesNothing) {
  TempDir dir;
  const fs::path scene = dir.path() / "bad.yaml";
  std::ofstream(scene)
      << "geometry: {box: {size_mm: [10, 10, 10]}}\n"
         "material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.7}}\n"
         "boundary_conditions: [{set: bottom, fixed: {}}]\n";
  const fs::path out = dir.path() / "result";
  const RunResult run =
      RunProcess({PBA_SOLVE_BIN, scene.string(), "--out", out.string(), "--progress", "json"});
  EXPECT_EQ(run.exit_code, 5);  // invalid
  EXPECT_NE(run.err.find("material.linear_elastic.poissons_ratio"), std::string::npos) << run.err;
  EXPECT_NE(run.out.find("\"ERROR\""), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("INVALID_ARGUMENT"), std::string::npos) << run.out;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

// A scene on a real atlas, AAL with its table as Debian ships it, names
// AAL's structures: one it lacks is refused at once (before meshing),
// naming the nearest, and nothing is written.
TEST(PbaSolveTest, StructureNamesAreCheckedAgainstTheAtlasTable) {
  TempDir dir;
  const fs::path scene = dir.path() / "aal.yaml";
  std::ofstream(scene)
      << "geometry:\n  atlas:\n    source: /usr/share/mricron/templates/aal.nii.gz\n"
         "    colour_table: /usr/share/mricron/templates/aal.nii.txt\n"
         "mesh: {element_size_mm: 8}\n"
         "material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}\n"
         "region_materials:\n  - structures: [Precentral_L, Thalamus_X]\n"
         "    material: {neo_hookean: {shear_modulus_pa: 2000, bulk_modulus_pa: 2e6}}\n"
         "boundary_conditions: [{set: 'surface:Precentral_R', fixed: {}}]\n"
         "analysis: {type: NONLINEAR_STATIC}\n";
  const fs::path out = dir.path() / "result";
  const auto start = std::chrono::steady_clock::now();
  const RunResult run =
      RunProcess({PBA_SOLVE_BIN, scene.string(), "--out", out.string(), "--progress", "none"});
  EXPECT_EQ(run.exit_code, 5) << run.err;
  EXPECT_NE(run.err.find("region_materials[0].structures[1]"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("the atlas (116 structures) has no structure \"Thalamus_X\"; nearest "
                         "names: \"Thalamus_L\", \"Thalamus_R\""),
            std::string::npos)
      << run.err;
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20));
  EXPECT_FALSE(fs::exists(out));
}

TEST(PbaSolveTest, UnknownFieldNamesPathAndLine) {
  TempDir dir;
  const fs::path scene = dir.path() / "typo.yaml";
  std::ofstream(scene) << "name: x\nmaterial:\n  linear_elastic:\n    young: 3000\n";
  const RunResult run =
      RunProcess({PBA_SOLVE_BIN, scene.string(), "--out", (dir.path() / "r").string()});
  EXPECT_EQ(run.exit_code, 5);  // invalid
  EXPECT_NE(run.err.find("typo.yaml:4"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("material.linear_elastic.young"), std::string::npos) << run.err;
}

// Nine levels of ten aliases: a billion values from a kilobyte, refused
// before loading (exit 5 naming the alias and its line, at once).
TEST(PbaSolveTest, AliasBombSceneExitsFiveNamingTheAlias) {
  TempDir dir;
  const fs::path scene = dir.path() / "bomb.yaml";
  const std::string text = "name: bomb\n" + yaml_bombs::BillionLaughs();
  std::ofstream(scene) << text;
  const auto start = std::chrono::steady_clock::now();
  const RunResult run =
      RunProcess({PBA_SOLVE_BIN, scene.string(), "--out", (dir.path() / "r").string()},
                 std::chrono::seconds(30));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10);
  EXPECT_EQ(run.exit_code, 5) << run.err;  // invalid
  EXPECT_NE(run.err.find("bomb.yaml:3: YAML aliases (*l0) are not accepted"), std::string::npos)
      << run.err;
  EXPECT_FALSE(fs::exists(dir.path() / "r"));
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
  EXPECT_EQ(WEXITSTATUS(status), 7);  // cancelled
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1)
      << "a partial result was left behind";
}

// Issue 18: a cancel ends pba-solve within a second whatever it is doing.
// SIGTERM lands `delay` after the JSON progress first names `phase`;
// returns the seconds from the signal to the exit and the exit code
// (-1 if it did not exit normally) and stderr.
struct CancelRun {
  double seconds = -1;
  int exit_code = -1;
  std::string err;
};

CancelRun CancelDuring(const std::string& yaml, const std::string& phase,
                       std::chrono::milliseconds delay) {
  TempDir dir;
  const fs::path scene = dir.path() / "long.yaml";
  std::ofstream(scene) << yaml;
  const fs::path out = dir.path() / "result";
  const fs::path err = dir.path() / "stderr.txt";
  int pipe_fds[2];
  if (::pipe(pipe_fds) != 0) return {};
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(pipe_fds[1], STDOUT_FILENO);
    ::close(pipe_fds[0]);
    ::freopen(err.c_str(), "w", stderr);
    ::execl(PBA_SOLVE_BIN, PBA_SOLVE_BIN, scene.c_str(), "--out", out.c_str(), "--progress", "json",
            static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  ::close(pipe_fds[1]);
  FILE* progress = ::fdopen(pipe_fds[0], "r");
  char line[4096];
  const std::string wanted = "\"phase\":\"" + phase + "\"";
  while (std::fgets(line, sizeof line, progress) != nullptr) {
    if (std::string(line).find(wanted) != std::string::npos) break;
  }
  std::this_thread::sleep_for(delay);
  const auto signalled = std::chrono::steady_clock::now();
  ::kill(pid, SIGTERM);
  while (std::fgets(line, sizeof line, progress) != nullptr) {
  }
  std::fclose(progress);
  int status = 0;
  ::waitpid(pid, &status, 0);
  CancelRun run;
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err);
  std::stringstream text;
  text << in.rdbuf();
  run.err = text.str();
  return run;
}

const std::string kLongBlock = BlockSceneYaml("long-block", 50);

// A CHOLMOD factorisation (a minute here) cannot look at the flag: the
// watchdog ends the process.
TEST(PbaSolveTest, SigtermDuringAFactorisationExitsWithinASecond) {
  const CancelRun run = CancelDuring(kLongBlock, "factorize", std::chrono::milliseconds(500));
  EXPECT_EQ(run.exit_code, 7) << run.err;  // cancelled
  EXPECT_LT(run.seconds, 1.0) << run.err;
}

// Conjugate gradients look at it every iteration: the solve's own error.
TEST(PbaSolveTest, SigtermDuringConjugateGradientsExitsWithinASecond) {
  const CancelRun run = CancelDuring(std::string(kLongBlock) + "analysis: {linear_solver: PCG}\n",
                                     "solve", std::chrono::milliseconds(500));
  EXPECT_EQ(run.exit_code, 7) << run.err;  // cancelled
  EXPECT_LT(run.seconds, 1.0) << run.err;
  EXPECT_NE(run.err.find("conjugate gradients"), std::string::npos) << run.err;
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
  EXPECT_EQ(run.exit_code, 2);  // usage
  EXPECT_NE(run.err.find("--out"), std::string::npos) << run.err;
}

// CLI11's refusals are usage errors too, as in pba and pba-atlas: exit 2,
// not the 5 of a bad scene.
TEST(PbaSolveTest, UnknownOptionOrBadValueIsAUsageError) {
  const std::string scene = std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml";
  RunResult run = RunProcess({PBA_SOLVE_BIN, scene, "--export-inp", "x.inp", "--no-such-flag"});
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find("--no-such-flag"), std::string::npos) << run.err;
  run = RunProcess({PBA_SOLVE_BIN, scene, "--export-inp", "x.inp", "--progress", "loud"});
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_NE(run.err.find("loud"), std::string::npos) << run.err;
}

TEST(PbaSolveTest, CheckpointThenRestartExtendsTheHold) {
  TempDir dir;
  const fs::path first = dir.path() / "first.yaml", longer = dir.path() / "longer.yaml",
                 finer = dir.path() / "finer.yaml";
  std::ofstream(first) << HoldSceneYaml(10);
  std::ofstream(longer) << HoldSceneYaml(20);
  std::ofstream(finer) << HoldSceneYaml(20, 2.5);
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
  EXPECT_EQ(run.exit_code, 11) << run.out << run.err;  // numerical: cannot be solved as posed
  EXPECT_NE(run.err.find("its mesh has"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(r3));
}

// --out DIR: what is there is replaced only when pba-solve wrote it and
// --force says so; a file, a link, or a directory holding anything else is
// refused (exit 5) before anything is solved, and left as it was.
constexpr char kSmallBlock[] =
    "geometry: {box: {size_mm: [10, 10, 10]}}\nmesh: {element_size_mm: 5}\n"
    "material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}\n"
    "boundary_conditions: [{set: bottom, fixed: {}}, {set: top, displacement: {z_mm: -1}}]\n";

std::string ReadAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

RunResult SolveInto(const fs::path& scene, const fs::path& out, bool force = false) {
  std::vector<std::string> args = {PBA_SOLVE_BIN, scene.string(), "--out", out.string()};
  args.insert(args.end(), {"--progress", "json"});
  if (force) args.push_back("--force");
  return RunProcess(args);
}

// A refusal names --out and comes before the solve: no progress at all.
void ExpectRefused(const RunResult& run, const std::string& why) {
  EXPECT_EQ(run.exit_code, 5) << run.out << run.err;  // invalid
  EXPECT_NE(run.err.find("--out"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find(why), std::string::npos) << run.err;
  EXPECT_EQ(run.out.find("PROGRESS"), std::string::npos) << run.out;
}

TEST(PbaSolveOutputTest, AnEarlierResultIsReplacedOnlyWithForce) {
  TempDir dir;
  const fs::path scene = dir.path() / "block.yaml";
  std::ofstream(scene) << kSmallBlock;
  const fs::path out = dir.path() / "result";
  const RunResult first = SolveInto(scene, out);
  ASSERT_EQ(first.exit_code, 0) << first.out << first.err;
  const std::string summary = ReadAll(out / "summary.json");

  ExpectRefused(SolveInto(scene, out), "--force");
  EXPECT_EQ(ReadAll(out / "summary.json"), summary);
  const RunResult forced = SolveInto(scene, out, true);
  EXPECT_EQ(forced.exit_code, 0) << forced.out << forced.err;
  EXPECT_TRUE(fs::exists(out / "result.h5"));

  // An empty directory is taken without --force.
  const fs::path empty = dir.path() / "empty";
  fs::create_directories(empty);
  const RunResult into_empty = SolveInto(scene, empty);
  EXPECT_EQ(into_empty.exit_code, 0) << into_empty.out << into_empty.err;
  EXPECT_TRUE(fs::exists(empty / "summary.json"));
}

TEST(PbaSolveOutputTest, WhatPbaSolveDidNotWriteIsNeverReplaced) {
  TempDir dir;
  const fs::path scene = dir.path() / "block.yaml";
  std::ofstream(scene) << kSmallBlock;
  // A regular file.
  const fs::path file = dir.path() / "thesis.docx";
  std::ofstream(file) << "three years of work";
  for (bool force : {false, true}) {
    ExpectRefused(SolveInto(scene, file, force), "is a file");
    EXPECT_EQ(ReadAll(file), "three years of work");
  }

  // A folder with the user's things beside an earlier result, at its top
  // or inside the import's structures/ folder.
  const fs::path folder = dir.path() / "results";
  ASSERT_EQ(SolveInto(scene, folder).exit_code, 0);
  std::ofstream(folder / "notes.txt") << "mine";
  ExpectRefused(SolveInto(scene, folder, true), "did not write");
  EXPECT_EQ(ReadAll(folder / "notes.txt"), "mine");
  EXPECT_TRUE(fs::exists(folder / "result.h5"));
  fs::remove(folder / "notes.txt");
  fs::create_directories(folder / "structures");
  std::ofstream(folder / "structures" / "draft.txt") << "mine too";
  ExpectRefused(SolveInto(scene, folder, true), "did not write");
  EXPECT_EQ(ReadAll(folder / "structures" / "draft.txt"), "mine too");

  // The import's --out follows the same rule.
  const RunResult import = RunProcess({PBA_SOLVE_BIN, "--import-atlas", "synthetic", "--out",
                                       file.string(), "--force", "--progress", "json"});
  ExpectRefused(import, "is a file");
  EXPECT_EQ(ReadAll(file), "three years of work");

  // A link, to a folder or anywhere.
  const fs::path link = dir.path() / "link";
  fs::create_directory_symlink(dir.path() / "elsewhere", link);
  ExpectRefused(SolveInto(scene, link, true), "symbolic link");
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_FALSE(fs::exists(dir.path() / "elsewhere"));
}

// --atlas-surfaces: a structure set's surfaces as glTF binary, one node per
// structure; a set that cannot be meshed exits 5 naming why and writes
// nothing; with a scene it is a usage error.
TEST(PbaSolveTest, AtlasSurfacesOfAStructureSet) {
  TempDir dir;
  const fs::path set = dir.path() / "set";
  fs::create_directories(set);
  std::string plates;
  for (int z = 0; z <= 20; z += 5) {
    plates += std::string(plates.empty() ? "" : ",") + "{\"z_mm\": " + std::to_string(z) +
              ", \"polygons\": [[[0, 0], [12, 0], [12, 12], [0, 12]]]}";
  }
  std::ofstream(set / "Block.json") << "{\"plates\": [" << plates << "]}";
  std::ofstream(set / "manifest.json")
      << R"({"structures": [{"name": "Block", "file": "Block.json", "format": "contours_json",)"
      << R"( "colour": "200,20,20"}]})";
  const fs::path out = dir.path() / "out";
  const RunResult made = RunProcess({PBA_SOLVE_BIN, "--atlas-surfaces", set.string(), "--out",
                                     out.string(), "--progress", "text"});
  ASSERT_EQ(made.exit_code, 0) << made.out << made.err;
  EXPECT_NE(made.out.find("1 structures' surfaces"), std::string::npos) << made.out;
  const std::string glb = ReadAll(out / "surfaces.glb");
  ASSERT_GT(glb.size(), 20u);
  EXPECT_EQ(glb.substr(0, 4), "glTF");
  EXPECT_NE(glb.find("\"name\":\"Block\""), std::string::npos);
  EXPECT_EQ(glb.find("_DISPLACEMENT"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "summary.json"));

  // One plate has no volume.
  std::ofstream(set / "Block.json", std::ios::trunc)
      << R"({"plates": [{"z_mm": 0, "polygons": [[[0, 0], [12, 0], [12, 12], [0, 12]]]}]})";
  const fs::path flat = dir.path() / "flat";
  const RunResult refused = RunProcess({PBA_SOLVE_BIN, "--atlas-surfaces", set.string(), "--out",
                                        flat.string(), "--progress", "json"});
  EXPECT_EQ(refused.exit_code, 5) << refused.out << refused.err;
  EXPECT_NE(refused.out.find("two heights"), std::string::npos) << refused.out;
  EXPECT_FALSE(fs::exists(flat));
  const RunResult both =
      RunProcess({PBA_SOLVE_BIN, std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml",
                  "--atlas-surfaces", set.string(), "--out", flat.string()});
  EXPECT_EQ(both.exit_code, 2) << both.out << both.err;
  EXPECT_FALSE(fs::exists(flat));
}

}  // namespace
}  // namespace pba::testing
