#include "atlas/geometric_validation.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <set>
#include <sstream>
#include <vector>

#include "atlas/loft.h"
#include "atlas/synthetic_atlas.h"
#include "common/plate_stacks.h"
#include "mesh/primitive_mesher.h"

namespace pba {
namespace {

constexpr double kMm = 1e-3;

// A tetrahedral box of edge `size` [mm], elements of `h` [mm], translated so
// its lowest corner is at `corner` [mm].
Mesh BoxMesh(const Eigen::Vector3d& size, double h, const Eigen::Vector3d& corner) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {size.x(), size.y(), size.z()};
  MeshSpec options;
  options.element = ElementType::kTet4;
  options.element_size_mm = h;
  MeshStats stats;
  Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
  mesh.nodes.rowwise() += (corner * kMm).transpose();
  return mesh;
}

Eigen::Vector3d CentroidMm(const Mesh& mesh, int e) {
  return TetCorners(mesh, e).colwise().mean().transpose() / kMm;
}

// Plates of width x height pixels of `pixel` mm centred on (0, 0), pixel
// (c, r) at (origin.x + c h, origin.y - r h), labelled by paint(x, y, z).
PlateStack MakePlates(double pixel, int width, int height, const std::vector<double>& z_mm,
                      const ColourTable& colours,
                      const std::function<uint16_t(double, double, double)>& paint) {
  PlateStack stack =
      testing::PaintPlateStack(pixel, width, height, z_mm,
                               [&](int, double x, double y, double z) { return paint(x, y, z); });
  stack.colours = colours;
  return stack;
}

const StructureValidation* Find(const GeometricValidation& v, uint16_t label) {
  for (const StructureValidation& s : v.structures) {
    if (s.label == label) return &s;
  }
  return nullptr;
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// The two-structure box: a 40 mm cube centred on the origin, 2 mm
// elements; an element whose centroid lies within 12 mm of the origin is
// structure B (label 2), the rest A (label 1). Plates on a 0.5 mm grid
// (80 x 80 pixels, the cube's extent) at heights between node layers and on
// one (z = 1 and z = 4 are on none, z = -6 and 8 are on one).
class SphereInBoxTest : public ::testing::Test {
 protected:
  static constexpr double kRadius = 12, kPixel = 0.5, kH = 2;
  static constexpr uint16_t kA = 1, kB = 2, kC = 3;

  void SetUp() override {
    mesh_ = BoxMesh(Eigen::Vector3d::Constant(40), kH, Eigen::Vector3d::Constant(-20));
    mesh_.region_names = {"A", "B"};
    mesh_.element_region.resize(mesh_.tets.size());
    for (int e = 0; e < mesh_.num_elements(); ++e) {
      mesh_.element_region[e] = CentroidMm(mesh_, e).norm() < kRadius ? 1 : 0;
    }
    ASSERT_TRUE(ColourTable::FromEntries(
                    {{kA, "A", 200, 0, 0}, {kB, "B", 0, 200, 0}, {kC, "C", 0, 0, 200}}, &colours_)
                    .ok());
    ASSERT_TRUE(RegionLabelsFromNames(mesh_, colours_, &region_label_).ok());
  }

  // Plates of the sphere centred at (shift, 0, 0).
  PlateStack SpherePlates(double shift) const {
    return MakePlates(kPixel, 80, 80, z_, colours_, [shift](double x, double y, double z) {
      return (Eigen::Vector3d(x - shift, y, z).norm() < kRadius) ? kB : kA;
    });
  }

  Mesh mesh_;
  ColourTable colours_;
  std::vector<uint16_t> region_label_;
  std::vector<double> z_ = {-9, -6, -2.5, 1, 4, 8};
};

// Plates rendered from the very shapes the mesh was labelled by: what is
// left is discretisation. The region boundary is a staircase of element
// faces whose centroids fall on either side of the sphere: it strays from
// the sphere by at most about half an element's extent, on average much
// less; the pixels add a quarter pixel. Bound: E < h/2 = 1 mm for both.
// The perimeter of B on plate i is the marching-squares length of a disc
// of radius sqrt(R^2 - z^2): 0 to 5.5 % above 2 pi r (see the header),
// allowing one pixel of radius for the digital disc: within [0.96, 1.08].
// The sections are cut in parallel, each into its own slot: one thread and
// two give the same figures, number for number.
TEST_F(SphereInBoxTest, TheSameOnOneThreadAndTwo) {
  GeometricValidation one, two;
  ASSERT_TRUE(
      ValidateAgainstPlates(mesh_, region_label_, SpherePlates(2), ThreadContext(1), &one).ok());
  ASSERT_TRUE(
      ValidateAgainstPlates(mesh_, region_label_, SpherePlates(2), ThreadContext(2), &two).ok());
  ASSERT_EQ(one.structures.size(), two.structures.size());
  EXPECT_EQ(one.total_sections, two.total_sections);
  EXPECT_EQ(one.overall_structural_error_mm, two.overall_structural_error_mm);
  EXPECT_GT(one.overall_structural_error_mm, 0);
  for (std::size_t k = 0; k < one.structures.size(); ++k) {
    EXPECT_EQ(one.structures[k].structural_error_mm, two.structures[k].structural_error_mm);
    EXPECT_EQ(one.structures[k].sections.size(), two.structures[k].sections.size());
  }
}

TEST_F(SphereInBoxTest, MatchingPlatesLeaveOnlyDiscretisationError) {
  const auto start = std::chrono::steady_clock::now();
  GeometricValidation v;
  ASSERT_TRUE(
      ValidateAgainstPlates(mesh_, region_label_, SpherePlates(0), ThreadContext(), &v).ok());
  std::printf("%d tets, %.2f s\n%s", mesh_.num_elements(), Seconds(start),
              FormatValidationTable(v, TableFormat::kText).c_str());
  ASSERT_EQ(v.structures.size(), 2u);
  for (uint16_t label : {kA, kB}) {
    const StructureValidation* s = Find(v, label);
    ASSERT_NE(s, nullptr);
    EXPECT_EQ(s->sections.size(), z_.size());
    EXPECT_LT(s->structural_error_mm, kH / 2) << s->name;
    EXPECT_GT(s->structural_error_mm, 0) << s->name;
    for (const SectionError& e : s->sections) {
      EXPECT_TRUE(e.in_plate && e.in_section);
      EXPECT_GT(e.landmarks, 0);
    }
  }
  const StructureValidation& b = *Find(v, kB);
  double sum_p = 0, sum_pe = 0;
  for (const SectionError& e : b.sections) {
    const double r = std::sqrt(kRadius * kRadius - e.z_mm * e.z_mm);
    EXPECT_GT(e.perimeter_mm, 0.96 * 2 * M_PI * r) << e.z_mm;
    EXPECT_LT(e.perimeter_mm, 1.08 * 2 * M_PI * r) << e.z_mm;
    sum_p += e.perimeter_mm;
    sum_pe += e.perimeter_mm * e.mean_distance_mm;
  }
  // Eqs. 4.2 and 4.3 from the sections.
  EXPECT_NEAR(b.structural_error_mm, sum_pe / sum_p, 1e-12);
  EXPECT_NEAR(b.percentage_error, sum_pe / sum_p * b.sections.size() / sum_p * 100, 1e-12);
  std::printf("matching plates: B E = %.3f mm, %%Err = %.3f; A E = %.3f mm, %%Err = %.3f\n",
              b.structural_error_mm, b.percentage_error, Find(v, kA)->structural_error_mm,
              Find(v, kA)->percentage_error);
}

// The plates' sphere shifted by s = 2 mm in x. Between two circles of radius
// r >> s whose centres are s apart, a point at angle theta on one lies
// |s cos theta| (to first order in s / r) from the other, so both mean
// distances are 2 s / pi = 1.27 mm. The discretisation error of the
// matching case (under 1 mm, partly cancelling) sits on top, and the
// smallest section (r = 8.5 mm at z = -9) bends the first-order estimate
// by under 0.1 mm: E of B within [2 s / pi - 0.5, 2 s / pi + 0.5]. %Err
// grows with E (same perimeters within a pixel).
TEST_F(SphereInBoxTest, ShiftedSphereRaisesTheErrorToAboutTheShift) {
  GeometricValidation matching, shifted;
  ASSERT_TRUE(
      ValidateAgainstPlates(mesh_, region_label_, SpherePlates(0), ThreadContext(), &matching)
          .ok());
  ASSERT_TRUE(
      ValidateAgainstPlates(mesh_, region_label_, SpherePlates(2), ThreadContext(), &shifted).ok());
  std::printf("%s", FormatValidationTable(shifted, TableFormat::kText).c_str());
  const StructureValidation& b0 = *Find(matching, kB);
  const StructureValidation& b2 = *Find(shifted, kB);
  const double expected = 2 * 2 / M_PI;
  std::printf(
      "shifted 2 mm: B E = %.3f mm (first order 2 s / pi = %.3f), %%Err = %.3f (was %.3f)\n",
      b2.structural_error_mm, expected, b2.percentage_error, b0.percentage_error);
  EXPECT_GT(b2.structural_error_mm, expected - 0.5);
  EXPECT_LT(b2.structural_error_mm, expected + 0.5);
  EXPECT_GT(b2.structural_error_mm, 2 * b0.structural_error_mm);
  EXPECT_GT(b2.percentage_error, 2 * b0.percentage_error);
  EXPECT_GT(Find(shifted, kA)->structural_error_mm, Find(matching, kA)->structural_error_mm);
  EXPECT_GT(shifted.overall_percentage_error, matching.overall_percentage_error);
}

// A plate with a structure the mesh lacks (C, a 3 mm disc at (10, 10) on
// plate 0) and a plate without the sphere the mesh has (plate 1): both are
// reported. Plate only: e_i = the mean distance of the plate's boundary
// pixels of C to C's centroid, recomputed here (about the radius less a
// quarter pixel). Section only: e_i = the same for the section's boundary
// pixels of B, about the section's radius sqrt(R^2 - z^2).
TEST_F(SphereInBoxTest, MissingAndExtraStructuresAreReportedAsDocumented) {
  z_ = {0, 5};
  const PlateStack plates =
      MakePlates(kPixel, 80, 80, z_, colours_, [](double x, double y, double z) {
        if (z > 0) return kA;
        if (std::hypot(x - 10, y - 10) < 3) return kC;
        return Eigen::Vector3d(x, y, z).norm() < kRadius ? kB : kA;
      });
  GeometricValidation v;
  ASSERT_TRUE(ValidateAgainstPlates(mesh_, region_label_, plates, ThreadContext(), &v).ok());
  std::printf("%s", FormatValidationTable(v, TableFormat::kText).c_str());
  ASSERT_EQ(v.structures.size(), 3u);

  const StructureValidation* c = Find(v, kC);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->name, "C");
  ASSERT_EQ(c->sections.size(), 1u);
  const SectionError& ce = c->sections[0];
  EXPECT_TRUE(ce.in_plate);
  EXPECT_FALSE(ce.in_section);
  EXPECT_EQ(ce.section_landmarks, 0);
  // The centroid and boundary of C on plate 0, by brute force.
  const auto at = [&](int col, int row) {
    return col >= 0 && row >= 0 && col < 80 && row < 80 ? plates.at(0, col, row) : 0;
  };
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> boundary;
  int count = 0;
  for (int row = 0; row < 80; ++row) {
    for (int col = 0; col < 80; ++col) {
      if (at(col, row) != kC) continue;
      const Eigen::Vector2d x = plates.PixelCentreMm(0, col, row).head<2>();
      centroid += x;
      ++count;
      if (at(col - 1, row) != kC || at(col + 1, row) != kC || at(col, row - 1) != kC ||
          at(col, row + 1) != kC) {
        boundary.push_back(x);
      }
    }
  }
  centroid /= count;
  double mean_radius = 0;
  for (const Eigen::Vector2d& x : boundary) mean_radius += (x - centroid).norm();
  mean_radius /= boundary.size();
  EXPECT_EQ(ce.landmarks, static_cast<int>(boundary.size()));
  EXPECT_NEAR(ce.mean_distance_mm, mean_radius, 1e-9);
  EXPECT_NEAR(ce.mean_distance_mm, 3 - 0.25, 0.25);
  std::printf("C (plate only): e = %.3f mm, %d landmarks\n", ce.mean_distance_mm, ce.landmarks);

  const StructureValidation& b = *Find(v, kB);
  ASSERT_EQ(b.sections.size(), 2u);
  const SectionError& be = b.sections[1];
  EXPECT_FALSE(be.in_plate);
  EXPECT_TRUE(be.in_section);
  const double r = std::sqrt(kRadius * kRadius - 25);
  EXPECT_NEAR(be.mean_distance_mm, r, 1.0);
  EXPECT_GT(be.perimeter_mm, 0);
  std::printf("B (section only at z = 5): e = %.3f mm (sphere radius there %.3f)\n",
              be.mean_distance_mm, r);
  EXPECT_GT(b.structural_error_mm, 3.0);
  EXPECT_TRUE(b.flagged);
}

TEST_F(SphereInBoxTest, RejectsBadInputNamingTheField) {
  GeometricValidation v;
  Status s = ValidateAgainstPlates(mesh_, {kA}, SpherePlates(0), ThreadContext(), &v);
  EXPECT_EQ(s.field(), "region_label");
  PlateStack plates = SpherePlates(0);
  plates.labels[1].pop_back();
  s = ValidateAgainstPlates(mesh_, region_label_, plates, ThreadContext(), &v);
  EXPECT_EQ(s.field(), "plates.labels[1]");
  mesh_.region_names[1] = "no such structure";
  s = RegionLabelsFromNames(mesh_, colours_, &region_label_);
  EXPECT_EQ(s.field(), "mesh.region_names[1]");
}

// The synthetic atlas at 2 mm voxels, rendered in memory onto the 27
// default plates (0.5 mm pixels, each pixel the label of the nearest voxel,
// as WritePlates does), lofted back at 1 mm; the "mesh" is a box of 2 mm
// elements over the lofted volume whose elements take the lofted label at
// their centroids (background elements dropped). Every structure of the
// plates must be in the table. The big structures' contours are followed to
// within the element staircase: E below half an element, 1 mm, as for the
// sphere; the whole atlas within the thesis's limit. The element faces lie
// on the 2 mm atlas voxels' faces in x and y (the box starts on a loft
// voxel face, 1 mm voxels, and the plates span the atlas from face to
// face), so the staircases of mesh and plates largely coincide: the
// figures (printed) are a floor for what a real mesher reaches, not an
// estimate of it.
TEST(AtlasValidationTest, BoxMeshSampledFromTheLoftFollowsThePlates) {
  auto start = std::chrono::steady_clock::now();
  SyntheticAtlasOptions atlas_options;
  atlas_options.voxel_size_mm = 2.0;
  const LabelVolume atlas = MakeSyntheticAtlas(atlas_options);
  const double pixel = 0.5;
  const Eigen::Vector3d lo = atlas.origin_mm() - 0.5 * atlas.spacing_mm();
  const Eigen::Vector3d hi = atlas.VoxelCentreMm(atlas.nx() - 1, atlas.ny() - 1, atlas.nz() - 1) +
                             0.5 * atlas.spacing_mm();
  PlateStack plates;
  plates.pixel_size_mm = pixel;
  plates.width = static_cast<int>(std::ceil((hi.x() - lo.x()) / pixel - 1e-9));
  plates.height = static_cast<int>(std::ceil((hi.y() - lo.y()) / pixel - 1e-9));
  plates.origin_mm = Eigen::Vector2d(lo.x() + 0.5 * pixel, hi.y() - 0.5 * pixel);
  plates.z_mm = DefaultPlateHeightsMm();
  plates.colours = ColourTable::Builtin();
  std::set<uint16_t> on_plates;
  for (int p = 0; p < plates.num_plates(); ++p) {
    std::vector<uint16_t> labels(static_cast<size_t>(plates.width) * plates.height);
    for (int r = 0; r < plates.height; ++r) {
      for (int c = 0; c < plates.width; ++c) {
        const uint16_t l = atlas.SampleNearest(plates.PixelCentreMm(p, c, r));
        labels[static_cast<size_t>(r) * plates.width + c] = l;
        if (l != 0) on_plates.insert(l);
      }
    }
    plates.labels.push_back(std::move(labels));
    plates.files.push_back("plate");
  }
  LoftOptions loft_options;
  loft_options.voxel_size_mm = 1.0;
  LabelVolume loft;
  ASSERT_TRUE(LoftPlates(plates, loft_options, &loft).ok());
  std::printf("atlas, plates and loft: %.2f s\n", Seconds(start));

  start = std::chrono::steady_clock::now();
  const Eigen::Vector3d box_lo = loft.origin_mm() - 0.5 * loft.spacing_mm();
  const Eigen::Vector3d box_hi =
      loft.VoxelCentreMm(loft.nx() - 1, loft.ny() - 1, loft.nz() - 1) + 0.5 * loft.spacing_mm();
  const double h = 2.0;
  Mesh box = BoxMesh(box_hi - box_lo, h, box_lo);
  Mesh mesh;
  mesh.nodes = box.nodes;
  std::vector<int> region_of_label(65536, -1);
  for (int e = 0; e < static_cast<int>(box.tets.size()); ++e) {
    const uint16_t l = loft.SampleNearest(CentroidMm(box, e));
    if (l == 0) continue;
    if (region_of_label[l] < 0) {
      region_of_label[l] = static_cast<int>(mesh.region_names.size());
      mesh.region_names.push_back(ColourTable::Builtin().FindByLabel(l)->name);
    }
    mesh.tets.push_back(box.tets[e]);
    mesh.element_region.push_back(region_of_label[l]);
  }
  std::vector<uint16_t> region_label;
  ASSERT_TRUE(RegionLabelsFromNames(mesh, ColourTable::Builtin(), &region_label).ok());
  std::printf("box mesh: %d of %zu tets in the brain, %zu regions: %.2f s\n", mesh.num_elements(),
              box.tets.size(), mesh.region_names.size(), Seconds(start));

  start = std::chrono::steady_clock::now();
  GeometricValidation v;
  ASSERT_TRUE(ValidateAgainstPlates(mesh, region_label, plates, ThreadContext(), &v).ok());
  std::printf("validation: %.2f s\n%s", Seconds(start),
              FormatValidationTable(v, TableFormat::kText).c_str());

  for (uint16_t l : on_plates) {
    const StructureValidation* s = Find(v, l);
    ASSERT_NE(s, nullptr) << l;
    int plates_with = 0;
    for (const SectionError& e : s->sections) plates_with += e.in_plate;
    EXPECT_GT(plates_with, 0) << s->name;
  }
  int flagged = 0;
  for (const StructureValidation& s : v.structures) {
    flagged += s.flagged;
    if (!s.flagged) continue;
    std::printf("%s:", s.name.c_str());
    for (const SectionError& e : s.sections) {
      std::printf(" [z %g: P %.1f e %.2f%s]", e.z_mm, e.perimeter_mm, e.mean_distance_mm,
                  e.in_plate ? (e.in_section ? "" : " plate only") : " section only");
    }
    std::printf("\n");
  }
  std::printf("%zu structures, %d flagged; overall E = %.3f mm, %%Err = %.3f\n",
              v.structures.size(), flagged, v.overall_structural_error_mm,
              v.overall_percentage_error);
  for (uint16_t l : {kWhiteMatter, kPutamen, kVentricles, kThalamusPulvinar, kThalamusOthers,
                     kNucleusCaudatus, kCorpusCallosum}) {
    const StructureValidation* s = Find(v, l);
    ASSERT_NE(s, nullptr) << l;
    EXPECT_LT(s->structural_error_mm, h / 2) << s->name;
  }
  EXPECT_FALSE(v.overall_flagged);
}

// A validation of known figures in the three forms.
GeometricValidation KnownValidation() {
  GeometricValidation v;
  StructureValidation a;
  a.name = "White matter";
  a.label = kWhiteMatter;
  a.sections.resize(27);
  a.structural_error_mm = 0.4125;
  a.percentage_error = 0.0123;
  StructureValidation b;
  b.name = "Thalamus: pulvinar";
  b.label = kThalamusPulvinar;
  b.sections.resize(5);
  b.structural_error_mm = 1.5;
  b.percentage_error = 2.25;
  b.flagged = true;
  v.structures = {a, b};
  v.total_sections = 32;
  v.overall_structural_error_mm = 0.5;
  v.overall_percentage_error = 0.125;
  return v;
}

TEST(ValidationTableTest, TextHasAlignedColumnsAndAnOverallLine) {
  const std::string text = FormatValidationTable(KnownValidation(), TableFormat::kText);
  std::printf("%s", text.c_str());
  std::istringstream in(text);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 7u);  // title, header, rule, 2 rows, rule, overall
  EXPECT_NE(lines[1].find("structure"), std::string::npos);
  EXPECT_NE(lines[1].find("E [mm]"), std::string::npos);
  EXPECT_NE(lines[3].find("White matter"), std::string::npos);
  EXPECT_NE(lines[3].find("0.412"), std::string::npos);
  EXPECT_NE(lines[4].find("FLAG"), std::string::npos);
  EXPECT_EQ(lines[3].find("FLAG"), std::string::npos);
  EXPECT_EQ(lines[6].rfind("overall", 0), 0u);
  // Right-aligned numbers: the E column ends at the same place in every row.
  const size_t end = lines[1].find("E [mm]") + 6;
  EXPECT_EQ(lines[3].substr(end - 5, 5), "0.412");
  EXPECT_EQ(lines[4].substr(end - 5, 5), "1.500");
  EXPECT_EQ(lines[6].substr(end - 5, 5), "0.500");
}

