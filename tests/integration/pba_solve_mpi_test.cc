// pba-solve as an MPI job, `mpirun -np 2 pba-solve SCENE --out DIR`, the way
// users run it: the two ranks share each linear solve and must write the
// answer one process writes (to 1e-8, relative) in the same files, once;
// scenes the ranks cannot share are refused naming the field, and a solve
// that breaks down ends the whole job with the serial exit code.

#include <gtest/gtest.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "common/subprocess.h"
#include "integration/block_scene.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;

// Open MPI refuses root unless told; the ranks may outnumber the cores.
const std::vector<std::string> kMpiEnvironment = {"OMPI_ALLOW_RUN_AS_ROOT=1",
                                                  "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1",
                                                  "OMPI_MCA_rmaps_base_oversubscribe=1"};

// pba-solve SCENE --out OUT [extra...], under mpirun when `ranks` > 1.
RunResult Solve(const fs::path& scene, const fs::path& out, int ranks,
                const std::vector<std::string>& extra = {}) {
  std::vector<std::string> argv;
  if (ranks > 1) argv = {PBA_MPIEXEC, "-np", std::to_string(ranks)};
  for (const std::string& arg : {std::string(PBA_SOLVE_BIN), scene.string(), std::string("--out"),
                                 out.string(), std::string("--progress"), std::string("json")}) {
    argv.push_back(arg);
  }
  argv.insert(argv.end(), extra.begin(), extra.end());
  return RunProcess(argv, kMpiEnvironment, std::chrono::seconds(600));
}

