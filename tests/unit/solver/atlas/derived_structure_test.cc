// Derived structures: their recipes read (and bad ones refused, naming the
// key), the order they are made in and the checks of what each reads, the
// names label steps leave, and a structure set with derived structures
// composed voxel for voxel.
#include "atlas/derived_structure.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "atlas/contours.h"
#include "atlas/label_volume_io.h"
#include "atlas/structure_set.h"
#include "atlas/structure_split.h"

namespace pba {
namespace {

namespace fs = std::filesystem;

DerivedStructure Parse(const std::string& yaml, const std::string& name = "D") {
  DerivedStructure d;
  const Status s = ParseDerivedStructure(yaml, name, "structures[4]", &d);
  EXPECT_TRUE(s.ok()) << yaml << ": " << s.ToString();
  return d;
}

Status ParseError(const std::string& yaml) {
  DerivedStructure d;
  return ParseDerivedStructure(yaml, "D", "structures[4]", &d);
}

TEST(DerivedStructureTest, RecipesReadInTheirShortAndLongForms) {
  DerivedStructure merge = Parse("merge: [Caudate, Putamen]", "Striatum");
  EXPECT_EQ(merge.step.kind, LabelStep::Kind::kMerge);
  EXPECT_EQ(merge.step.name, "Striatum");
  EXPECT_EQ(merge.name, "Striatum");
  EXPECT_EQ(merge.field, "structures[4]");
  EXPECT_EQ(merge.step.structures, (std::vector<std::string>{"Caudate", "Putamen"}));
  EXPECT_EQ(Parse("{\"merge\": {\"structures\": [\"A\"]}}").step.structures,
            std::vector<std::string>{"A"});

  const DerivedStructure fill = Parse("fill: {closing_mm: 4, min_piece_mm3: 50}");
  EXPECT_EQ(fill.step.kind, LabelStep::Kind::kFill);
  EXPECT_EQ(fill.step.closing_mm, 4);
  EXPECT_EQ(fill.step.min_piece_mm3, 50);
  EXPECT_EQ(Parse("fill:").step.kind, LabelStep::Kind::kFill);
  EXPECT_EQ(Parse("fill: {}").step.name, "D");

  const DerivedStructure cut =
      Parse("cut: {sphere: {centre_mm: [1, 2, 3], radius_mm: 5}, structures: [Cortex]}", "Cavity");
  EXPECT_EQ(cut.step.kind, LabelStep::Kind::kCut);
  EXPECT_EQ(cut.step.name, "Cavity");
  EXPECT_EQ(cut.step.region.kind, LabelRegion::Kind::kSphere);
  EXPECT_EQ(cut.step.region.radius_mm, 5);
  EXPECT_EQ(cut.step.structures, std::vector<std::string>{"Cortex"});
  const DerivedStructure around = Parse("cut: {around: {structures: [Tumour], margin_mm: 3}}");
  EXPECT_EQ(DerivedSources(around.step), std::vector<std::string>{"Tumour"});
}

TEST(DerivedStructureTest, BadRecipesAreRefusedNamingTheKey) {
  const struct {
    std::string yaml, field, words;
  } cases[] = {
      {"keep: [A]", "structures[4].keep", "merge, fill or cut"},
      {"merge: [A]\nfill: {}", "structures[4]", "one step"},
      {"[merge, A]", "structures[4]", "one step"},
      {"merge: {structures: [A], name: B}", "structures[4].merge.name", "own name"},
      {"cut: {mask: cavity.nii.gz}", "structures[4].cut.mask", "no mask file"},
      {"fill: {closing: 4}", "structures[4].fill.closing", "unknown key"},
      {"cut: {structures: [A]}", "structures[4].cut", "exactly one region"},
      {"merge: []", "structures[4].merge.structures", "structure name"},
      {"fill: 3", "structures[4].fill", "expected a map"},
      {"{[a, b]: 1}", "structures[4]", "malformed"},
      {"merge: [A", "structures[4]", "not valid YAML"},
      // Values are checked when the recipe is written, not when it is made.
      {"cut: {sphere: {centre_mm: [0, 0, 0], radius_mm: 0}}", "structures[4].cut.sphere.radius_mm",
       "must be positive"},
      {"cut: {cylinder: {from_mm: [1, 2, 3], to_mm: [1, 2, 3], radius_mm: 2}}",
       "structures[4].cut.cylinder", "one point"},
      {"cut: {around: {structures: [A], margin_mm: -1}}", "structures[4].cut.around.margin_mm",
       "[0, 50]"},
      {"fill: {closing_mm: 60}", "structures[4].fill.closing_mm", "[0, 50]"},
      {"fill: {min_piece_mm3: -5}", "structures[4].fill.min_piece_mm3", ">= 0"},
      {"fill: {closing_mm: .nan}", "structures[4].fill.closing_mm", "a number"},
  };
  for (const auto& c : cases) {
    const Status s = ParseError(c.yaml);
    EXPECT_EQ(s.code(), Status::Code::kInvalidArgument) << c.yaml;
    EXPECT_EQ(s.field(), c.field) << c.yaml << ": " << s.ToString();
    EXPECT_NE(s.message().find(c.words), std::string::npos) << c.yaml << ": " << s.ToString();
  }
}

DerivedStructure Made(const std::string& name, const std::string& yaml) {
  DerivedStructure d = Parse(yaml, name);
  d.field = "structures[" + name + "]";
  return d;
}

TEST(DerivedStructureTest, MergesComeFirstThenFillsThenCutsEachByName) {
  std::vector<DerivedStructure> derived = {
      Made("Cavity", "cut: {around: {structures: [Striatum]}, structures: [White matter]}"),
      Made("White matter", "fill: {}"), Made("Striatum", "merge: [Caudate, Putamen]"),
      Made("Basal ganglia", "merge: [Striatum, Pallidum]"),  // after Striatum? No: by name.
  };
  // "Basal ganglia" sorts before "Striatum", so it cannot read it.
  Status s = OrderDerivedStructures({"Caudate", "Putamen", "Pallidum"}, &derived);
  EXPECT_EQ(s.field(), "structures[Basal ganglia]");
  EXPECT_NE(s.message().find("'Striatum', a derived structure made after it"), std::string::npos)
      << s.ToString();

  derived.pop_back();
  s = OrderDerivedStructures({"Caudate", "Putamen", "Pallidum"}, &derived);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(derived.size(), 3u);
  EXPECT_EQ(derived[0].name, "Striatum");
  EXPECT_EQ(derived[1].name, "White matter");
  EXPECT_EQ(derived[2].name, "Cavity");
}

TEST(DerivedStructureTest, WhatARecipeReadsMustBeThereAtItsTurn) {
  const std::vector<std::string> base = {"Caudate", "Putamen", "Thalamus: VPL", "Thalamus: VPM"};
  const auto refusal = [&](std::vector<DerivedStructure> derived) {
    const Status s = OrderDerivedStructures(base, &derived);
    EXPECT_EQ(s.code(), Status::Code::kInvalidArgument);
    return s.field() + ": " + s.message();
  };
  EXPECT_NE(refusal({Made("D", "merge: [Caudate, Amygdala]")})
                .find("structures[D]: derived structure 'D' reads 'Amygdala', which is not "
                      "among the structures"),
            std::string::npos);
  EXPECT_NE(refusal({Made("Striatum", "merge: [Caudate, Putamen]"),
                     Made("Cavity", "cut: {around: {structures: [Putamen]}}")})
                .find("reads 'Putamen', which the merge 'Striatum' takes before it"),
            std::string::npos);
  // A group merged takes its members.
  EXPECT_NE(refusal({Made("Thalamus whole", "merge: [Thalamus]"),
                     Made("Cut",
                          "cut: {sphere: {centre_mm: [0, 0, 0], radius_mm: 2}, "
                          "structures: ['Thalamus: VPL']}")})
                .find("which the merge 'Thalamus whole' takes before it"),
            std::string::npos);
  EXPECT_NE(refusal({Made("Caudate", "fill: {}")}).find("has the name of another structure"),
            std::string::npos);
  EXPECT_NE(refusal({Made("D", "merge: [D, Caudate]")}).find("reads itself"), std::string::npos);
  // A group of the set is a name it has.
  std::vector<DerivedStructure> ok = {Made("Thalamus whole", "merge: [Thalamus]")};
  EXPECT_TRUE(OrderDerivedStructures(base, &ok).ok());
}

LabelStep Step(LabelStep::Kind kind, std::vector<std::string> structures = {},
               std::string name = "", std::string from = "") {
  LabelStep step;
  step.kind = kind;
  step.structures = std::move(structures);
  step.name = std::move(name);
  step.from = std::move(from);
  return step;
}

TEST(DerivedStructureTest, NamesAfterEachStep) {
  using K = LabelStep::Kind;
  const std::vector<std::string> names = {"A", "B", "G: x", "G: y"};
  EXPECT_EQ(NamesAfterStep(Step(K::kKeep, {"A", "G"}), names),
            (std::vector<std::string>{"A", "G: x", "G: y"}));
  EXPECT_EQ(NamesAfterStep(Step(K::kDrop, {"G: x"}), names),
            (std::vector<std::string>{"A", "B", "G: y"}));
  EXPECT_EQ(NamesAfterStep(Step(K::kMerge, {"G", "B"}, "M"), names),
            (std::vector<std::string>{"A", "M"}));
  EXPECT_EQ(NamesAfterStep(Step(K::kRename, {}, "Z", "A"), names),
            (std::vector<std::string>{"Z", "B", "G: x", "G: y"}));
  EXPECT_EQ(NamesAfterStep(Step(K::kFill, {}, "W"), names).back(), "W");
  // Cut to background: A may keep voxels.
  EXPECT_EQ(NamesAfterStep(Step(K::kCut, {"A"}), names), names);
  EXPECT_EQ(NamesAfterStep(Step(K::kCut, {"A"}, "Cavity"), names).back(), "Cavity");
  EXPECT_EQ(NamesAfterStep(Step(K::kResample), names), names);
}

// ---- composed

class DerivedComposeTest : public testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::path(testing::TempDir()) /
        ("derived_" + std::string(testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A mask of the voxels [lo, hi) (indices) on a 30^3 grid of 1 mm voxels
  // centred on integers.
  void AddBox(const std::string& name, std::array<int, 3> lo, std::array<int, 3> hi, uint8_t r) {
    LabelVolume mask({30, 30, 30}, Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
    for (int k = lo[2]; k < hi[2]; ++k) {
      for (int j = lo[1]; j < hi[1]; ++j) {
        for (int i = lo[0]; i < hi[0]; ++i) mask.set(i, j, k, 1);
      }
    }
    ASSERT_TRUE(WriteNifti(mask, dir_ / (name + ".nii.gz")).ok());
    Add(name, name + ".nii.gz", StructureFormat::kNifti, r);
  }
  void AddDerived(const std::string& name, const std::string& yaml, uint8_t r) {
    std::ofstream(dir_ / (name + ".yaml")) << yaml;
    Add(name, name + ".yaml", StructureFormat::kDerived, r);
  }
  void Add(const std::string& name, const std::string& file, StructureFormat format, uint8_t r) {
    StructureEntry e;
    e.name = name;
    e.file = file;
    e.format = format;
    e.r = r;
    e.g = 7;
    e.b = 9;
    set_.structures.push_back(e);
  }
  Status Compose(ComposedAtlas* atlas) {
    EXPECT_TRUE(WriteStructureSet(set_, dir_).ok());
    StructureSet read;
    PBA_RETURN_IF_ERROR(ReadStructureSet(dir_, &read));
    ComposeOptions options;
    options.voxel_size_mm = 1;
    return ComposeStructureSet(dir_, read, options, atlas);
  }
  int64_t Voxels(const ComposedAtlas& atlas, const std::string& name) {
    const ColourEntry* e = atlas.colours.FindByName(name);
    if (e == nullptr) return -1;
    return CountLabels(*atlas.volume)[e->label];
  }

  fs::path dir_;
  StructureSet set_;
};

// A shell of four walls, a floor and a roof around an empty core, two
// boxes merged, and a sphere cut out of the filled core: every count is
// known voxel for voxel.
TEST_F(DerivedComposeTest, MergeFillAndCutAreMadeOnTheComposedVoxels) {
  AddBox("Floor", {5, 5, 5}, {25, 25, 7}, 10);     // 20 x 20 x 2 = 800
  AddBox("Roof", {5, 5, 23}, {25, 25, 25}, 20);    // 800
  AddBox("Walls", {5, 5, 7}, {25, 7, 23}, 30);     // 20 x 2 x 16 = 640
  AddBox("Walls2", {5, 23, 7}, {25, 25, 23}, 40);  // 640
  AddBox("Side", {5, 7, 7}, {7, 23, 23}, 50);      // 2 x 16 x 16 = 512
  AddBox("Side2", {23, 7, 7}, {25, 23, 23}, 60);   // 512
  AddDerived("Lid", "merge: [Roof, Floor]", 70);
  AddDerived("Core", "fill: {min_piece_mm3: 1}", 80);  // 16 x 16 x 16 = 4096
  // A sphere of radius 3 mm about a voxel centre inside the core: the
  // voxels whose centres are within 3 mm, 123 of them.
  AddDerived("Cavity", "cut: {sphere: {centre_mm: [15, 15, 15], radius_mm: 3}, structures: [Core]}",
             90);
  ComposedAtlas atlas;
  const Status s = Compose(&atlas);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_TRUE(atlas.volume.has_value());
  EXPECT_EQ(Voxels(atlas, "Roof"), -1);  // taken by the merge
  EXPECT_EQ(Voxels(atlas, "Floor"), -1);
  EXPECT_EQ(Voxels(atlas, "Lid"), 1600);
  EXPECT_EQ(Voxels(atlas, "Walls"), 640);
  EXPECT_EQ(Voxels(atlas, "Cavity"), 123);
  EXPECT_EQ(Voxels(atlas, "Core"), 4096 - 123);
  EXPECT_DOUBLE_EQ(atlas.structure_mm3["Lid"], 1600);
  EXPECT_DOUBLE_EQ(atlas.structure_mm3["Cavity"], 123);
  // In the colours the set gives them.
  EXPECT_EQ(atlas.colours.FindByName("Lid")->r, 70);
  EXPECT_EQ(atlas.colours.FindByName("Core")->r, 80);
  EXPECT_EQ(atlas.colours.FindByName("Cavity")->r, 90);
  // One note each, in the order they were made.
  ASSERT_EQ(atlas.notes.size(), 3u);
  EXPECT_EQ(atlas.notes[0].rfind("derived structure 'Lid' (merge): ", 0), 0u) << atlas.notes[0];
  EXPECT_EQ(atlas.notes[1].rfind("derived structure 'Core' (fill): ", 0), 0u) << atlas.notes[1];
  EXPECT_EQ(atlas.notes[2].rfind("derived structure 'Cavity' (cut): ", 0), 0u) << atlas.notes[2];
}

TEST_F(DerivedComposeTest, ARecipeThatCannotBeMadeNamesItsEntry) {
  AddBox("A", {5, 5, 5}, {10, 10, 10}, 10);
  AddDerived("B", "merge: [A, Missing]", 20);
  ComposedAtlas atlas;
  Status s = Compose(&atlas);
  EXPECT_EQ(s.field(), "structures[1]");
  EXPECT_NE(s.message().find("'Missing', which is not among the structures"), std::string::npos)
      << s.ToString();

  // A bad recipe file: the entry and the key.
  set_.structures.pop_back();
  AddDerived("B", "merge: {structures: [A], colour: red}", 20);
  s = Compose(&atlas);
  EXPECT_EQ(s.field(), "structures[1].merge.colour") << s.ToString();

  // A recipe file larger than any YAML PBA reads (64 MiB): refused naming
  // the entry (and read no further than that).
  set_.structures.pop_back();
  AddDerived("B", "merge: [A]\n#" + std::string(64 << 20, 'x') + "\n", 20);
  s = Compose(&atlas);
  EXPECT_EQ(s.field(), "structures[1]") << s.ToString();
  EXPECT_EQ(s.code(), Status::Code::kInvalidArgument) << s.ToString();

  // Nothing but derived structures.
  set_.structures.clear();
  AddDerived("W", "fill: {}", 20);
  s = Compose(&atlas);
  EXPECT_NE(s.message().find("every structure is derived"), std::string::npos) << s.ToString();
}

// Contours alone compose to plates; a derived structure among them makes
// a volume (label algebra is on voxels).
TEST_F(DerivedComposeTest, ADerivedStructureAmongContoursMakesAVolume) {
  for (const auto& [name, x0] : {std::pair{"A", 0.0}, std::pair{"B", 10.0}}) {
    Contours c;
    c.pixel_size_mm = 0.5;
    for (double z : {0.0, 4.0, 8.0}) {
      ContourPlate plate;
      plate.z_mm = z;
      plate.polygons.push_back({{x0, 0}, {x0 + 10, 0}, {x0 + 10, 10}, {x0, 10}});
      c.plates.push_back(plate);
    }
    std::ofstream(dir_ / (std::string(name) + ".json")) << FormatContoursJson(c);
    Add(name, std::string(name) + ".json", StructureFormat::kContours, name[0]);
  }
  AddDerived("AB", "merge: [A, B]", 30);
  ComposedAtlas atlas;
  const Status s = Compose(&atlas);
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_FALSE(atlas.plates.has_value());
  ASSERT_TRUE(atlas.volume.has_value());
  EXPECT_EQ(atlas.colours.size(), 1);
  // 20 x 10 x 8 mm between the end plates, a little more with the loft's
  // ends.
  EXPECT_GT(Voxels(atlas, "AB"), 1400);
  EXPECT_LT(Voxels(atlas, "AB"), 2400);
}

// On a real atlas the derived route is the label-algebra route: AAL split
// into one mask per structure with a derived "White matter" (a fill after
// a 7 mm closing) composes, voxel for voxel, to AAL filled directly.
TEST_F(DerivedComposeTest, AalWithADerivedWhiteMatterIsAalFilled) {
  const fs::path templates = "/usr/share/mricron/templates";
  LabelAtlas direct;
  std::vector<std::string> notes;
  ASSERT_TRUE(ReadLabelAtlas(templates / "aal.nii.gz", templates / "aal.nii.txt", "labels", "table",
                             &direct, &notes)
                  .ok());
  LabelStep fill;
  fill.kind = LabelStep::Kind::kFill;
  fill.name = "White matter";
  fill.closing_mm = 7;
  ASSERT_TRUE(ApplyLabelSteps({fill}, &direct, &notes).ok());

  SplitOptions split;
  split.source.source = AtlasBuildOptions::Source::kLabelVolume;
  split.source.input = templates / "aal.nii.gz";
  split.source.colour_table = templates / "aal.nii.txt";
  SplitResult result;
  ASSERT_TRUE(SplitAtlas(split, dir_, &result).ok());  // dir_ is empty
  set_ = result.set;
  AddDerived("White matter", "fill: {closing_mm: 7}", 1);
  ComposedAtlas composed;
  ASSERT_TRUE(WriteStructureSet(set_, dir_).ok());
  ComposeOptions options;
  options.voxel_size_mm = 0;  // the masks' own voxels, as a snapshot's job has them
  const Status s = ComposeStructureSet(dir_, set_, options, &composed);
  ASSERT_TRUE(s.ok()) << s.ToString();

  // Every structure, the white matter included, has its voxels, on the
  // same lattice (the composed grid is cropped: compare by centre).
  const std::vector<int64_t> counts = CountLabels(direct.volume);
  const std::vector<int64_t> composed_counts = CountLabels(*composed.volume);
  ASSERT_EQ(composed.colours.size(), direct.table.size());
  for (const ColourEntry& e : direct.table.entries()) {
    const ColourEntry* c = composed.colours.FindByName(e.name);
    ASSERT_NE(c, nullptr) << e.name;
    EXPECT_EQ(composed_counts[c->label], counts[e.label]) << e.name;
  }
  EXPECT_GT(counts[direct.table.FindByName("White matter")->label], 300000);
  EXPECT_EQ(composed.colours.FindByName("White matter")->r, 1);
}

}  // namespace
}  // namespace pba
