// Structure sets: the manifest's checks and round trip, the contours' JSON
// form, and composing a set into plates or a label volume that BuildAtlas
// meshes.
#include "atlas/structure_set.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "atlas/atlas_build.h"
#include "atlas/contours.h"
#include "atlas/label_volume_io.h"
#include "atlas/structure_overlap.h"
#include "common/yaml_bombs.h"

namespace pba {
namespace {

namespace fs = std::filesystem;

void WriteText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// A rectangle [x0, x1] x [y0, y1] on each of the heights.
Contours Box(double x0, double x1, double y0, double y1, const std::vector<double>& heights) {
  Contours c;
  c.pixel_size_mm = 0.5;
  for (double z : heights) {
    ContourPlate plate;
    plate.z_mm = z;
    plate.polygons.push_back({{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}});
    c.plates.push_back(plate);
  }
  return c;
}

StructureEntry Entry(const std::string& name, const std::string& file, StructureFormat format,
                     uint8_t r) {
  StructureEntry e;
  e.name = name;
  e.file = file;
  e.format = format;
  e.r = r;
  e.g = 100;
  e.b = 50;
  return e;
}

// An ASCII STL of the cube [lo, lo + side]^3, faces outwards.
std::string StlCube(const Eigen::Vector3d& lo, double side) {
  static const int kQuads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                   {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  const auto corner = [&](int k) -> Eigen::Vector3d {
    return lo + side * Eigen::Vector3d(k & 1, (k >> 1) & 1, (k >> 2) & 1);
  };
  std::string stl = "solid cube\n";
  for (const auto& q : kQuads) {
    for (const auto& t : {std::array<int, 3>{q[0], q[1], q[2]}, {q[0], q[2], q[3]}}) {
      stl += " facet normal 0 0 0\n  outer loop\n";
      for (int k : t) {
        const Eigen::Vector3d p = corner(k);
        stl += "   vertex " + std::to_string(p.x()) + " " + std::to_string(p.y()) + " " +
               std::to_string(p.z()) + "\n";
      }
      stl += "  endloop\n endfacet\n";
    }
  }
  return stl + "endsolid cube\n";
}

class StructureSetTest : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(testing::TempDir()) /
           ("structure_set_" +
            std::string(testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes the contours as <name>.json and returns their entry.
  StructureEntry AddContours(const std::string& name, const Contours& c, uint8_t r) {
    WriteText(dir_ / (name + ".json"), FormatContoursJson(c));
    return Entry(name, name + ".json", StructureFormat::kContours, r);
  }

  Status Compose(const StructureSet& set, ComposedAtlas* atlas, double voxel_mm = 1) {
    EXPECT_TRUE(WriteStructureSet(set, dir_).ok());
    StructureSet read;
    PBA_RETURN_IF_ERROR(ReadStructureSet(dir_, &read));
    ComposeOptions options;
    options.voxel_size_mm = voxel_mm;
    return ComposeStructureSet(dir_, read, options, atlas);
  }

  fs::path dir_;
};

TEST_F(StructureSetTest, ManifestErrorsNameTheEntry) {
  StructureSet set;
  EXPECT_EQ(ReadStructureSet(dir_, &set).code(), Status::Code::kIo);
  EXPECT_FALSE(IsStructureSetDir(dir_));
  WriteText(dir_ / "a.json", "{}");
  WriteText(dir_ / "b.json", "{}");
  const auto read = [&](const std::string& structures) {
    WriteText(dir_ / "manifest.json", "{\"structures\": [" + structures + "]}");
    EXPECT_TRUE(IsStructureSetDir(dir_));
    return ReadStructureSet(dir_, &set);
  };
  const std::string a = R"({"name": "A", "file": "a.json", "format": "contours_json", )"
                        R"("colour": "10,20,30"})";
  EXPECT_TRUE(read(a).ok());
  const Status missing =
      read(a + R"(, {"name": "B", "file": "c.json", "format": "nifti", "colour": "1,2,3"})");
  EXPECT_EQ(missing.field(), "structures[1].file");
  const Status duplicate =
      read(a + R"(, {"name": "A", "file": "b.json", "format": "stl", "colour": "1,2,3"})");
  EXPECT_EQ(duplicate.field(), "structures[1].name");
  EXPECT_NE(duplicate.message().find("'A'"), std::string::npos) << duplicate.ToString();
  const Status black =
      read(R"({"name": "B", "file": "b.json", "format": "stl", "colour": "0,0,0"})");
  EXPECT_EQ(black.field(), "structures[0].colour");
  EXPECT_NE(black.message().find("'B'"), std::string::npos) << black.ToString();
  const Status same_colour =
      read(a + R"(, {"name": "B", "file": "b.json", "format": "stl", "colour": "10,20,30"})");
  EXPECT_EQ(same_colour.field(), "structures[1].colour");
  EXPECT_NE(same_colour.message().find("taken by structure 'A'"), std::string::npos)
      << same_colour.ToString();
  const Status format =
      read(R"({"name": "B", "file": "b.json", "format": "ply", "colour": "1,2,3"})");
  EXPECT_EQ(format.field(), "structures[0].format");
  EXPECT_NE(format.message().find("'ply'"), std::string::npos) << format.ToString();
  const Status sha = read(R"({"name": "B", "file": "b.json", "format": "stl", "colour": "1,2,3",)"
                          R"( "sha256": ")" +
                          std::string(64, '0') + "\"}");
  EXPECT_EQ(sha.field(), "structures[0].sha256");
  EXPECT_NE(sha.message().find("'B'"), std::string::npos) << sha.ToString();
  EXPECT_NE(sha.message().find("the manifest says 0000"), std::string::npos) << sha.ToString();
  const Status slash =
      read(R"({"name": "A/B", "file": "b.json", "format": "stl", "colour": "1,2,3"})");
  EXPECT_EQ(slash.field(), "structures[0].name");
  EXPECT_EQ(read("").field(), "structures");
  for (const Status& s : {missing, duplicate, black, same_colour, format, sha, slash}) {
    EXPECT_EQ(s.code(), Status::Code::kInvalidArgument) << s.ToString();
  }
}

TEST_F(StructureSetTest, ManifestRoundTripsWithItsChecksums) {
  WriteText(dir_ / "abc.stl", "abc");
  StructureSet set;
  set.project = "demo \"atlas\"";
  set.snapshot = 3;
  set.snapshot_name = "before edits";
  StructureEntry e = Entry("Putamen", "abc.stl", StructureFormat::kStl, 200);
  // SHA-256 of "abc" (FIPS 180-2, appendix B.1).
  e.sha256 = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";
  e.revision = 4;
  e.group_path = "Basal ganglia/Striatum";
  e.material_json = R"({"model": "neo_hookean", "mu_pa": 1000})";
  set.structures.push_back(e);
  set.structures.push_back(Entry("Caudate", "abc.stl", StructureFormat::kObj, 7));
  ASSERT_TRUE(WriteStructureSet(set, dir_).ok());
  StructureSet read;
  const Status s = ReadStructureSet(dir_, &read);
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_EQ(read.project, set.project);
  EXPECT_EQ(read.snapshot, 3);
  EXPECT_EQ(read.snapshot_name, set.snapshot_name);
  ASSERT_EQ(read.structures.size(), 2u);
  const StructureEntry& r = read.structures[0];
  EXPECT_EQ(r.name, e.name);
  EXPECT_EQ(r.file, e.file);
  EXPECT_EQ(r.format, StructureFormat::kStl);
  EXPECT_EQ((std::array<int, 3>{r.r, r.g, r.b}), (std::array<int, 3>{200, 100, 50}));
  EXPECT_EQ(r.sha256, e.sha256);
  EXPECT_EQ(r.revision, 4);
  EXPECT_EQ(r.group_path, e.group_path);
  EXPECT_EQ(r.material_json, e.material_json);
  EXPECT_EQ(read.structures[1].format, StructureFormat::kObj);
  for (StructureFormat f : {StructureFormat::kContours, StructureFormat::kNifti,
                            StructureFormat::kStl, StructureFormat::kObj, StructureFormat::kVtk}) {
    StructureFormat parsed = StructureFormat::kContours;
    EXPECT_TRUE(ParseStructureFormat(StructureFormatName(f), &parsed));
    EXPECT_EQ(parsed, f);
  }
}

// A structure named "manifest" is a legal name; its file must not be the
// manifest's, nor "Foo"'s and "foo"'s one file where case is folded.
TEST_F(StructureSetTest, FileNamesNeverTakeTheManifestsOrDifferOnlyInCase) {
  StructureFileNames names;
  EXPECT_EQ(names.Take("manifest", ".json"), "manifest_2.json");
  EXPECT_EQ(names.Take("Manifest", ".json"), "Manifest_3.json");
  EXPECT_EQ(names.Take("manifest", ".stl"), "manifest.stl");
  EXPECT_EQ(names.Take("Foo", ".json"), "Foo.json");
  EXPECT_EQ(names.Take("foo", ".json"), "foo_2.json");
  EXPECT_EQ(names.Take("foo_2", ".json"), "foo_2_2.json");

  // A manifest naming itself as a structure's file is refused, naming the
  // entry, and so is writing one.
  StructureSet set;
  set.structures.push_back(
      Entry("manifest", kStructureSetManifest, StructureFormat::kContours, 10));
  const Status written = WriteStructureSet(set, dir_);
  EXPECT_EQ(written.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(written.field(), "structures[0].file");
  EXPECT_NE(written.message().find("'manifest'"), std::string::npos) << written.ToString();
  WriteText(dir_ / kStructureSetManifest,
            R"({"structures": [{"name": "manifest", "file": "manifest.json", )"
            R"("format": "contours_json", "colour": "10,20,30"}]})");
  const Status read = ReadStructureSet(dir_, &set);
  EXPECT_EQ(read.field(), "structures[0].file");
  EXPECT_NE(read.message().find("is the manifest"), std::string::npos) << read.ToString();
}

// Nine levels of ten aliases (the "billion laughs") as a manifest's
// structures and as a contours file's polygons: refused before loading,
// naming the file (the manifest) or the field (the contours) and the line.
using yaml_bombs::AliasLevels;

TEST_F(StructureSetTest, AManifestOfAliasesIsRefusedNamingTheFile) {
  WriteText(dir_ / "a.json", "{}");
  WriteText(dir_ / kStructureSetManifest,
            AliasLevels(R"({"name": "A", "file": "a.json", "format": "contours_json", )"
                        R"("colour": "10,20,30"})") +
                "structures: *l9\n");
  const auto start = std::chrono::steady_clock::now();
  StructureSet set;
  const Status read = ReadStructureSet(dir_, &set);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 2);
  EXPECT_EQ(read.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(read.field(), "manifest.json");
  EXPECT_NE(read.ToString().find("manifest.json: line 2: YAML aliases (*l0) are not accepted"),
            std::string::npos)
      << read.ToString();
}

TEST(ContoursJsonTest, AliasesAreRefusedBeforeLoading) {
  const std::string bomb =
      AliasLevels("[[0, 0], [10, 0], [0, 10]]") + "plates: [{z_mm: 0, polygons: *l9}]\n";
  const auto start = std::chrono::steady_clock::now();
  Contours contours;
  const Status s = ParseContoursJson(bomb, "upload", &contours);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 2);
  EXPECT_EQ(s.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(s.field(), "upload");
  EXPECT_EQ(s.message().rfind("contours JSON: line 2: YAML aliases (*l0)", 0), 0u) << s.ToString();
}

TEST(ContoursJsonTest, NumbersRoundTripAndErrorsNameTheirPlace) {
  Contours c = Box(0.1, 1.0 / 3, -2.7, 4e-5, {2, -1.25});
  c.plates[1].polygons.push_back({{10, 10}, {11, 10}, {10.5, 11.0 / 7}});
  Contours read;
  const Status s = ParseContoursJson(FormatContoursJson(c), "f", &read);
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_EQ(read.pixel_size_mm, 0.5);
  ASSERT_EQ(read.plates.size(), 2u);
  EXPECT_EQ(read.plates[0].z_mm, -1.25);  // sorted by height
  EXPECT_EQ(read.plates[1].z_mm, 2);
  EXPECT_EQ(read.plates[1].polygons, c.plates[0].polygons);
  EXPECT_EQ(read.plates[0].polygons, c.plates[1].polygons);

  const auto error = [](const std::string& text) {
    Contours ignored;
    const Status s = ParseContoursJson(text, "upload", &ignored);
    EXPECT_EQ(s.field(), "upload");
    return s.message();
  };
  const std::string square = R"([[0, 0], [1, 0], [1, 1]])";
  EXPECT_NE(error("[1, 2]").find("top level"), std::string::npos);
  EXPECT_NE(error(R"({"plates": []})").find("plates"), std::string::npos);
  EXPECT_NE(error(R"({"plates": [{"z_mm": 1, "polygons": [)" + square +
                  R"(]}, {"z_mm": 1, "polygons": [)" + square + "]}]}")
                .find("plates[1].z_mm: another plate"),
            std::string::npos);
  EXPECT_NE(error(R"({"plates": [{"z_mm": 1, "polygons": [[[0, 0], [1, 1], [2, 2]]]}]})")
                .find("plates[0].polygons[0]: has no area"),
            std::string::npos);
  EXPECT_NE(error(R"({"plates": [{"z_mm": 1, "polygons": [[[0, 0], [1, 0], [1, 900]]]}]})")
                .find("plates[0].polygons[0][2]"),
            std::string::npos);
  EXPECT_NE(error(R"({"plates": [{"z_mm": 1, "polygons": [[[0, 0], [1, 0], [1, "1"]]]}]})")
                .find("plates[0].polygons[0][2]"),
            std::string::npos);
  EXPECT_NE(error(R"({"pixel_size_mm": 20, "plates": [{"z_mm": 1, "polygons": [)" + square + "]}]}")
                .find("pixel_size_mm"),
            std::string::npos);
  EXPECT_NE(error("{\"plates\": [").find("not valid JSON"), std::string::npos);
}

// Two structures drawn on the same heights, on pixel faces: the plates hold
// exactly the pixels whose centres they enclose.
TEST_F(StructureSetTest, ContoursOnSharedHeightsComposeToTheirPixels) {
  StructureSet set;
  set.structures.push_back(AddContours("B", Box(0, 10, 0, 5, {0, 2}), 20));
  set.structures.push_back(AddContours("A", Box(12, 15.5, -3, 6, {0, 2}), 10));
  ComposedAtlas atlas;
  const Status s = Compose(set, &atlas);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_TRUE(atlas.plates.has_value());
  EXPECT_FALSE(atlas.volume.has_value());
  EXPECT_TRUE(atlas.notes.empty());
  const PlateStack& p = *atlas.plates;
  ASSERT_EQ(p.num_plates(), 2);
  EXPECT_EQ(p.pixel_size_mm, 0.5);
  ASSERT_NE(atlas.colours.FindByName("A"), nullptr);
  EXPECT_EQ(atlas.colours.FindByName("A")->label, 1);  // byte-wise name order
  EXPECT_EQ(atlas.colours.FindByName("B")->label, 2);
  EXPECT_EQ(atlas.colours.FindByName("B")->r, 20);
  for (int plate = 0; plate < 2; ++plate) {
    int counts[3] = {0, 0, 0};
    for (int r = 0; r < p.height; ++r) {
      for (int c = 0; c < p.width; ++c) {
        const Eigen::Vector3d x = p.PixelCentreMm(plate, c, r);
        const int expected = (x.x() > 12 && x.x() < 15.5 && x.y() > -3 && x.y() < 6) ? 1
                             : (x.x() > 0 && x.x() < 10 && x.y() > 0 && x.y() < 5)   ? 2
                                                                                     : 0;
        ASSERT_EQ(p.at(plate, c, r), expected) << "plate " << plate << " at " << x.transpose();
        ++counts[expected];
      }
    }
    EXPECT_EQ(counts[1], 7 * 18);
    EXPECT_EQ(counts[2], 20 * 10);
  }
}

// A polygon inside another is a hole (even-odd rule), whichever way round
// either is drawn.
TEST_F(StructureSetTest, APolygonInsideAnotherIsAHole) {
  Contours ring = Box(0, 10, 0, 10, {0, 2});
  for (ContourPlate& plate : ring.plates) {
    plate.polygons.push_back({{3, 3}, {3, 7}, {7, 7}, {7, 3}});
  }
  StructureSet set;
  set.structures.push_back(AddContours("Ring", ring, 10));
  ComposedAtlas atlas;
  const Status s = Compose(set, &atlas);
  ASSERT_TRUE(s.ok()) << s.ToString();
  const PlateStack& p = *atlas.plates;
  for (int plate = 0; plate < 2; ++plate) {
    int count = 0;
    for (uint16_t l : p.labels[plate]) count += l == 1;
    EXPECT_EQ(count, 20 * 20 - 8 * 8);
    const Eigen::Vector3d centre = p.PixelCentreMm(plate, 0, 0);
    const int c = static_cast<int>(std::lround((5.25 - centre.x()) / p.pixel_size_mm));
    const int r = static_cast<int>(std::lround((centre.y() - 5.25) / p.pixel_size_mm));
    EXPECT_EQ(p.at(plate, c, r), 0);
  }
}

// B is drawn at z = 0 and 4 only, A at 0, 2 and 4: B's section on A's
// plate at z = 2 is interpolated from its own (here the same square).
TEST_F(StructureSetTest, AStructureGetsASectionOnPlatesBetweenItsOwn) {
  StructureSet set;
  set.structures.push_back(AddContours("A", Box(0, 10, 0, 10, {0, 2, 4}), 10));
  set.structures.push_back(AddContours("B", Box(20, 30, 0, 8, {0, 4}), 20));
  set.structures.push_back(AddContours("C", Box(-10, -5, 0, 8, {2}), 30));
  ComposedAtlas atlas;
  const Status s = Compose(set, &atlas);
  ASSERT_TRUE(s.ok()) << s.ToString();
  const PlateStack& p = *atlas.plates;
  ASSERT_EQ(p.z_mm, (std::vector<double>{0, 2, 4}));
  int on_own[3] = {0, 0, 0}, b_elsewhere = 0, c_count[3] = {0, 0, 0};
  for (int plate = 0; plate < 3; ++plate) {
    for (int r = 0; r < p.height; ++r) {
      for (int c = 0; c < p.width; ++c) {
        const Eigen::Vector3d x = p.PixelCentreMm(plate, c, r);
        if (p.at(plate, c, r) == 3) ++c_count[plate];
        if (p.at(plate, c, r) != 2) continue;
        if (x.x() > 20 && x.x() < 30 && x.y() > 0 && x.y() < 8) {
          ++on_own[plate];
        } else {
          ++b_elsewhere;
        }
      }
    }
  }
  EXPECT_EQ(on_own[0], 20 * 16);
  EXPECT_EQ(on_own[2], 20 * 16);
  // The loft of two equal sections is that section.
  EXPECT_GE(on_own[1], 20 * 16 - 2 * (20 + 16));
  EXPECT_EQ(b_elsewhere, 0);
  // C is on one plate only: nothing is made up above or below it.
  EXPECT_EQ(c_count[0], 0);
  EXPECT_EQ(c_count[1], 10 * 16);
  EXPECT_EQ(c_count[2], 0);
}

TEST_F(StructureSetTest, OverlapsAreReportedAndTheFirstNameKeepsThePixels) {
  StructureSet set;
  set.structures.push_back(AddContours("Beta", Box(0, 10, 0, 10, {0, 3}), 20));
  set.structures.push_back(AddContours("Alpha", Box(8, 18, 0, 10, {3}), 10));
  ComposedAtlas atlas;
  const Status s = Compose(set, &atlas);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(atlas.notes.size(), 1u);
  // 2 mm x 10 mm of 0.5 mm pixels at z = 3.
  EXPECT_NE(atlas.notes[0].find("Alpha and Beta overlap on 80 pixels (20 mm^2) at z = 3 mm"),
            std::string::npos)
      << atlas.notes[0];
  const PlateStack& p = *atlas.plates;
  int alpha = 0;
  for (uint16_t l : p.labels[1]) alpha += l == 1;
  EXPECT_EQ(alpha, 20 * 20);
}

// A mask, a closed surface and contours on one voxel grid: each structure's
// voxel count is its volume within a layer of voxels over its surface.
TEST_F(StructureSetTest, MasksSurfacesAndContoursComposeToOneVolume) {
  // The mask: a 10 x 8 x 6 mm box of 1 mm voxels.
  LabelVolume mask({14, 12, 10}, Eigen::Vector3d(-20.5, -0.5, -0.5), Eigen::Vector3d::Ones());
  for (int k = 2; k < 8; ++k) {
    for (int j = 2; j < 10; ++j) {
      for (int i = 2; i < 12; ++i) mask.set(i, j, k, 1);
    }
  }
  ASSERT_TRUE(WriteNifti(mask, dir_ / "mask.nii.gz").ok());
  WriteText(dir_ / "cube.stl", StlCube(Eigen::Vector3d(10, 0, 0), 10));
  StructureSet set;
  set.structures.push_back(Entry("Mask", "mask.nii.gz", StructureFormat::kNifti, 10));
  set.structures.push_back(Entry("Cube", "cube.stl", StructureFormat::kStl, 20));
  set.structures.push_back(AddContours("Slab", Box(0, 8, 20, 28, {0, 2, 4, 6, 8}), 30));
  // Drawn on one plate: one voxel layer (centres on the outline excluded).
  set.structures.push_back(AddContours("Sheet", Box(40, 46, 0, 6, {3}), 40));
  ComposedAtlas atlas;
  const Status s = Compose(set, &atlas, 1.0);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_TRUE(atlas.volume.has_value());
  EXPECT_FALSE(atlas.plates.has_value());
  EXPECT_TRUE(atlas.notes.empty());
  const std::vector<int64_t> counts = CountLabels(*atlas.volume);
  const uint16_t cube = atlas.colours.FindByName("Cube")->label;
  const uint16_t box = atlas.colours.FindByName("Mask")->label;
  const uint16_t slab = atlas.colours.FindByName("Slab")->label;
  EXPECT_EQ(cube, 1);
  // Within a layer of voxels (1 mm times half the surface area) of the
  // analytic volumes.
  EXPECT_NEAR(counts[box], 480, 0.5 * 2 * (80 + 60 + 48)) << counts[box];
  EXPECT_NEAR(counts[cube], 1000, 0.5 * 600) << counts[cube];
  // The slab is 8 mm between its end plates, and the loft runs on to a
  // point half a plate spacing beyond each.
  EXPECT_GT(counts[slab], 64 * 8 - 0.5 * (2 * 64 + 4 * 8 * 8));
  EXPECT_LT(counts[slab], 64 * 10 + 0.5 * (2 * 64 + 4 * 8 * 10));
  EXPECT_EQ(counts[atlas.colours.FindByName("Sheet")->label], 5 * 5);
}

// Voxel size 0: masks on a 0.7 mm grid are taken at their own voxels,
// voxel for voxel, not resampled (a snapshot of an imported label volume).
TEST_F(StructureSetTest, MasksComposeAtTheirOwnVoxelsWhenNoSizeIsGiven) {
  const double h = 0.7;
  LabelVolume a({10, 9, 8}, Eigen::Vector3d(2.1, -1.4, 0.7), Eigen::Vector3d::Constant(h));
  LabelVolume b = a;
  int64_t in_a = 0, in_b = 0;
  for (int k = 1; k < 7; ++k) {
    for (int j = 1; j < 8; ++j) {
      for (int i = 1; i < 9; ++i) {
        const bool left = i < 4 || (i == 4 && j % 2 == 0);  // a ragged boundary
        (left ? a : b).set(i, j, k, 1);
        ++(left ? in_a : in_b);
      }
    }
  }
  ASSERT_TRUE(WriteNifti(a, dir_ / "a.nii.gz").ok());
  ASSERT_TRUE(WriteNifti(b, dir_ / "b.nii.gz").ok());
  StructureSet set;
  set.structures.push_back(Entry("A", "a.nii.gz", StructureFormat::kNifti, 10));
  set.structures.push_back(Entry("B", "b.nii.gz", StructureFormat::kNifti, 20));
  ComposedAtlas atlas;
  const Status s = Compose(set, &atlas, 0);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_TRUE(atlas.volume.has_value());
  EXPECT_NEAR(atlas.volume->spacing_mm().x(), h, 1e-6);
  const std::vector<int64_t> counts = CountLabels(*atlas.volume);
  EXPECT_EQ(counts[atlas.colours.FindByName("A")->label], in_a);
  EXPECT_EQ(counts[atlas.colours.FindByName("B")->label], in_b);
}

TEST_F(StructureSetTest, VolumeOverlapsAreReportedInCubicMillimetres) {
  WriteText(dir_ / "one.stl", StlCube(Eigen::Vector3d(0, 0, 0), 10));
  WriteText(dir_ / "two.stl", StlCube(Eigen::Vector3d(5, 0, 0), 10));
  StructureSet set;
  set.structures.push_back(Entry("Two", "two.stl", StructureFormat::kStl, 20));
  set.structures.push_back(Entry("One", "one.stl", StructureFormat::kStl, 10));
  ComposedAtlas atlas;
  const Status s = Compose(set, &atlas, 1.0);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(atlas.notes.size(), 1u);
  EXPECT_NE(atlas.notes[0].find("One and Two overlap on 500 voxels (500 mm^3)"), std::string::npos)
      << atlas.notes[0];
  const std::vector<int64_t> counts = CountLabels(*atlas.volume);
  EXPECT_EQ(counts[1], 1000);
  EXPECT_EQ(counts[2], 500);
}

// BuildAtlas meshes a structure set: from contours through the plates path
// (with the geometric validation), from surfaces through a label volume.
TEST_F(StructureSetTest, BuildAtlasMeshesAStructureSet) {
  StructureSet set;
  const std::vector<double> z = {0, 3, 6, 9, 12};
  set.structures.push_back(AddContours("Left", Box(-12, 0, -6, 6, z), 10));
  set.structures.push_back(AddContours("Right", Box(0, 12, -6, 6, z), 20));
  ASSERT_TRUE(WriteStructureSet(set, dir_).ok());
  AtlasBuildOptions options;
  options.source = AtlasBuildOptions::Source::kStructures;
  options.input = dir_;
  options.cell_size_mm = options.facet_size_mm = 3;
  options.facets_per_section = 0;
  options.odt_iterations = 0;
  AtlasBuildResult result;
  Status s = BuildAtlas(options, &result);
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_TRUE(result.plates.has_value());
  EXPECT_TRUE(result.validation.has_value());
  EXPECT_EQ(result.region_labels, (std::vector<uint16_t>{1, 2}));
  std::vector<int> per_region(result.mesh.region_names.size());
  for (int r : result.mesh.element_region) ++per_region[r];
  ASSERT_EQ(per_region.size(), 2u);
  EXPECT_GT(per_region[0], 20);
  EXPECT_GT(per_region[1], 20);

  // The same two boxes as closed surfaces.
  const fs::path surfaces = dir_ / "surfaces";
  fs::create_directories(surfaces);
  WriteText(surfaces / "left.stl", StlCube(Eigen::Vector3d(-12, -6, 0), 12));
  WriteText(surfaces / "right.stl", StlCube(Eigen::Vector3d(0, -6, 0), 12));
  StructureSet cubes;
  cubes.structures.push_back(Entry("Left", "left.stl", StructureFormat::kStl, 10));
  cubes.structures.push_back(Entry("Right", "right.stl", StructureFormat::kStl, 20));
  ASSERT_TRUE(WriteStructureSet(cubes, surfaces).ok());
  options.input = surfaces;
  s = BuildAtlas(options, &result);
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_FALSE(result.plates.has_value());
  EXPECT_EQ(result.region_labels, (std::vector<uint16_t>{1, 2}));
  EXPECT_EQ(result.colours.FindByLabel(2)->name, "Right");
  EXPECT_TRUE(result.notes.empty());
}

// MeasureOverlap: two cubes 10 mm on a side, half of one inside the other;
// voxel centres lie on whole millimetres, the cubes' faces between them.
TEST_F(StructureSetTest, MeasureOverlapOfTwoCubesSharingHalfTheirVolume) {
  WriteText(dir_ / "a.stl", StlCube({0.25, 0.25, 0.25}, 10));
  WriteText(dir_ / "b.stl", StlCube({5.25, 0.25, 0.25}, 10));
  WriteText(dir_ / "c.stl", StlCube({30.25, 0.25, 0.25}, 10));
  OverlapMeasure m;
  ASSERT_TRUE(MeasureOverlap({StructureFormat::kStl, dir_ / "a.stl"},
                             {StructureFormat::kStl, dir_ / "b.stl"}, 1, &m)
                  .ok());
  EXPECT_DOUBLE_EQ(m.a_mm3, 1000);
  EXPECT_DOUBLE_EQ(m.b_mm3, 1000);
  EXPECT_DOUBLE_EQ(m.overlap_mm3, 500);
  EXPECT_DOUBLE_EQ(m.fraction_of_smaller(), 0.5);
  ASSERT_TRUE(MeasureOverlap({StructureFormat::kStl, dir_ / "a.stl"},
                             {StructureFormat::kStl, dir_ / "c.stl"}, 1, &m)
                  .ok());
  EXPECT_DOUBLE_EQ(m.overlap_mm3, 0);
  // The files are read, not moved.
  EXPECT_TRUE(fs::exists(dir_ / "a.stl"));
  // Contours too: a square drawn on two plates 4 mm apart against the cube.
  Contours square;
  for (double z : {2.0, 6.0}) {
    ContourPlate plate;
    plate.z_mm = z;
    plate.polygons = {{{-4.75, 0.25}, {4.75, 0.25}, {4.75, 9.75}, {-4.75, 9.75}}};
    square.plates.push_back(plate);
  }
  WriteText(dir_ / "square.json", FormatContoursJson(square));
  ASSERT_TRUE(MeasureOverlap({StructureFormat::kContours, dir_ / "square.json"},
                             {StructureFormat::kStl, dir_ / "a.stl"}, 1, &m)
                  .ok());
  // Columns x = 1..4 (4), y = 1..9 (9) inside both; the loft runs 2 mm
  // beyond each end plate, so z = 1..8 (the cube's 1..10 holds them).
  EXPECT_GT(m.overlap_mm3, 0);
  EXPECT_LE(m.overlap_mm3, 4 * 9 * 8);
  EXPECT_LT(m.overlap_mm3, m.a_mm3);
  // A file that is not its format is named.
  WriteText(dir_ / "bad.stl", "solid nothing\nendsolid\n");
  EXPECT_FALSE(MeasureOverlap({StructureFormat::kStl, dir_ / "bad.stl"},
                              {StructureFormat::kStl, dir_ / "a.stl"}, 1, &m)
                   .ok());
}

// CompareShapes: the same two cubes, now as two revisions of a structure.
TEST_F(StructureSetTest, CompareShapesOfTwoCubes) {
  WriteText(dir_ / "a.stl", StlCube({0.25, 0.25, 0.25}, 10));
  WriteText(dir_ / "b.stl", StlCube({5.25, 0.25, 0.25}, 10));
  ShapeComparison c;
  ASSERT_TRUE(CompareShapes({StructureFormat::kStl, dir_ / "a.stl"},
                            {StructureFormat::kStl, dir_ / "b.stl"}, 1, &c)
                  .ok());
  EXPECT_DOUBLE_EQ(c.overlap.a_mm3, 1000);
  EXPECT_DOUBLE_EQ(c.overlap.b_mm3, 1000);
  EXPECT_DOUBLE_EQ(c.overlap.overlap_mm3, 500);
  EXPECT_DOUBLE_EQ(c.dice, 0.5);
  // The x = 1 face of one lies 5 voxels from the nearest boundary of the
  // other (its x = 6 face); nothing lies farther.
  EXPECT_DOUBLE_EQ(c.hausdorff_mm, 5);
  EXPECT_GT(c.mean_surface_distance_mm, 0);
  EXPECT_LT(c.mean_surface_distance_mm, 5);
  // A shape against itself.
  ASSERT_TRUE(CompareShapes({StructureFormat::kStl, dir_ / "a.stl"},
                            {StructureFormat::kStl, dir_ / "a.stl"}, 1, &c)
                  .ok());
  EXPECT_DOUBLE_EQ(c.dice, 1);
  EXPECT_DOUBLE_EQ(c.hausdorff_mm, 0);
}

}  // namespace
}  // namespace pba