// /fields/displacement of a result.h5, node by node.
std::vector<double> ReadDisplacement(const fs::path& result) {
  std::vector<double> values;
  const hid_t file = H5Fopen(result.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return values;
  const hid_t data = H5Dopen2(file, "/fields/displacement", H5P_DEFAULT);
  if (data >= 0) {
    const hid_t space = H5Dget_space(data);
    hsize_t dims[2] = {0, 0};
    H5Sget_simple_extent_dims(space, dims, nullptr);
    values.resize(dims[0] * dims[1]);
    if (H5Dread(data, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0) {
      values.clear();
    }
    H5Sclose(space);
    H5Dclose(data);
  }
  H5Fclose(file);
  return values;
}

// The relative difference of two result.h5's displacements (infinite when
// either is missing or they differ in size).
double DisplacementDifference(const fs::path& a_result, const fs::path& b_result) {
  const std::vector<double> a = ReadDisplacement(a_result), b = ReadDisplacement(b_result);
  if (a.empty() || a.size() != b.size()) return INFINITY;
  double difference = 0, norm = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    difference += (a[i] - b[i]) * (a[i] - b[i]);
    norm += a[i] * a[i];
  }
  return norm > 0 ? std::sqrt(difference / norm) : INFINITY;
}

// The scene text of an example with `replace` applied to it.
fs::path Variant(const fs::path& dir, const std::string& example,
                 const std::vector<std::pair<std::string, std::string>>& replace) {
  std::string text = ReadFile(fs::path(PBA_EXAMPLES_DIR) / (example + ".yaml"));
  for (const auto& [from, to] : replace) {
    const std::size_t at = text.find(from);
    if (at == std::string::npos) return {};
    text.replace(at, from.size(), to);
  }
  const fs::path path = dir / (example + ".yaml");
  std::ofstream(path) << text;
  return path;
}

struct Case {
  const char* name;
  const char* example;
  std::vector<std::pair<std::string, std::string>> replace;
  const char* serial_solver;  // in the one-process summary's solver line
  const char* ranks_solver;   // in the two-rank one
  // Newton's tangents assembled partitioned on the ranks (the summary's
  // note), as they are for every solver that reads only its ranks' share.
  bool partitioned = false;
};

// `scene` solved by one process and by two ranks into `dir`: the same
// files, written once, the same displacements to 1e-8, the solvers and
// the partitioned assembly `c` names in the summaries.
void ExpectRanksGiveTheSerialAnswer(const fs::path& dir, const fs::path& scene, const Case& c) {
  const RunResult serial = Solve(scene, dir / "serial", 1);
  ASSERT_EQ(serial.exit_code, 0) << serial.err;
  const RunResult ranks = Solve(scene, dir / "ranks", 2);
  ASSERT_EQ(ranks.exit_code, 0) << ranks.err;

  // One writer: the same files, and one DONE event on the job's stdout.
  std::vector<std::string> serial_files, rank_files;
  for (const auto& e : fs::directory_iterator(dir / "serial")) {
    serial_files.push_back(e.path().filename().string());
  }
  for (const auto& e : fs::directory_iterator(dir / "ranks")) {
    rank_files.push_back(e.path().filename().string());
  }
  std::sort(serial_files.begin(), serial_files.end());
  std::sort(rank_files.begin(), rank_files.end());
  EXPECT_EQ(serial_files, rank_files);
  EXPECT_EQ(CountOf(ranks.out, "\"DONE\""), 1u) << ranks.out;

  const double relative =
      DisplacementDifference(dir / "serial" / "result.h5", dir / "ranks" / "result.h5");
  std::printf("%s: 2 ranks against 1, relative difference of the displacements %.2e\n", c.name,
              relative);
  EXPECT_LE(relative, 1e-8);

  const std::string serial_summary = ReadFile(dir / "serial" / "summary.json");
  const std::string rank_summary = ReadFile(dir / "ranks" / "summary.json");
  EXPECT_NE(serial_summary.find(c.serial_solver), std::string::npos) << serial_summary;
  EXPECT_NE(rank_summary.find(c.ranks_solver), std::string::npos) << rank_summary;
  // A fallback is taken on both sides or on neither.
  EXPECT_EQ(serial_summary.find("redone by MUMPS") == std::string::npos,
            rank_summary.find("redone by MUMPS") == std::string::npos)
      << serial_summary << rank_summary;
  EXPECT_NE(rank_summary.find("on 2 MPI ranks"), std::string::npos) << rank_summary;
  const std::regex partitioned(
      "\"([1-9][0-9]*) of ([0-9]+) tangent stiffnesses were assembled "
      "partitioned between the 2 MPI ranks");
  std::smatch tangents;
  EXPECT_EQ(std::regex_search(rank_summary, tangents, partitioned), c.partitioned) << rank_summary;
  if (c.partitioned && !tangents.empty()) {
    // Whole are only the first ones (AUTO reads a tangent to choose, for
    // each of Newton's two solvers) and those a substitute needed.
    EXPECT_GE(2 * std::stoi(tangents[1]), std::stoi(tangents[2])) << rank_summary;
  }
  EXPECT_EQ(serial_summary.find("assembled partitioned"), std::string::npos) << serial_summary;
  EXPECT_TRUE(std::regex_search(rank_summary, std::regex("\"ranks\": 2\\b"))) << rank_summary;
}

class RanksGiveTheSerialAnswer : public ::testing::TestWithParam<Case> {};

TEST_P(RanksGiveTheSerialAnswer, SameFilesSameDisplacements) {
  const Case& c = GetParam();
  TempDir dir;
  const fs::path scene = Variant(dir.path(), c.example, c.replace);
  ASSERT_FALSE(scene.empty()) << "the example changed: " << c.example;
  ExpectRanksGiveTheSerialAnswer(dir.path(), scene, c);
}

const Case kCases[] = {
    // LINEAR_STATIC, multigrid on both sides, to a tolerance that makes
    // the two iterations' answers agree to 1e-8.
    {"linear_amg",
     "quickstart",
     {{"linear_solver: CHOLMOD",
       "linear_solver: AMG\n  linear_solver_options: {relative_tolerance: 1.0e-13}"}},
     "GAMG",
     "GAMG"},
    // AUTO: CHOLMOD in one process, MUMPS across the ranks.
    {"linear_auto",
     "quickstart",
     {{"linear_solver: CHOLMOD", "linear_solver: AUTO"}},
     "CHOLMOD",
     "MUMPS"},
    // NONLINEAR_STATIC on 10-node elements (a pressurised cavity), AUTO.
    {"tet10_cavity", "pressurised_cavity", {}, "CHOLMOD", "MUMPS", true},
    // The same with multigrid, which K / mu = 1e4 defeats: its solves stop
    // at 60 iterations and are redone by MUMPS, across the ranks too.
    {"tet10_cavity_amg_fallback",
     "pressurised_cavity",
     {{"type: NONLINEAR_STATIC",
       "type: NONLINEAR_STATIC\n  linear_solver: AMG\n  linear_solver_options: {max_iterations: "
       "60}"}},
     "redone by MUMPS",
     "redone by MUMPS",
     true},
    // NONLINEAR_STATIC, nearly incompressible Mooney-Rivlin, AMG.
    {"mooney_rivlin_amg",
     "mooney_rivlin_uniaxial",
     {{"type: NONLINEAR_STATIC", "type: NONLINEAR_STATIC\n  linear_solver: AMG"}},
     "GAMG",
     "GAMG",
     true},
    // A rigid punch's contact adds to the tangent after the tissue's
    // partitioned assembly; MUMPS on both sides.
    {"contact_mumps",
     "mooney_rivlin_uniaxial",
     {{"element_size_mm: 5", "element_size_mm: 2.5"},
      {"  - {set: top, displacement: {z_mm: 3}}\n",
       "contacts:\n  - {name: punch, set: top, shape: FLAT_PUNCH, position_mm: [0, 0, 10], "
       "axis: [0, 0, -1], radius_mm: 4, motion_mm: [0, 0, -1.5]}\n"},
      {"type: NONLINEAR_STATIC", "type: NONLINEAR_STATIC\n  linear_solver: MUMPS"},
      {"reaction_sets: [top]", "reaction_sets: [top, bottom]"}},
     "MUMPS",
     "MUMPS",
     true},
    // TET10_MD's element pressures as unknowns (PRESSURE_SCHUR): the mixed
    // system's pressures split between the ranks as well.
    {"tet10md_cavity_pressure_schur",
     "pressurised_cavity",
     {{"element: TET10\n", "element: TET10_MD\n"},
      {"type: NONLINEAR_STATIC",
       "type: NONLINEAR_STATIC\n  linear_solver: AMG\n  linear_solver_options: {preconditioner: "
       "PRESSURE_SCHUR, relative_tolerance: 1.0e-12}"}},
     "1152 pressures",
     "1152 pressures"},
    // QUASI_STATIC through time with a viscoelastic material, AUTO.
    {"viscoelastic_relaxation", "relaxation", {}, "CHOLMOD", "MUMPS", true},
    // mesh.adapt, AUTO: every rank refines its copy of the mesh from the
    // shared answer, cycle after cycle, to the same final mesh.
    {"adaptive_block", "adaptive_block", {}, "CHOLMOD", "MUMPS"},
};

INSTANTIATE_TEST_SUITE_P(Scenes, RanksGiveTheSerialAnswer, ::testing::ValuesIn(kCases),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           return std::string(info.param.name);
                         });

