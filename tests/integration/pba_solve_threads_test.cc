// pba-solve --threads 1 keeps to one core: its own OpenMP loops, CHOLMOD's
// OpenMP teams and OpenBLAS's threads are all bounded by the one count
// (core/thread_context.h). The scene is a pressed C3D8 (HEX8_FULL) cube of
// 16^3 bricks, NONLINEAR_STATIC: about twenty supernodal factorisations of
// 13,000 unknowns, whose large supernodes OpenBLAS would split among its
// threads (before the bound, such a solve took 11.8 s of CPU in 6.2 s).
//
// The check is one-sided and so safe on a busy machine: in a given wall
// time a process can only get less CPU when other processes want the
// cores, never more than its threads can use.

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/subprocess.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;

constexpr char kPressedCube[] =
    "name: c3d8-cube\n"
    "geometry: {box: {size_mm: [10, 10, 10]}}\n"
    "mesh: {element_size_mm: 0.625, element: HEX8_FULL}\n"
    "material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1.0e5}}\n"
    "boundary_conditions:\n"
    "  - {set: bottom, fixed: {}}\n"
    "  - {set: top, displacement: {z_mm: -3}}\n"
    "analysis: {type: NONLINEAR_STATIC, nonlinear: {increments: 10}}\n";

// User plus system time of the children reaped so far [s].
double ChildrenCpuSeconds() {
  rusage usage{};
  ::getrusage(RUSAGE_CHILDREN, &usage);
  const auto seconds = [](const timeval& t) { return t.tv_sec + t.tv_usec * 1e-6; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

TEST(PbaSolveThreadsTest, OneThreadUsesAboutOneCore) {
  TempDir dir;
  const fs::path scene = dir.path() / "cube.yaml";
  std::ofstream(scene) << kPressedCube;
  const fs::path out = dir.path() / "result";
  const double cpu_before = ChildrenCpuSeconds();
  const auto start = std::chrono::steady_clock::now();
  const RunResult run = RunProcess({PBA_SOLVE_BIN, scene.string(), "--out", out.string(),
                                    "--progress", "none", "--threads", "1"},
                                   std::chrono::seconds(300));
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cpu = ChildrenCpuSeconds() - cpu_before;
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  const std::string summary = ReadFile(out / "summary.json");
  EXPECT_NE(summary.find("\"threads\": 1"), std::string::npos) << summary;
  // 1.3: a second thread busy a third of the time fails it. The half
  // second covers start-up: OpenBLAS starts its pool when the library
  // loads, before main, and those threads wait busily for a moment.
  EXPECT_LE(cpu, 1.3 * wall + 0.5) << "CPU " << cpu << " s in " << wall << " s of wall time";
}

}  // namespace
}  // namespace pba::testing