TEST(ValidationTableTest, CsvHasAHeaderARowPerStructureAndTheOverallRow) {
  const std::string csv = FormatValidationTable(KnownValidation(), TableFormat::kCsv);
  EXPECT_EQ(csv,
            "structure,label,sections,E [mm],%Err,flag\n"
            "White matter,44,27,0.4125,0.0123,false\n"
            "Thalamus: pulvinar,38,5,1.5,2.25,true\n"
            "overall,,32,0.5,0.125,false\n");
}

TEST(ValidationTableTest, JsonParsesWithTheNumbers) {
  const GeometricValidation v = KnownValidation();
  const std::string json = FormatValidationTable(v, TableFormat::kJson);
  std::printf("%s", json.c_str());
  const YAML::Node root = YAML::Load(json);
  ASSERT_TRUE(root["rows"].IsSequence());
  ASSERT_EQ(root["rows"].size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const YAML::Node row = root["rows"][i];
    const StructureValidation& s = v.structures[i];
    EXPECT_EQ(row["structure"].as<std::string>(), s.name);
    EXPECT_EQ(row["label"].as<int>(), s.label);
    EXPECT_EQ(row["sections"].as<int>(), static_cast<int>(s.sections.size()));
    EXPECT_DOUBLE_EQ(row["structural_error_mm"].as<double>(), s.structural_error_mm);
    EXPECT_DOUBLE_EQ(row["percentage_error"].as<double>(), s.percentage_error);
    EXPECT_EQ(row["flagged"].as<bool>(), s.flagged);
  }
  EXPECT_EQ(root["overall"]["sections"].as<int>(), 32);
  EXPECT_DOUBLE_EQ(root["overall"]["structural_error_mm"].as<double>(), 0.5);
  EXPECT_DOUBLE_EQ(root["overall"]["percentage_error"].as<double>(), 0.125);
  EXPECT_FALSE(root["overall"]["flagged"].as<bool>());
}

}  // namespace
}  // namespace pba