// A bonded TET4_ANP cube compressed by half passes a bifurcation (the
// tangent turns indefinite near 42 %), past which Newton steps with the
// indefinite tangent's LDL^T: across ranks every rank then assembles the
// tangent whole for it, and the ranks land on the serial answer and say
// the same about the instability.
TEST(PbaSolveRanks, PastABifurcationTheRanksTakeTheSerialPath) {
  TempDir dir;
  const fs::path scene = dir.path() / "half_compressed.yaml";
  std::ofstream(scene) << "name: half-compressed\n"
                          "geometry: {box: {size_mm: [10, 10, 10]}}\n"
                          "mesh: {element: TET4_ANP, element_size_mm: 2.5}\n"
                          "material: {neo_hookean: {shear_modulus_pa: 1000, "
                          "bulk_modulus_pa: 1000000}}\n"
                          "boundary_conditions:\n"
                          "  - {set: bottom, fixed: {}}\n"
                          "  - {set: top, displacement: {x_mm: 0, y_mm: 0, z_mm: -5}}\n"
                          "analysis:\n"
                          "  type: NONLINEAR_STATIC\n"
                          "  linear_solver: MUMPS\n"
                          "  nonlinear: {increments: 20}\n"
                          "outputs: {reaction_sets: [top]}\n";
  const Case c{"half_compressed", "", {}, "MUMPS", "MUMPS", true};
  ExpectRanksGiveTheSerialAnswer(dir.path(), scene, c);
  const std::string serial_summary = ReadFile(dir.path() / "serial" / "summary.json");
  const std::string rank_summary = ReadFile(dir.path() / "ranks" / "summary.json");
  const std::regex told(
      "(\\d+) increment\\(s\\) converged to an equilibrium whose tangent "
      "stiffness has up to (\\d+) negative eigenvalue");
  std::smatch serial_told, rank_told;
  ASSERT_TRUE(std::regex_search(serial_summary, serial_told, told)) << serial_summary;
  ASSERT_TRUE(std::regex_search(rank_summary, rank_told, told)) << rank_summary;
  EXPECT_EQ(serial_told.str(0), rank_told.str(0));
}

