// Label algebra (atlas/label_algebra.h) on small volumes whose answers are
// counted independently: a hollow shell's cavity filled voxel for voxel, an
// opening sealed by a closing, a sphere cut exactly, a second atlas laid on
// a coarser grid, a majority resample that keeps a block's volume and loses
// a one-voxel sheet with a note; every bad step refused naming it, the atlas
// left as it was.
#include "atlas/label_algebra.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>

#include "atlas/distance_transform.h"
#include "atlas/label_volume_io.h"
#include "common/subprocess.h"

namespace pba {
namespace {

namespace fs = std::filesystem;

// An n^3 atlas of 1 mm voxels centred at 0..n-1 whose structures are
// "A", "B", ... with labels 1, 2, ...
LabelAtlas MakeAtlas(int n, int structures) {
  LabelAtlas atlas;
  atlas.volume = LabelVolume({n, n, n}, Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  std::vector<ColourEntry> entries;
  for (int s = 1; s <= structures; ++s) {
    entries.push_back({static_cast<uint16_t>(s), std::string(1, char('A' + s - 1)),
                       static_cast<uint8_t>(40 * s), 10, 10});
  }
  EXPECT_TRUE(ColourTable::FromEntries(entries, &atlas.table).ok());
  return atlas;
}

template <typename F>
void Paint(LabelVolume* v, uint16_t label, F inside) {
  for (int k = 0; k < v->nz(); ++k) {
    for (int j = 0; j < v->ny(); ++j) {
      for (int i = 0; i < v->nx(); ++i) {
        if (inside(Eigen::Vector3d(i, j, k))) v->set(i, j, k, label);
      }
    }
  }
}

int64_t Count(const LabelAtlas& atlas, const std::string& name) {
  const ColourEntry* e = atlas.table.FindByName(name);
  if (e == nullptr) return -1;
  int64_t n = 0;
  for (uint16_t l : atlas.volume.labels()) n += l == e->label;
  return n;
}

LabelStep Fill(const std::string& name, double closing_mm = 0) {
  LabelStep step;
  step.kind = LabelStep::Kind::kFill;
  step.name = name;
  step.closing_mm = closing_mm;
  return step;
}

// A shell of A between radii 6 and `outer` voxels around voxel (12, 12, 12)
// of a 25^3 grid.
LabelAtlas Shell(double outer = 8) {
  LabelAtlas atlas = MakeAtlas(25, 1);
  const Eigen::Vector3d c(12, 12, 12);
  Paint(&atlas.volume, 1, [&](const Eigen::Vector3d& p) {
    const double r = (p - c).norm();
    return r >= 6 && r <= outer;
  });
  return atlas;
}

TEST(LabelAlgebraTest, FillTakesExactlyTheCavityOfAClosedShell) {
  LabelAtlas atlas = Shell();
  int64_t cavity = 0;
  Paint(&atlas.volume, 0, [&](const Eigen::Vector3d& p) {
    cavity += (p - Eigen::Vector3d(12, 12, 12)).norm() < 6;
    return false;
  });
  const int64_t shell = Count(atlas, "A");
  std::vector<std::string> notes;
  ASSERT_TRUE(ApplyLabelSteps({Fill("Core")}, &atlas, &notes).ok());
  EXPECT_EQ(Count(atlas, "Core"), cavity);
  EXPECT_EQ(Count(atlas, "A"), shell);
  EXPECT_EQ(atlas.table.FindByName("Core")->label, 2);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("labels[0] fill: \"Core\" (label 2) fills " + std::to_string(cavity) +
                          " voxels"),
            std::string::npos)
      << notes[0];
}

TEST(LabelAlgebraTest, AnOpenShellNeedsAClosingAndTheClosingSealsOnlyTheOpening) {
  // A wall 5 voxels thick with a 3 x 3 voxel channel through it along +x.
  LabelAtlas atlas = Shell(11);
  const Eigen::Vector3d c(12, 12, 12);
  int64_t cavity = 0, channel = 0;
  Paint(&atlas.volume, 0, [&](const Eigen::Vector3d& p) {
    const double r = (p - c).norm();
    cavity += r < 6;
    const bool hole = p.x() > 12 && std::abs(p.y() - 12) <= 1 && std::abs(p.z() - 12) <= 1;
    channel += hole && r >= 6 && r <= 11;
    return hole;
  });
  const LabelAtlas before = atlas;
  std::vector<std::string> notes;
  Status s = ApplyLabelSteps({Fill("Core")}, &atlas, &notes);
  EXPECT_EQ(s.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(s.field(), "labels[0]");
  EXPECT_NE(s.message().find("encloses no background"), std::string::npos) << s.message();
  EXPECT_EQ(atlas.volume.labels(), before.volume.labels());
  EXPECT_TRUE(notes.empty());

  ASSERT_TRUE(ApplyLabelSteps({Fill("Core", 3)}, &atlas, &notes).ok());
  const int64_t filled = Count(atlas, "Core");
  // The cavity, and of the channel at least its middle, sealed.
  EXPECT_GE(filled, cavity + 9) << notes[0];
  EXPECT_LE(filled, cavity + channel) << notes[0];
  // Nothing outside the shell.
  for (int k = 0; k < 25; ++k) {
    for (int j = 0; j < 25; ++j) {
      for (int i = 0; i < 25; ++i) {
        if ((Eigen::Vector3d(i, j, k) - c).norm() > 11) {
          ASSERT_EQ(atlas.volume.at(i, j, k), 0) << i << " " << j << " " << k;
        }
      }
    }
  }
}

TEST(LabelAlgebraTest, FillKeepsTheLargestPieceAndThoseAboveTheSmallestSize) {
  LabelAtlas atlas = MakeAtlas(30, 1);
  // Two hollow boxes: cavities of 6^3 = 216 and 2^3 = 8 voxels.
  Paint(&atlas.volume, 1, [](const Eigen::Vector3d& p) {
    const bool big = p.minCoeff() >= 1 && p.maxCoeff() <= 8;
    const bool small =
        p.x() >= 20 && p.x() <= 23 && p.y() >= 1 && p.y() <= 4 && p.z() >= 1 && p.z() <= 4;
    return big || small;
  });
  Paint(&atlas.volume, 0, [](const Eigen::Vector3d& p) {
    const bool big = p.minCoeff() >= 2 && p.maxCoeff() <= 7;
    const bool small =
        p.x() >= 21 && p.x() <= 22 && p.y() >= 2 && p.y() <= 3 && p.z() >= 2 && p.z() <= 3;
    return big || small;
  });
  LabelStep step = Fill("Core");
  step.min_piece_mm3 = 100;
  LabelAtlas one = atlas;
  std::vector<std::string> notes;
  ASSERT_TRUE(ApplyLabelSteps({step}, &one, &notes).ok());
  EXPECT_EQ(Count(one, "Core"), 216);
  EXPECT_NE(notes[0].find("1 smaller enclosed piece (8 voxels"), std::string::npos) << notes[0];
  step.min_piece_mm3 = 5;
  ASSERT_TRUE(ApplyLabelSteps({step}, &atlas, &notes).ok());
  EXPECT_EQ(Count(atlas, "Core"), 224);
}

// Three slabs along x: A (x < 5), B (5..9), C (10..14) on 15^3 voxels.
LabelAtlas Slabs() {
  LabelAtlas atlas = MakeAtlas(15, 3);
  Paint(&atlas.volume, 1, [](const Eigen::Vector3d& p) { return p.x() < 5; });
  Paint(&atlas.volume, 2, [](const Eigen::Vector3d& p) { return p.x() >= 5 && p.x() < 10; });
  Paint(&atlas.volume, 3, [](const Eigen::Vector3d& p) { return p.x() >= 10; });
  return atlas;
}

TEST(LabelAlgebraTest, MergeKeepDropAndRename) {
  LabelAtlas atlas = Slabs();
  std::vector<LabelStep> steps(3);
  steps[0].kind = LabelStep::Kind::kMerge;
  steps[0].structures = {"C", "B"};
  steps[0].name = "BC";
  steps[1].kind = LabelStep::Kind::kRename;
  steps[1].from = "A";
  steps[1].name = "Alpha";
  steps[2].kind = LabelStep::Kind::kDrop;
  steps[2].structures = {"Alpha"};
  std::vector<std::string> notes;
  ASSERT_TRUE(ApplyLabelSteps(steps, &atlas, &notes).ok());
  ASSERT_EQ(atlas.table.size(), 1);
  EXPECT_EQ(atlas.table.entries()[0].label, 2);  // the lowest of the merged
  EXPECT_EQ(Count(atlas, "BC"), 10 * 15 * 15);
  EXPECT_EQ(atlas.volume.at(2, 3, 4), 0);
  ASSERT_EQ(notes.size(), 3u);
  EXPECT_NE(notes[0].find("\"BC\" (label 2) is the union of 2 structures: B, C"), std::string::npos)
      << notes[0];

  atlas = Slabs();
  LabelStep keep;
  keep.kind = LabelStep::Kind::kKeep;
  keep.structures = {"B"};
  ASSERT_TRUE(ApplyLabelSteps({keep}, &atlas, &notes).ok());
  EXPECT_EQ(atlas.table.size(), 1);
  EXPECT_EQ(Count(atlas, "B"), 5 * 15 * 15);
  int64_t background = 0;
  for (uint16_t l : atlas.volume.labels()) background += l == 0;
  EXPECT_EQ(background, 10 * 15 * 15);
}

TEST(LabelAlgebraTest, ABadStepIsRefusedNamingItAndNothingChanges) {
  const LabelAtlas original = Slabs();
  const auto refused = [&](std::vector<LabelStep> steps, const std::string& field,
                           const std::string& part) {
    LabelAtlas atlas = original;
    std::vector<std::string> notes;
    const Status s = ApplyLabelSteps(steps, &atlas, &notes);
    EXPECT_EQ(s.code(), Status::Code::kInvalidArgument) << field;
    EXPECT_EQ(s.field(), field);
    EXPECT_NE(s.message().find(part), std::string::npos) << s.ToString();
    EXPECT_EQ(atlas.volume.labels(), original.volume.labels());
    EXPECT_EQ(atlas.table.size(), original.table.size());
    EXPECT_TRUE(notes.empty());
  };
  LabelStep merge;
  merge.kind = LabelStep::Kind::kMerge;
  merge.structures = {"A", "B"};
  merge.name = "AB";
  LabelStep keep;
  keep.kind = LabelStep::Kind::kKeep;
  keep.structures = {"Nope"};
  // The first step was good: the second's failure undoes it.
  refused({merge, keep}, "labels[1]", "(keep) no structure \"Nope\"");
  merge.name = "C";  // C is not merged
  refused({merge}, "labels[0].name", "already has a structure \"C\" outside the merge");
  LabelStep rename;
  rename.kind = LabelStep::Kind::kRename;
  rename.from = "A";
  rename.name = "B";
  refused({rename}, "labels[0].to", "already has a structure \"B\"");
  LabelStep fill = Fill("A");
  refused({fill}, "labels[0].name", "already has a structure \"A\"");
  LabelStep cut;
  cut.kind = LabelStep::Kind::kCut;
  cut.region.centre_mm = {100, 100, 100};
  cut.region.radius_mm = 3;
  refused({cut}, "labels[0]", "holds no voxel");
  cut.region.radius_mm = -1;
  refused({cut}, "labels[0].sphere.radius_mm", "must be positive");
  LabelStep resample;
  resample.kind = LabelStep::Kind::kResample;
  resample.voxel_mm = 0.01;
  refused({resample}, "labels[0].voxel_mm", "over the");
}

TEST(LabelAlgebraTest, CutsTakeExactlyTheirRegionFromTheStructuresNamed) {
  LabelAtlas atlas = Slabs();
  LabelStep cut;
  cut.kind = LabelStep::Kind::kCut;
  cut.region.centre_mm = {7, 7, 7};
  cut.region.radius_mm = 4.5;
  cut.name = "Cavity";
  int64_t in_sphere = 0, in_b = 0;
  Paint(&atlas.volume, 0, [&](const Eigen::Vector3d& p) {
    const bool in = (p - Eigen::Vector3d(7, 7, 7)).norm() <= 4.5;
    in_sphere += in;
    in_b += in && p.x() >= 5 && p.x() < 10;
    return false;
  });
  LabelAtlas all = atlas;
  std::vector<std::string> notes;
  ASSERT_TRUE(ApplyLabelSteps({cut}, &all, &notes).ok());
  EXPECT_EQ(Count(all, "Cavity"), in_sphere);
  EXPECT_NE(notes[0].find("cut " + std::to_string(in_sphere) + " voxels"), std::string::npos);
  cut.structures = {"B"};
  cut.name.clear();
  LabelAtlas only_b = atlas;
  ASSERT_TRUE(ApplyLabelSteps({cut}, &only_b, &notes).ok());
  EXPECT_EQ(Count(only_b, "B"), 5 * 15 * 15 - in_b);
  EXPECT_EQ(Count(only_b, "A"), Count(atlas, "A"));

  // A cylinder along z through (7, 7), radius 2, from z = 3 to 11.
  cut = LabelStep();
  cut.kind = LabelStep::Kind::kCut;
  cut.region.kind = LabelRegion::Kind::kCylinder;
  cut.region.centre_mm = {7, 7, 3};
  cut.region.end_mm = {7, 7, 11};
  cut.region.radius_mm = 2;
  LabelAtlas cylinder = atlas;
  ASSERT_TRUE(ApplyLabelSteps({cut}, &cylinder, &notes).ok());
  int64_t background = 0;
  for (uint16_t l : cylinder.volume.labels()) background += l == 0;
  EXPECT_EQ(background, 13 * 9);  // 13 voxel centres within 2 of the axis, 9 layers

  // Around B by 1.5 mm: the layer of A and of C next to it, B itself kept.
  cut = LabelStep();
  cut.kind = LabelStep::Kind::kCut;
  cut.region.kind = LabelRegion::Kind::kStructures;
  cut.region.structures = {"B"};
  cut.region.margin_mm = 1.5;
  LabelAtlas around = atlas;
  ASSERT_TRUE(ApplyLabelSteps({cut}, &around, &notes).ok());
  EXPECT_EQ(Count(around, "B"), 5 * 15 * 15);
  EXPECT_EQ(Count(around, "A"), 4 * 15 * 15);
  EXPECT_EQ(Count(around, "C"), 4 * 15 * 15);
}

TEST(LabelAlgebraTest, ASecondAtlasIsLaidOverOrUnderOnItsOwnGrid) {
  pba::testing::TempDir dir;
  // The second atlas: 2 mm voxels over the same 15 mm box, "T" in its
  // voxels 1..2 (centres 1.75 and 3.75 mm: the first atlas's 1..4).
  LabelAtlas top;
  top.volume =
      LabelVolume({8, 8, 8}, Eigen::Vector3d::Constant(-0.25), Eigen::Vector3d::Constant(2));
  for (int k = 1; k <= 2; ++k) {
    for (int j = 1; j <= 2; ++j) {
      for (int i = 1; i <= 2; ++i) top.volume.set(i, j, k, 1);
    }
  }
  ASSERT_TRUE(ColourTable::FromEntries({{1, "T", 1, 2, 3}}, &top.table).ok());
  ASSERT_TRUE(WriteNifti(top.volume, dir.path() / "top.nii.gz").ok());
  ASSERT_TRUE(WriteColourTableCsv(top.table, dir.path() / "top.csv").ok());

  LabelAtlas base = Slabs();
  Paint(&base.volume, 0, [](const Eigen::Vector3d& p) { return p.y() < 3; });  // background
  LabelStep over;
  over.kind = LabelStep::Kind::kOverlay;
  over.volume = dir.path() / "top.nii.gz";
  over.table = dir.path() / "top.csv";
  LabelAtlas laid = base;
  std::vector<std::string> notes;
  ASSERT_TRUE(ApplyLabelSteps({over}, &laid, &notes).ok());
  EXPECT_EQ(laid.table.FindByName("T")->label, 4);  // 1 is A's
  EXPECT_EQ(Count(laid, "T"), 4 * 4 * 4);
  EXPECT_EQ(Count(laid, "A"), Count(base, "A") - 4 * 2 * 4);  // y = 3, 4 were A's

  over.under = true;
  LabelAtlas under = base;
  ASSERT_TRUE(ApplyLabelSteps({over}, &under, &notes).ok());
  EXPECT_EQ(Count(under, "T"), 4 * 2 * 4);  // only y = 1, 2: background there
  EXPECT_EQ(Count(under, "A"), Count(base, "A"));

  // The same name in both atlases is refused.
  ASSERT_TRUE(ColourTable::FromEntries({{1, "B", 1, 2, 3}}, &top.table).ok());
  ASSERT_TRUE(WriteColourTableCsv(top.table, dir.path() / "top.csv").ok());
  LabelAtlas clash = base;
  const Status s = ApplyLabelSteps({over}, &clash, &notes);
  EXPECT_EQ(s.field(), "labels[0].structures");
  EXPECT_NE(s.message().find("both atlases have a structure \"B\""), std::string::npos);
  // A second atlas whose table misses one of its labels is refused.
  top.volume.set(5, 5, 5, 9);
  ASSERT_TRUE(WriteNifti(top.volume, dir.path() / "top.nii.gz").ok());
  const Status missing = ApplyLabelSteps({over}, &clash, &notes);
  EXPECT_EQ(missing.field(), "labels[0].table");
  EXPECT_NE(missing.message().find("label 9 of top.nii.gz (1 voxels) has no entry in top.csv"),
            std::string::npos)
      << missing.message();
}

TEST(LabelAlgebraTest, MajorityResampleKeepsABlockAndSaysWhatVanished) {
  LabelAtlas atlas = MakeAtlas(16, 2);
  Paint(&atlas.volume, 1,
        [](const Eigen::Vector3d& p) { return p.minCoeff() >= 4 && p.maxCoeff() <= 11; });
  Paint(&atlas.volume, 2, [](const Eigen::Vector3d& p) { return p.x() == 14; });  // a sheet
  LabelStep step;
  step.kind = LabelStep::Kind::kResample;
  step.voxel_mm = 2;
  std::vector<std::string> notes;
  ASSERT_TRUE(ApplyLabelSteps({step}, &atlas, &notes).ok());
  EXPECT_EQ(atlas.volume.dims(), (std::array<int, 3>{8, 8, 8}));
  EXPECT_TRUE(atlas.volume.origin_mm().isApprox(Eigen::Vector3d::Constant(0.5)));
  EXPECT_EQ(Count(atlas, "A"), 4 * 4 * 4);  // 512 mm^3 as before
  EXPECT_EQ(Count(atlas, "B"), 0);
  EXPECT_NE(notes[0].find("1 structure thinner than the new voxels vanished: B"), std::string::npos)
      << notes[0];
}

// Pieces joined by no face (an island apart, a cube on an edge) go; a
// piece joined by a face stays; the largest always stays.
TEST(LabelAlgebraTest, IslandsUnderTheSizeBecomeBackground) {
  LabelAtlas atlas = MakeAtlas(20, 3);
  Paint(&atlas.volume, 1, [](const Eigen::Vector3d& p) { return p.maxCoeff() <= 9; });  // 1000
  Paint(&atlas.volume, 2, [](const Eigen::Vector3d& p) {  // 8, on an edge of A
    return p.x() >= 10 && p.x() <= 11 && p.y() >= 10 && p.y() <= 11 && p.z() <= 1;
  });
  Paint(&atlas.volume, 3, [](const Eigen::Vector3d& p) {  // 27, apart
    return p.minCoeff() >= 15 && p.maxCoeff() <= 17;
  });
  atlas.volume.set(10, 0, 0, 3);  // C also has a voxel on a face of A: it stays
  const LabelAtlas before = atlas;
  LabelStep step;
  step.kind = LabelStep::Kind::kIslands;
  step.min_piece_mm3 = 20;
  std::vector<std::string> notes;
  ASSERT_TRUE(ApplyLabelSteps({step}, &atlas, &notes).ok());
  EXPECT_EQ(Count(atlas, "A"), 1000);
  EXPECT_EQ(Count(atlas, "B"), 0);
  EXPECT_EQ(Count(atlas, "C"), 28);
  EXPECT_NE(notes[0].find("1 island of the atlas"), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("2 pieces kept, the largest 1001 voxels"), std::string::npos) << notes[0];
  // The automatic form, relative to the largest piece: 2 % keeps C's 27, 3 % does not.
  atlas = before;
  std::string note;
  ASSERT_TRUE(DropIslands(0.02, &atlas, &note));
  EXPECT_EQ(Count(atlas, "B"), 0);
  EXPECT_EQ(Count(atlas, "C"), 28);
  atlas = before;
  ASSERT_TRUE(DropIslands(0.03, &atlas, &note));
  EXPECT_EQ(Count(atlas, "C"), 1);
  LabelAtlas whole = MakeAtlas(5, 1);
  Paint(&whole.volume, 1, [](const Eigen::Vector3d&) { return true; });
  EXPECT_FALSE(DropIslands(0.5, &whole, &note));
}

TEST(LabelAlgebraTest, StepsReadFromYaml) {
  const std::string yaml = R"(
- fill: {name: White matter, closing_mm: 7}
- overlay: {volume: jhu.nii.gz, table: /abs/jhu.txt, structures: [Fornix], under: true}
- merge: {structures: [Caudate_L, Caudate_R], name: Caudate}
- rename: {from: Caudate, to: Caudate nucleus}
- keep: [A, B]
- drop: C
- resample: {voxel_mm: 2}
- cut: {sphere: {centre_mm: [1, 2, 3], radius_mm: 10}, name: Cavity}
- cut: {cylinder: {from_mm: [0, 0, 0], to_mm: [0, 0, 9], radius_mm: 2}, structures: [A]}
- cut: {mask: m.nii.gz}
- cut: {around: {structures: [T], margin_mm: 2}}
- islands: {min_piece_mm3: 50}
- keep: {structures: [A]}
)";
  std::vector<LabelStep> steps;
  ASSERT_TRUE(ParseLabelSteps(yaml, "steps", "/base", &steps).ok());
  ASSERT_EQ(steps.size(), 13u);
  EXPECT_EQ(steps[11].kind, LabelStep::Kind::kIslands);
  EXPECT_EQ(steps[11].min_piece_mm3, 50);
  EXPECT_EQ(steps[12].structures, std::vector<std::string>{"A"});
  EXPECT_EQ(steps[0].kind, LabelStep::Kind::kFill);
  EXPECT_EQ(steps[0].name, "White matter");
  EXPECT_EQ(steps[0].closing_mm, 7);
  EXPECT_EQ(steps[1].volume, fs::path("/base/jhu.nii.gz"));
  EXPECT_EQ(steps[1].table, fs::path("/abs/jhu.txt"));
  EXPECT_TRUE(steps[1].under);
  EXPECT_EQ(steps[3].from, "Caudate");
  EXPECT_EQ(steps[5].structures, std::vector<std::string>{"C"});
  EXPECT_EQ(steps[7].region.kind, LabelRegion::Kind::kSphere);
  EXPECT_EQ(steps[7].region.centre_mm, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(steps[8].region.kind, LabelRegion::Kind::kCylinder);
  EXPECT_EQ(steps[9].region.mask, fs::path("/base/m.nii.gz"));
  EXPECT_EQ(steps[10].region.margin_mm, 2);
  ASSERT_EQ(LabelStepFiles(steps).size(), 3u);  // the overlay's volume and table, the mask
  std::vector<LabelStep> other = steps;
  other[7].region.radius_mm = 10.000001;
  EXPECT_NE(DescribeLabelSteps(steps), DescribeLabelSteps(other));

  const auto refused = [](const std::string& text, const std::string& field,
                          const std::string& part) {
    std::vector<LabelStep> out;
    const Status s = ParseLabelSteps(text, "steps", "/", &out);
    EXPECT_EQ(s.field(), field) << text;
    EXPECT_NE(s.message().find(part), std::string::npos) << s.ToString();
  };
  refused("- fil: {name: X}", "steps[0].fil", "unknown step");
  refused("- fill: {name: X, closing: 3}", "steps[0].fill.closing", "unknown key");
  refused("- merge: {structures: [A]}", "steps[0].merge.name", "is required");
  refused("- cut: {name: X}", "steps[0].cut", "exactly one region");
  refused("- cut: {sphere: {centre_mm: [1, 2], radius_mm: 1}}", "steps[0].cut.sphere.centre_mm",
          "[x, y, z]");
  refused("- resample: {voxel_mm: \"2\"}", "steps[0].resample.voxel_mm", "a number");
  refused("- resample: {voxel_mm: 0}", "steps[0].resample.voxel_mm", "must be positive");
  refused("- islands: {min_piece_mm3: -1}", "steps[0].islands.min_piece_mm3", ">= 0");
  refused("- cut: {cylinder: {from_mm: [0, 0, 0], to_mm: [0, 0, 9], radius_mm: -2}}",
          "steps[0].cut.cylinder.radius_mm", "must be positive");
  refused("fill: {name: X}", "steps", "a list of steps");
  refused("- &a {keep: [A]}\n- *a", "steps", "alias");
}

TEST(LabelAlgebraTest, AnisotropicDistanceTransformMatchesBruteForce) {
  const int nx = 7, ny = 5, nz = 6;
  const double h[3] = {1.0, 2.0, 0.5};
  std::mt19937 random(7);
  std::vector<uint8_t> feature(nx * ny * nz, 0);
  for (int n = 0; n < 5; ++n) feature[random() % feature.size()] = 1;
  std::vector<double> d2;
  SquaredDistanceTransform3dMm(feature, nx, ny, nz, h, &d2);
  for (int q = 0; q < nx * ny * nz; ++q) {
    double best = std::numeric_limits<double>::infinity();
    for (int p = 0; p < nx * ny * nz; ++p) {
      if (!feature[p]) continue;
      const double dx = h[0] * (q % nx - p % nx), dy = h[1] * (q / nx % ny - p / nx % ny),
                   dz = h[2] * (q / (nx * ny) - p / (nx * ny));
      best = std::min(best, dx * dx + dy * dy + dz * dz);
    }
    ASSERT_NEAR(d2[q], best, 1e-9) << q;
  }
}

}  // namespace
}  // namespace pba
