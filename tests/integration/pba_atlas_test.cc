// pba-atlas as users call it: the synthetic atlas's plates out of the box,
// an atlas mesh built from them, from the label volume and from the
// synthetic source directly, each with its reports; bad input exits 2
// naming what is wrong and leaves nothing behind.

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "integration/subprocess.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;

std::string ReadFile(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

// The quality report's JSON: every structure has elements and a volume,
// every tetrahedron is valid (aspect ratio finite, dihedral angle > 0), and
// the rows' elements add up to the overall count.
void ExpectQualityReport(const fs::path& dir, size_t structures) {
  const YAML::Node report = YAML::LoadFile((dir / "quality.json").string());
  ASSERT_EQ(report["rows"].size(), structures);
  int64_t elements = 0;
  std::set<std::string> names;
  for (const YAML::Node& row : report["rows"]) {
    EXPECT_GT(row["elements"].as<int64_t>(), 0) << row["structure"].as<std::string>();
    // At least one tetrahedron's four nodes, at most ten per element.
    EXPECT_GE(row["nodes"].as<int64_t>(), 4);
    EXPECT_LE(row["nodes"].as<int64_t>(), 10 * row["elements"].as<int64_t>());
    EXPECT_GT(row["volume_mm3"].as<double>(), 0);
    EXPECT_GT(row["min_dihedral_deg"].as<double>(), 0);
    EXPECT_LT(row["aspect_ratio_max"].as<double>(), 1e3);
    elements += row["elements"].as<int64_t>();
    names.insert(row["structure"].as<std::string>());
  }
  EXPECT_EQ(names.size(), structures);
  EXPECT_EQ(report["overall"]["elements"].as<int64_t>(), elements);
  EXPECT_TRUE(fs::exists(dir / "quality.txt"));
  EXPECT_TRUE(fs::exists(dir / "quality.csv"));
  EXPECT_TRUE(fs::exists(dir / "labels.nii.gz"));
  for (const char* mesh : {"atlas.vtu", "atlas.xdmf", "atlas.h5", "atlas.msh", "atlas.inp"}) {
    EXPECT_TRUE(fs::exists(dir / mesh)) << mesh;
  }
}

class PbaAtlasTest : public ::testing::Test {
 protected:
  // The synthetic atlas at 2 mm voxels, coarse tetrahedra: a few seconds.
  // Coarse and quick: the global sizes everywhere (no finer facets on small
  // structures), no ODT smoothing.
  static std::vector<std::string> Coarse() {
    return {"--cell-mm", "8", "--facet-mm", "4", "--facets-per-section", "0", "--odt", "0"};
  }
  TempDir dir_;
};

TEST_F(PbaAtlasTest, PlatesThenMeshFromThemAndFromTheLabelVolume) {
  const fs::path plates = dir_.path() / "synthetic";
  RunResult run = RunProcess({PBA_ATLAS_BIN, "plates", "-o", plates.string(), "--voxel-mm", "2"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ASSERT_TRUE(fs::exists(plates / "plates" / "plates.json"));
  EXPECT_NE(ReadFile(plates / "plates" / "colour_table.csv").find("not for clinical use"),
            std::string::npos);
  int pngs = 0;
  for (const auto& entry : fs::directory_iterator(plates / "plates")) {
    pngs += entry.path().extension() == ".png";
  }
  EXPECT_EQ(pngs, 27);

  const fs::path from_plates = dir_.path() / "from_plates";
  std::vector<std::string> args = {PBA_ATLAS_BIN,        "build",    "-o",
                                   from_plates.string(), "--plates", (plates / "plates").string(),
                                   "--loft-voxel-mm",    "2"};
  for (const std::string& a : Coarse()) args.push_back(a);
  run = RunProcess(args);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::printf("%s", run.out.c_str());
  ExpectQualityReport(from_plates, 44);
  // Validated against the plates: a row per structure, the overall error
  // finite and below the thesis's limit at this coarse size for the big
  // structures' pooled figure.
  const YAML::Node validation = YAML::LoadFile((from_plates / "validation.json").string());
  EXPECT_EQ(validation["rows"].size(), 44u);
  for (const YAML::Node& row : validation["rows"]) {
    if (row["structure"].as<std::string>() == "White matter") {
      EXPECT_LT(row["percentage_error"].as<double>(), 0.65);
    }
  }

  const fs::path from_labels = dir_.path() / "from_labels";
  args = {PBA_ATLAS_BIN, "build",
          "-o",          from_labels.string(),
          "--labels",    (plates / "labels.nii.gz").string(),
          "--structure", "Putamen",
          "--structure", "Nucleus caudatus",
          "--format",    "json",
          "--roi",       "-24,-5,6,12",
          "--roi-mm",    "2"};
  for (const std::string& a : Coarse()) args.push_back(a);
  run = RunProcess(args);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ExpectQualityReport(from_labels, 2);
  // No plates, no validation; stdout is the report as JSON.
  EXPECT_FALSE(fs::exists(from_labels / "validation.json"));
  EXPECT_EQ(YAML::Load(run.out)["rows"].size(), 2u);
  // The region of interest around the left putamen refines it: more
  // elements than the 8 mm mesh from the plates gave it.
  const auto putamen_elements = [](const fs::path& dir) {
    for (const YAML::Node& row : YAML::LoadFile((dir / "quality.json").string())["rows"]) {
      if (row["structure"].as<std::string>() == "Putamen") return row["elements"].as<int64_t>();
    }
    return int64_t{0};
  };
  EXPECT_GT(putamen_elements(from_labels), 2 * putamen_elements(from_plates));
}

TEST_F(PbaAtlasTest, SyntheticBuildKeepsItsPlates) {
  const fs::path out = dir_.path() / "atlas";
  std::vector<std::string> args = {
      PBA_ATLAS_BIN, "build",           "-o", out.string(), "--synthetic-voxel-mm",
      "2",           "--loft-voxel-mm", "2",  "--quadratic"};
  for (const std::string& a : Coarse()) args.push_back(a);
  const RunResult run = RunProcess(args);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("(10-node)"), std::string::npos) << run.out;
  ExpectQualityReport(out, 44);
  EXPECT_TRUE(fs::exists(out / "plates" / "plates.json"));
  EXPECT_TRUE(fs::exists(out / "validation.csv"));
  // The synthetic atlas says what it is in the files it writes.
  for (const char* mesh : {"atlas.vtu", "atlas.msh", "atlas.inp"}) {
    EXPECT_NE(ReadFile(out / mesh).find("not for clinical use"), std::string::npos) << mesh;
  }
  // 10-node elements in every form: VTK_QUADRATIC_TETRA, Gmsh type 11, C3D10.
  EXPECT_NE(ReadFile(out / "atlas.inp").find("C3D10"), std::string::npos);
}

// Two structures kept, the rest merged into one region around them; the
// validation judges only the two.
TEST_F(PbaAtlasTest, MergedRestIsOneRegionAndOnlyKeptStructuresAreJudged) {
  const fs::path out = dir_.path() / "atlas";
  std::vector<std::string> args = {PBA_ATLAS_BIN,
                                   "build",
                                   "-o",
                                   out.string(),
                                   "--synthetic-voxel-mm",
                                   "2",
                                   "--loft-voxel-mm",
                                   "2",
                                   "--structure",
                                   "Putamen",
                                   "--structure",
                                   "Thalamus: pulvinar",
                                   "--merge-rest"};
  for (const std::string& a : Coarse()) args.push_back(a);
  const RunResult run = RunProcess(args);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("42 structures merged into \"Surrounding tissue\""), std::string::npos)
      << run.out;
  ExpectQualityReport(out, 3);
  std::set<std::string> judged;
  for (const YAML::Node& row : YAML::LoadFile((out / "validation.json").string())["rows"]) {
    judged.insert(row["structure"].as<std::string>());
  }
  EXPECT_EQ(judged, (std::set<std::string>{"Putamen", "Thalamus: pulvinar"}));
}

TEST_F(PbaAtlasTest, BadInputExitsTwoNamingItAndWritesNothing) {
  const fs::path out = dir_.path() / "atlas";
  RunResult run = RunProcess({PBA_ATLAS_BIN, "build", "-o", out.string(), "--synthetic-voxel-mm",
                              "2", "--structure", "Amygdala"});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("structures[0]"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("Amygdala"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(out));

  run = RunProcess({PBA_ATLAS_BIN, "build", "-o", out.string(), "--cell-mm", "-1"});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("cell_size_mm"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(out));

  run = RunProcess({PBA_ATLAS_BIN, "build", "-o", out.string(), "--labels",
                    (dir_.path() / "missing.nii.gz").string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("missing.nii.gz"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(out));
  // Nothing half-written beside it either.
  for (const auto& entry : fs::directory_iterator(dir_.path())) {
    ADD_FAILURE() << "left behind: " << entry.path();
  }
}

}  // namespace
}  // namespace pba::testing