TEST(PbaSolveRanks, ScenesWithoutASharedSolveAreRefusedNamingTheField) {
  TempDir dir;
  const std::pair<const char*, const char*> refused[] = {
      {"gel_impact", "analysis.type"},          // EXPLICIT_DYNAMIC: no linear solve
      {"quickstart", "analysis.linear_solver"}  // CHOLMOD: one process's
  };
  for (const auto& [example, field] : refused) {
    const fs::path out = dir.path() / example;
    const RunResult run =
        Solve(fs::path(PBA_EXAMPLES_DIR) / (std::string(example) + ".yaml"), out, 2);
    EXPECT_EQ(run.exit_code, 5) << example << ": " << run.err;
    EXPECT_NE(run.err.find(field), std::string::npos) << run.err;
    EXPECT_NE(run.out.find("\"ERROR\""), std::string::npos) << run.out;
    EXPECT_FALSE(fs::exists(out)) << example;
  }
}

TEST(PbaSolveRanks, ABrokenDownSolveEndsTheJobWithTheSerialCodeAndNoResult) {
  TempDir dir;
  // A cube crushed to beyond its height: Newton cannot apply the load.
  const fs::path scene =
      Variant(dir.path(), "mooney_rivlin_uniaxial", {{"z_mm: 3}", "z_mm: -12}"}});
  ASSERT_FALSE(scene.empty());
  const auto start = std::chrono::steady_clock::now();
  const RunResult serial = Solve(scene, dir.path() / "serial", 1);
  const RunResult ranks = Solve(scene, dir.path() / "ranks", 2);
  EXPECT_EQ(serial.exit_code, 11) << serial.err;
  EXPECT_EQ(ranks.exit_code, 11) << ranks.err;
  EXPECT_NE(ranks.err.find("could not be applied beyond"), std::string::npos) << ranks.err;
  EXPECT_FALSE(fs::exists(dir.path() / "ranks"));
  // Neither rank waits for the other after the failure.
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(60));
}

