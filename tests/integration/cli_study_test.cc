// `pba study convergence` end to end: the real pba-server on loopback, the
// real pba client, the real pba-solve, on the quick-start block.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "common/subprocess.h"
#include "integration/server_fixture.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;

constexpr int kInvalid = 5;  // client_cli/exit_codes.h

// The whitespace-separated cells of the printed line that starts with `first`.
std::vector<std::string> Row(const std::string& out, const std::string& first) {
  std::stringstream lines(out);
  for (std::string line; std::getline(lines, line);) {
    std::stringstream cells(line);
    std::vector<std::string> row;
    for (std::string cell; cells >> cell;) row.push_back(cell);
    if (!row.empty() && row[0] == first) return row;
  }
  return {};
}

using CliStudyTest = ServerTest;

// Three meshes of the quick-start block (element sizes 2, 1.418, 1.006 mm:
// 9000 to 72000 tetrahedra, about a second of solving in all). The top's
// prescribed displacement is the largest one on every mesh, so that
// quantity is reported unchanged; the strain energy converges, with a
// finite order and GCI. A rerun finds every job in the state file.
TEST_F(CliStudyTest, ConvergenceStudyOfTheQuickStartBlockAndItsRerun) {
  const fs::path csv = dir_.path() / "quickstart.convergence.csv";
  const std::vector<std::string> args = {"study",
                                         "convergence",
                                         std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml",
                                         "--quantity",
                                         "results.max_displacement_mm",
                                         "--quantity",
                                         "results.strain_energy_j",
                                         "--meshes",
                                         "3",
                                         "--out",
                                         csv.string()};
  const RunResult run = Pba(args);
  std::cout << run.out;
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("3 meshes (element size 2, 1.418, 1.006 mm)"), std::string::npos)
      << run.out;

  // mesh, size, elements, nodes, wall time, then per quantity: value, change, below 5 %.
  double previous = 0;
  for (const char* mesh : {"1", "2", "3"}) {
    const std::vector<std::string> row = Row(run.out, mesh);
    ASSERT_EQ(row.size(), 11u) << "mesh " << mesh << ":\n" << run.out;
    const double elements = std::stod(row[2]);
    EXPECT_GT(elements, previous) << run.out;
    previous = elements;
    EXPECT_GE(std::stod(row[4]), 0) << row[4];
    EXPECT_EQ(std::stod(row[5]), 1.5) << "the prescribed top displacement";
  }
  EXPECT_EQ(Row(run.out, "3")[7], "yes") << run.out;  // 1.5 again: a change below 5 %

  // quantity, convergence, r21, r32, p, extrapolate, e_ext, GCI fine, GCI coarse, ratio.
  const std::vector<std::string> energy = Row(run.out, "results.strain_energy_j");
  ASSERT_EQ(energy.size(), 10u) << run.out;
  EXPECT_EQ(energy[1], "monotone");
  const double order = std::stod(energy[4]), gci = std::stod(energy[7]);
  EXPECT_TRUE(std::isfinite(order) && order > 0.5 && order < 3) << energy[4];
  EXPECT_TRUE(std::isfinite(gci) && gci > 0 && gci < 20) << energy[7];
  EXPECT_LT(std::stod(energy[5]), std::stod(Row(run.out, "3")[8])) << "energy falls to its limit";
  const std::vector<std::string> top = Row(run.out, "results.max_displacement_mm");
  ASSERT_EQ(top.size(), 10u) << run.out;
  EXPECT_EQ(top[1], "unchanged");
  EXPECT_EQ(top[4], "-") << "no order for a value that does not change";
  EXPECT_EQ(run.out.find("nan"), std::string::npos) << run.out;

  const std::string table = ReadFile(csv);
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 4) << table;
  EXPECT_EQ(table.rfind("mesh,element_size_mm,elements,nodes,wall_time_s,job,", 0), 0u) << table;
  EXPECT_TRUE(fs::exists(csv.string() + ".pba-study"));
  EXPECT_EQ(JobCount(), 3u);

  const RunResult again = Pba(args);
  ASSERT_EQ(again.exit_code, 0) << again.out << again.err;
  EXPECT_NE(again.out.find("3 from an earlier run, 0 to submit"), std::string::npos) << again.out;
  EXPECT_EQ(again.out.find("submitted"), std::string::npos) << again.out;
  EXPECT_EQ(Row(again.out, "results.strain_energy_j"), energy);
  EXPECT_EQ(JobCount(), 3u);

  // The same as JSON: numbers as numbers, no extrapolate where there is none.
  std::vector<std::string> json_args = args;
  json_args.insert(json_args.begin(), "--json");
  const RunResult json = Pba(json_args);
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_NE(json.out.find("\"convergence\": \"monotone\""), std::string::npos) << json.out;
  EXPECT_NE(json.out.find("\"gci_fine_pct\": "), std::string::npos) << json.out;
  EXPECT_NE(json.out.find("\"elements\": 72000"), std::string::npos) << json.out;
  EXPECT_EQ(json.out.find("nan"), std::string::npos) << json.out;
  EXPECT_EQ(JobCount(), 3u);
}

