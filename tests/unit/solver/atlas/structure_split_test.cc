// Splitting an atlas into a structure set (structure_split.h): the
// synthetic atlas into contours, a label volume into masks, file names that
// would clash with the manifest or in case, and the all-or-nothing output
// directory.
#include "atlas/structure_split.h"

#include <gtest/gtest.h>
#include <openssl/evp.h>
#include <unistd.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "atlas/contours.h"
#include "atlas/label_volume_io.h"
#include "atlas/plates.h"
#include "atlas/synthetic_atlas.h"

namespace pba {
namespace {

namespace fs = std::filesystem;

std::string Slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string Sha256Hex(const std::string& bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EXPECT_EQ(EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr), 1);
  static const char kHex[] = "0123456789abcdef";
  std::string hex;
  for (unsigned int i = 0; i < length; ++i) {
    hex += kHex[digest[i] >> 4];
    hex += kHex[digest[i] & 15];
  }
  return hex;
}

std::set<std::string> Entries(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.insert(entry.path().filename());
  return names;
}

class StructureSplitTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("pba_structure_split_test_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  // Two structures on a small anisotropic grid: a block that touches the
  // grid's edge (its mask reaches beyond the grid) and a few scattered
  // voxels; a third table entry has no voxel. The two names differ only in
  // case and punctuation, so their file names must be told apart.
  void WriteLabelVolume(LabelVolume* volume, ColourTable* colours) {
    *volume =
        LabelVolume({7, 6, 5}, Eigen::Vector3d(-3.5, 10.25, 2), Eigen::Vector3d(0.5, 0.75, 1.25));
    for (int k = 0; k < 3; ++k) {
      for (int j = 1; j < 4; ++j) {
        for (int i = 0; i < 2; ++i) volume->set(i, j, k, 1);
      }
    }
    volume->set(5, 4, 3, 2);
    volume->set(3, 1, 4, 2);
    volume->set(6, 5, 1, 2);
    ASSERT_TRUE(WriteNifti(*volume, root_ / "labels.nii.gz").ok());
    // What the split reads: the volume as stored (float32 origin).
    ASSERT_TRUE(ReadNifti(root_ / "labels.nii.gz", volume).ok());
    ASSERT_TRUE(ColourTable::FromEntries({{1, "Nucleus A", 200, 10, 10},
                                          {2, "nucleus_a", 10, 200, 10},
                                          {3, "Absent body", 10, 10, 200}},
                                         colours)
                    .ok());
    ASSERT_TRUE(WriteColourTableCsv(*colours, root_ / "table.csv").ok());
  }

  SplitOptions LabelOptions() const {
    SplitOptions options;
    options.source.source = AtlasBuildOptions::Source::kLabelVolume;
    options.source.input = root_ / "labels.nii.gz";
    options.source.colour_table = root_ / "table.csv";
    return options;
  }

  fs::path root_;
};

TEST_F(StructureSplitTest, SyntheticAtlasGivesOneContoursFilePerPresentStructure) {
  SplitOptions options;
  options.source.synthetic_voxel_mm = 2.0;
  SplitResult result;
  const Status split = SplitAtlas(options, root_ / "set", &result);
  ASSERT_TRUE(split.ok()) << split.ToString();

  // The same plates, rendered here: every structure on them, and only
  // those, has a file holding exactly its traced contours.
  SyntheticAtlasOptions synthetic;
  synthetic.voxel_size_mm = 2.0;
  ASSERT_TRUE(WritePlates(MakeSyntheticAtlas(synthetic), ColourTable::Builtin(), PlateOptions(),
                          root_ / "plates")
                  .ok());
  PlateStack stack;
  ASSERT_TRUE(ReadPlates(root_ / "plates", &stack).ok());
  std::set<std::string> expected_files = {kStructureSetManifest};
  size_t next = 0;
  std::set<std::string> absent(result.absent.begin(), result.absent.end());
  for (const ColourEntry& colour : ColourTable::Builtin().entries()) {
    const Contours contours = TraceContours(stack, colour.label);
    if (contours.plates.empty()) {
      EXPECT_TRUE(absent.count(colour.name)) << colour.name;
      continue;
    }
    EXPECT_FALSE(absent.count(colour.name)) << colour.name;
    ASSERT_LT(next, result.set.structures.size());
    const StructureEntry& entry = result.set.structures[next++];
    EXPECT_EQ(entry.name, colour.name);
    EXPECT_EQ(entry.format, StructureFormat::kContours);
    EXPECT_EQ(fs::path(entry.file).extension(), ".json");
    EXPECT_EQ(std::make_tuple(entry.r, entry.g, entry.b),
              std::make_tuple(colour.r, colour.g, colour.b));
    EXPECT_EQ(entry.revision, 0);
    const std::string text = Slurp(root_ / "set" / entry.file);
    EXPECT_EQ(text, FormatContoursJson(contours)) << entry.name;
    EXPECT_EQ(entry.sha256, Sha256Hex(text)) << entry.name;
    expected_files.insert(entry.file);
  }
  EXPECT_EQ(next, result.set.structures.size());
  EXPECT_EQ(result.set.structures.size() + result.absent.size(), 44u);
  EXPECT_GT(result.set.structures.size(), 35u);
  // Nothing else in the directory (the rendered plates are gone), nothing
  // left beside it.
  EXPECT_EQ(Entries(root_ / "set"), expected_files);
  EXPECT_EQ(Entries(root_), (std::set<std::string>{"plates", "set"}));

  // The manifest as the structure-set reader sees it.
  StructureSet read;
  const Status read_status = ReadStructureSet(root_ / "set", &read);
  ASSERT_TRUE(read_status.ok()) << read_status.ToString();
  ASSERT_EQ(read.structures.size(), result.set.structures.size());
  for (size_t i = 0; i < read.structures.size(); ++i) {
    EXPECT_EQ(read.structures[i].name, result.set.structures[i].name);
    EXPECT_EQ(read.structures[i].file, result.set.structures[i].file);
    EXPECT_EQ(read.structures[i].sha256, result.set.structures[i].sha256);
  }
}

TEST_F(StructureSplitTest, StructuresFilterKeepsGroups) {
  SplitOptions options;
  options.source.synthetic_voxel_mm = 2.5;
  options.structures = {"Thalamus", "Putamen"};
  SplitResult result;
  const Status split = SplitAtlas(options, root_ / "set", &result);
  ASSERT_TRUE(split.ok()) << split.ToString();
  ASSERT_EQ(result.set.structures.size() + result.absent.size(), 12u);
  for (const StructureEntry& entry : result.set.structures) {
    EXPECT_TRUE(entry.name == "Putamen" || InStructureGroup(entry.name, "Thalamus")) << entry.name;
  }

  options.structures = {"Thalamus", "Nucleus nowhere"};
  const Status unknown = SplitAtlas(options, root_ / "other", &result);
  EXPECT_EQ(unknown.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(unknown.field(), "structures[1]");
  EXPECT_FALSE(fs::exists(root_ / "other"));
}

TEST_F(StructureSplitTest, LabelVolumeSplitsIntoCroppedMasksOnTheSameLattice) {
  LabelVolume volume;
  ColourTable colours;
  WriteLabelVolume(&volume, &colours);
  SplitResult result;
  const Status split = SplitAtlas(LabelOptions(), root_ / "set", &result);
  ASSERT_TRUE(split.ok()) << split.ToString();
  EXPECT_EQ(result.absent, std::vector<std::string>{"Absent body"});
  ASSERT_EQ(result.set.structures.size(), 2u);
  EXPECT_EQ(result.set.structures[0].file, "Nucleus_A.nii.gz");
  EXPECT_EQ(result.set.structures[1].file, "nucleus_a_2.nii.gz");

  const std::vector<int64_t> counts = CountLabels(volume);
  for (size_t s = 0; s < 2; ++s) {
    const StructureEntry& entry = result.set.structures[s];
    const uint16_t label = static_cast<uint16_t>(s + 1);
    EXPECT_EQ(entry.format, StructureFormat::kNifti);
    const fs::path file = root_ / "set" / entry.file;
    const std::string bytes = Slurp(file);
    ASSERT_GE(bytes.size(), 2u);
    EXPECT_EQ(static_cast<unsigned char>(bytes[0]), 0x1f) << "gzip";
    EXPECT_EQ(static_cast<unsigned char>(bytes[1]), 0x8b) << "gzip";
    EXPECT_EQ(entry.sha256, Sha256Hex(bytes));

    LabelVolume mask;
    ASSERT_TRUE(ReadNifti(file, &mask).ok());
    EXPECT_TRUE(mask.spacing_mm().isApprox(volume.spacing_mm(), 1e-6));
    int64_t ones = 0;
    for (int k = 0; k < mask.nz(); ++k) {
      for (int j = 0; j < mask.ny(); ++j) {
        for (int i = 0; i < mask.nx(); ++i) {
          const uint16_t value = mask.at(i, j, k);
          ASSERT_LE(value, 1);
          // A border of background all round.
          if (i == 0 || j == 0 || k == 0 || i == mask.nx() - 1 || j == mask.ny() - 1 ||
              k == mask.nz() - 1) {
            EXPECT_EQ(value, 0);
          }
          if (value == 0) continue;
          ++ones;
          // The voxel's centre is one of the original's, with this label.
          const Eigen::Vector3d centre = mask.VoxelCentreMm(i, j, k);
          std::array<int, 3> ijk;
          ASSERT_TRUE(volume.NearestVoxel(centre, &ijk));
          EXPECT_LT((volume.VoxelCentreMm(ijk[0], ijk[1], ijk[2]) - centre).norm(), 1e-4);
          EXPECT_EQ(volume.at(ijk[0], ijk[1], ijk[2]), label);
        }
      }
    }
    EXPECT_EQ(ones, counts[label]) << entry.name;
  }
  // The block spans 2 x 3 x 3 voxels: its mask 4 x 5 x 5.
  LabelVolume block;
  ASSERT_TRUE(ReadNifti(root_ / "set" / "Nucleus_A.nii.gz", &block).ok());
  EXPECT_EQ(block.dims(), (std::array<int, 3>{4, 5, 5}));

  // Only the named structure.
  SplitOptions options = LabelOptions();
  options.structures = {"nucleus_a"};
  ASSERT_TRUE(SplitAtlas(options, root_ / "one", &result).ok());
  ASSERT_EQ(result.set.structures.size(), 1u);
  EXPECT_EQ(result.set.structures[0].name, "nucleus_a");
  EXPECT_EQ(result.set.structures[0].file, "nucleus_a.nii.gz");
}

// A structure named "manifest" split from plates would be manifest.json,
// the manifest's own name; "Foo" and "foo" would be one file on macOS and
// Windows. Each gets a file of its own and the set reads back whole.
TEST_F(StructureSplitTest, PlateNamesClashingWithTheManifestOrInCaseGetFilesOfTheirOwn) {
  LabelVolume volume({20, 10, 6}, Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 1, 1));
  for (int k = 0; k < 6; ++k) {
    for (int j = 2; j < 8; ++j) {
      for (int i = 1; i < 18; ++i) {
        if (i % 6 != 0) volume.set(i, j, k, static_cast<uint16_t>(i / 6 + 1));
      }
    }
  }
  ColourTable colours;
  ASSERT_TRUE(ColourTable::FromEntries(
                  {{1, "manifest", 200, 10, 10}, {2, "Foo", 10, 200, 10}, {3, "foo", 10, 10, 200}},
                  &colours)
                  .ok());
  PlateOptions plates;
  plates.z_mm = {1, 2, 3, 4};
  ASSERT_TRUE(WritePlates(volume, colours, plates, root_ / "plates").ok());
  SplitOptions options;
  options.source.source = AtlasBuildOptions::Source::kPlates;
  options.source.input = root_ / "plates";
  SplitResult result;
  const Status split = SplitAtlas(options, root_ / "set", &result);
  ASSERT_TRUE(split.ok()) << split.ToString();

  std::map<std::string, std::string> files;
  for (const StructureEntry& entry : result.set.structures) files[entry.name] = entry.file;
  EXPECT_EQ(files,
            (std::map<std::string, std::string>{
                {"manifest", "manifest_2.json"}, {"Foo", "Foo.json"}, {"foo", "foo_2.json"}}));
  EXPECT_EQ(Entries(root_ / "set"), (std::set<std::string>{kStructureSetManifest, "manifest_2.json",
                                                           "Foo.json", "foo_2.json"}));
  // Readable: every file where the manifest says, its SHA-256 matching, and
  // the set composes into the three structures.
  StructureSet read;
  const Status read_status = ReadStructureSet(root_ / "set", &read);
  ASSERT_TRUE(read_status.ok()) << read_status.ToString();
  ASSERT_EQ(read.structures.size(), 3u);
  for (const StructureEntry& entry : read.structures) {
    EXPECT_EQ(entry.sha256, Sha256Hex(Slurp(root_ / "set" / entry.file))) << entry.name;
  }
  ComposedAtlas atlas;
  const Status composed = ComposeStructureSet(root_ / "set", read, ComposeOptions(), &atlas);
  ASSERT_TRUE(composed.ok()) << composed.ToString();
  EXPECT_EQ(atlas.colours.entries().size(), 3u);
}

TEST_F(StructureSplitTest, ExistingNonEmptyDirectoryIsRefusedAndLeftAlone) {
  LabelVolume volume;
  ColourTable colours;
  WriteLabelVolume(&volume, &colours);
  fs::create_directories(root_ / "set");
  std::ofstream(root_ / "set" / "keep.txt") << "mine";
  const std::set<std::string> before = Entries(root_);
  SplitResult result;
  const Status split = SplitAtlas(LabelOptions(), root_ / "set", &result);
  EXPECT_FALSE(split.ok());
  EXPECT_EQ(Entries(root_ / "set"), std::set<std::string>{"keep.txt"});
  EXPECT_EQ(Slurp(root_ / "set" / "keep.txt"), "mine");
  EXPECT_EQ(Entries(root_), before);

  // An empty directory is taken.
  fs::create_directories(root_ / "empty");
  const Status into_empty = SplitAtlas(LabelOptions(), root_ / "empty", &result);
  ASSERT_TRUE(into_empty.ok()) << into_empty.ToString();
  EXPECT_TRUE(fs::exists(root_ / "empty" / kStructureSetManifest));
}

TEST_F(StructureSplitTest, FailureLeavesNoDirectory) {
  LabelVolume volume;
  ColourTable colours;
  WriteLabelVolume(&volume, &colours);
  // The first structure is written before the second's name is refused.
  ColourTable bad;
  ASSERT_TRUE(
      ColourTable::FromEntries({{1, "Nucleus A", 200, 10, 10}, {2, "..", 10, 200, 10}}, &bad).ok());
  ASSERT_TRUE(WriteColourTableCsv(bad, root_ / "bad.csv").ok());
  SplitOptions options = LabelOptions();
  options.source.colour_table = root_ / "bad.csv";
  const std::set<std::string> before = Entries(root_);
  SplitResult result;
  const Status split = SplitAtlas(options, root_ / "set", &result);
  EXPECT_EQ(split.code(), Status::Code::kInvalidArgument);
  EXPECT_NE(split.message().find("\"..\""), std::string::npos) << split.ToString();
  EXPECT_FALSE(fs::exists(root_ / "set"));
  EXPECT_EQ(Entries(root_), before);
  EXPECT_TRUE(result.set.structures.empty());

  // A label with no colour-table entry, and a missing input.
  ColourTable partial;
  ASSERT_TRUE(ColourTable::FromEntries({{1, "Nucleus A", 200, 10, 10}}, &partial).ok());
  ASSERT_TRUE(WriteColourTableCsv(partial, root_ / "partial.csv").ok());
  options.source.colour_table = root_ / "partial.csv";
  EXPECT_EQ(SplitAtlas(options, root_ / "set", &result).code(), Status::Code::kInvalidArgument);
  options.source.input = root_ / "missing.nii.gz";
  EXPECT_FALSE(SplitAtlas(options, root_ / "set", &result).ok());
  EXPECT_FALSE(fs::exists(root_ / "set"));
  EXPECT_EQ(Entries(root_),
            (std::set<std::string>{"bad.csv", "labels.nii.gz", "partial.csv", "table.csv"}));
}

}  // namespace
}  // namespace pba