// Checkpoints from rank 0 alone; a restart read by every rank continues to
// the uninterrupted answer.
TEST(PbaSolveRanks, CheckpointAndRestartOnRanksGiveTheUninterruptedAnswer) {
  TempDir dir;
  const fs::path first = dir.path() / "first.yaml", longer = dir.path() / "longer.yaml";
  std::ofstream(first) << HoldSceneYaml(10);
  std::ofstream(longer) << HoldSceneYaml(20);
  const fs::path checkpoints = dir.path() / "checkpoints";
  RunResult run = Solve(first, dir.path() / "first", 2,
                        {"--checkpoint", checkpoints.string(), "--checkpoint-every", "0"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(checkpoints)) {
    files.push_back(e.path().filename().string());
  }
  EXPECT_EQ(files, std::vector<std::string>{"checkpoint.h5"});
  run = Solve(longer, dir.path() / "restarted", 2,
              {"--restart", (checkpoints / "checkpoint.h5").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(ReadFile(dir.path() / "restarted" / "summary.json")
                .find("restarted from a checkpoint at t = 10 s"),
            std::string::npos);
  run = Solve(longer, dir.path() / "uninterrupted", 1);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_LE(DisplacementDifference(dir.path() / "uninterrupted" / "result.h5",
                                   dir.path() / "restarted" / "result.h5"),
            1e-8);
}

// SIGTERM to mpirun (as a shell's Ctrl-C or a scheduler's cancel sends)
// reaches every rank: the job ends cancelled, promptly, with nothing
// written and no rank left running.
TEST(PbaSolveRanks, SigtermToMpirunCancelsEveryRankAndWritesNothing) {
  TempDir dir;
  const fs::path scene = dir.path() / "long.yaml";
  std::ofstream(scene) << BlockSceneYaml("long-running", 50) << "analysis: {linear_solver: AMG}\n";
  const fs::path out = dir.path() / "result";
  const pid_t pid = ::fork();
  if (pid == 0) {
    for (const std::string& entry : kMpiEnvironment) ::putenv(::strdup(entry.c_str()));
    ::freopen("/dev/null", "w", stdout);
    ::execl(PBA_MPIEXEC, PBA_MPIEXEC, "-np", "2", PBA_SOLVE_BIN, scene.c_str(), "--out",
            out.c_str(), "--progress", "json", static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  // The ranks are mpirun's children.
  std::vector<pid_t> ranks;
  for (int i = 0; i < 200 && ranks.size() < 2; ++i) {
    ranks = ChildrenNamed(pid, "pba-solve");
    if (ranks.size() < 2) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_EQ(ranks.size(), 2u);
  std::this_thread::sleep_for(std::chrono::seconds(2));
  const auto signalled = std::chrono::steady_clock::now();
  ::kill(pid, SIGTERM);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_LT(std::chrono::steady_clock::now() - signalled, std::chrono::seconds(15));
  EXPECT_TRUE(!WIFEXITED(status) || WEXITSTATUS(status) != 0) << "a cancelled job reported success";
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1)
      << "a partial result was left behind";
  // A rank that mpirun killed can still be tearing down (state R, its
  // memory already released) in the moment mpirun returns; it must be gone
  // (or a zombie) within two seconds, not left running.
  for (const pid_t rank : ranks) {
    std::string stat;
    bool gone = false;
    for (int i = 0; i < 40 && !gone; ++i) {
      if (i > 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));
      stat = ReadFile("/proc/" + std::to_string(rank) + "/stat");
      gone = ::kill(rank, 0) != 0 || stat.find(") Z") != std::string::npos;
    }
    EXPECT_TRUE(gone) << "rank " << rank << " outlived mpirun by two seconds: " << stat;
  }
}

TEST(PbaSolveRanks, AnOutputDirectoryInTheWayIsRefusedBeforeTheSolve) {
  TempDir dir;
  const fs::path out = dir.path() / "taken";
  fs::create_directories(out);
  std::ofstream(out / "notes.txt") << "mine";
  const RunResult run = Solve(fs::path(PBA_EXAMPLES_DIR) / "relaxation.yaml", out, 2);
  EXPECT_NE(run.exit_code, 0) << run.err;
  EXPECT_EQ(ReadFile(out / "notes.txt"), "mine");
  EXPECT_FALSE(fs::exists(out / "result.h5"));
}

}  // namespace
}  // namespace pba::testing