// A quantity the summary does not have is named, with what is there,
// before anything is submitted.
TEST_F(CliStudyTest, UnknownQuantityIsNamedAndNothingIsSubmitted) {
  const RunResult run =
      Pba({"study", "convergence", std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml", "--quantity",
           "results.max_displacement", "--out", (dir_.path() / "bad.csv").string()});
  EXPECT_EQ(run.exit_code, kInvalid) << run.out << run.err;
  EXPECT_NE(run.err.find("results.max_displacement"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("max_displacement_mm"), std::string::npos) << run.err;
  EXPECT_EQ(JobCount(), 0u);
  EXPECT_FALSE(fs::exists(dir_.path() / "bad.csv.pba-study"));
}

// An adaptive scene is refused: each member would refine its own mesh.
TEST_F(CliStudyTest, AnAdaptiveSceneIsRefusedAndNothingIsSubmitted) {
  const RunResult run =
      Pba({"study", "convergence", std::string(PBA_EXAMPLES_DIR) + "/adaptive_block.yaml",
           "--quantity", "results.strain_energy_j", "--out", (dir_.path() / "a.csv").string()});
  EXPECT_EQ(run.exit_code, kInvalid) << run.out << run.err;
  EXPECT_NE(run.err.find("mesh.adapt"), std::string::npos) << run.err;
  EXPECT_EQ(JobCount(), 0u);
  EXPECT_FALSE(fs::exists(dir_.path() / "a.csv"));
}

// An atlas scene's region of interest and facets are refined with the
// mesh: each scaled by the ratio of the element sizes (--dry-run: nothing
// is meshed or submitted).
TEST_F(CliStudyTest, AtlasRegionOfInterestScalesWithTheMesh) {
  const fs::path scene = dir_.path() / "roi.yaml";
  std::ofstream(scene) << R"(
name: roi-study
geometry:
  atlas:
    source: synthetic
    facet_size_mm: 5
    roi_centre_mm: [25, -29, 60]
    roi_radius_mm: 20
    roi_element_size_mm: 4
mesh: {element: TET4_ANP, element_size_mm: 10}
material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}
boundary_conditions:
  - {set: surface, fixed: {}}
)";
  const RunResult run =
      Pba({"study", "convergence", scene.string(), "--quantity", "results.max_von_mises_pa",
           "--meshes", "3", "--ratio", "2", "--dry-run"});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("mesh 1: mesh.element_size_mm = 10, geometry.atlas.roi_element_size_mm = "
                         "4, geometry.atlas.facet_size_mm = 5"),
            std::string::npos)
      << run.out;
  EXPECT_NE(run.out.find("mesh 3: mesh.element_size_mm = 2.5, geometry.atlas.roi_element_size_mm "
                         "= 1, geometry.atlas.facet_size_mm = 1.25"),
            std::string::npos)
      << run.out;
  EXPECT_NE(run.out.find("3 meshes; nothing submitted"), std::string::npos) << run.out;
  EXPECT_EQ(JobCount(), 0u);
}

}  // namespace
}  // namespace pba::testing
