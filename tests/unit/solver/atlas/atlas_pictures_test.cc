#include "atlas/atlas_pictures.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "common/plate_stacks.h"
#include "io/png_io.h"
#include "mesh/primitive_mesher.h"
#include "mesh/quadratic.h"

namespace pba {
namespace {

namespace fs = std::filesystem;
constexpr double kMm = 1e-3;
using Rgb = std::array<uint8_t, 3>;

// A tetrahedral box of edge `size` [mm], elements of `h` [mm] (node layers
// every h from `corner`), its lowest corner at `corner` [mm].
Mesh BoxMesh(const Eigen::Vector3d& size, double h, const Eigen::Vector3d& corner,
             ElementType element = ElementType::kTet4) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {size.x(), size.y(), size.z()};
  MeshSpec options;
  options.element = element;
  options.element_size_mm = h;
  MeshStats stats;
  Mesh mesh = BuildPrimitiveMesh(g, options, &stats);
  mesh.nodes.rowwise() += (corner * kMm).transpose();
  return mesh;
}

Eigen::Vector3d CentroidMm(const Mesh& mesh, int e) {
  return TetCorners(mesh, e).colwise().mean().transpose() / kMm;
}

Rgb Shaded(const Rgb& rgb) {
  Rgb out;
  for (int k = 0; k < 3; ++k) out[k] = static_cast<uint8_t>(std::lround(rgb[k] * kEdgeShade));
  return out;
}

std::string Show(const Rgb& rgb) {
  return std::to_string(rgb[0]) + " " + std::to_string(rgb[1]) + " " + std::to_string(rgb[2]);
}

fs::path TempRoot() {
  return fs::temp_directory_path() / ("pba_atlas_pictures_test_" + std::to_string(::getpid()));
}

// The 20 mm box centred on the origin, 2 mm elements (node layers on every
// even millimetre, so the regions below meet on element faces), in four
// regions by element centroid:
//   A (label 1): x < 0;  B (2): x > 0, y < 0;  C (3): x > 0, y > 0, z < 0;
//   D (4): x > 0, y > 0, z > 0.
// The label volume (0.5 mm voxels centred on (k + 1/2) 0.5 mm, the box's
// extent) holds the same four regions, so the contours lie on the
// interfaces.
class MeshCutTest : public ::testing::Test {
 protected:
  static constexpr uint16_t kA = 1, kB = 2, kC = 3, kD = 4;
  static constexpr Rgb kRgbA = {200, 40, 40}, kRgbB = {40, 200, 40}, kRgbC = {40, 40, 200},
                       kRgbD = {200, 200, 40};

  static uint16_t Quadrant(const Eigen::Vector3d& p) {
    if (p.x() < 0) return kA;
    if (p.y() < 0) return kB;
    return p.z() < 0 ? kC : kD;
  }

  void SetUp() override {
    mesh_ = BoxMesh(Eigen::Vector3d::Constant(20), 2, Eigen::Vector3d::Constant(-10));
    mesh_.region_names = {"A", "B", "C", "D"};
    mesh_.element_region.resize(mesh_.tets.size());
    for (int e = 0; e < mesh_.num_elements(); ++e) {
      mesh_.element_region[e] = Quadrant(CentroidMm(mesh_, e)) - 1;
    }
    region_labels_ = {kA, kB, kC, kD};
    ASSERT_TRUE(ColourTable::FromEntries({{kA, "A", 200, 40, 40},
                                          {kB, "B", 40, 200, 40},
                                          {kC, "C", 40, 40, 200},
                                          {kD, "D", 200, 200, 40},
                                          {5, "E", 90, 0, 90},
                                          {6, "F", 0, 90, 90}},
                                         &colours_)
                    .ok());
    volume_ =
        LabelVolume({40, 40, 40}, Eigen::Vector3d::Constant(-9.75), Eigen::Vector3d::Constant(0.5));
    for (int k = 0; k < 40; ++k) {
      for (int j = 0; j < 40; ++j) {
        for (int i = 0; i < 40; ++i) {
          volume_.set(i, j, k, Quadrant(volume_.VoxelCentreMm(i, j, k)));
        }
      }
    }
  }

  MeshCutPicture Cut(CutAxis axis, double position, const CutSource& source = {},
                     bool edges = false) const {
    MeshCutOptions options;
    options.axis = axis;
    options.position_mm = position;
    options.edges = edges;
    MeshCutPicture picture;
    const Status s = RenderMeshCut(mesh_, region_labels_, colours_, source, options, &picture);
    EXPECT_TRUE(s.ok()) << s.ToString();
    return picture;
  }

  // The colour at the image pixel of point (x, y, z) [mm].
  static Rgb At(const MeshCutPicture& pic, double x, double y, double z) {
    const std::array<int, 2> px = pic.ImagePixel({x, y, z});
    return pic.At(px[0], px[1]);
  }
  // The colour at fractions (fu, fv) of the section's width and height,
  // from its top left corner: orientation without ImagePixel.
  static Rgb AtFraction(const MeshCutPicture& pic, double fu, double fv) {
    return pic.At(pic.left + static_cast<int>(fu * pic.width),
                  pic.top + static_cast<int>(fv * pic.height));
  }

  Mesh mesh_;
  std::vector<uint16_t> region_labels_;
  ColourTable colours_;
  LabelVolume volume_;
};

TEST_F(MeshCutTest, AxialCutPaintsEachRegionOnItsSideAndBlackOutside) {
  const MeshCutPicture pic = Cut(CutAxis::kAxial, -5);
  // The box plus the 3 mm margin, 0.5 mm pixels, in a frame.
  EXPECT_EQ(pic.width, 54);
  EXPECT_EQ(pic.height, 54);
  EXPECT_GT(pic.left, 0);
  EXPECT_GT(pic.top, pic.left);  // the caption band above the frame
  EXPECT_GE(pic.image.width, pic.left + pic.width);
  EXPECT_EQ(pic.image.height, pic.top + pic.height + pic.left);
  EXPECT_EQ(pic.contour_source, "");

  EXPECT_EQ(At(pic, -5, 0, -5), kRgbA);
  EXPECT_EQ(At(pic, 5, -5, -5), kRgbB);
  EXPECT_EQ(At(pic, 5, 5, -5), kRgbC);
  // Half a pixel to either side of the interfaces x = 0 and y = 0.
  EXPECT_EQ(At(pic, -0.25, 5, -5), kRgbA);
  EXPECT_EQ(At(pic, 0.25, 5, -5), kRgbC);
  EXPECT_EQ(At(pic, 5, -0.25, -5), kRgbB);
  EXPECT_EQ(At(pic, 5, 0.25, -5), kRgbC);
  // Outside the box, inside the margin: black; the frame around it.
  EXPECT_EQ(At(pic, 12, 0, -5), (Rgb{0, 0, 0}));
  EXPECT_EQ(At(pic, 0, -12.5, -5), (Rgb{0, 0, 0}));
  EXPECT_EQ(pic.At(pic.left - 1, pic.top), kFrameColour);
  // Seen from above, +x right, anterior up: A fills the left half, B the
  // lower right, C the upper right quadrant.
  EXPECT_EQ(AtFraction(pic, 0.3, 0.5), kRgbA);
  EXPECT_EQ(AtFraction(pic, 0.7, 0.3), kRgbC);
  EXPECT_EQ(AtFraction(pic, 0.7, 0.7), kRgbB);
  // Above z = 0 the upper right is D.
  EXPECT_EQ(AtFraction(Cut(CutAxis::kAxial, 5), 0.7, 0.3), kRgbD);
  // Every section pixel centre inside the box is painted, none outside.
  for (int r = 0; r < pic.height; ++r) {
    for (int c = 0; c < pic.width; ++c) {
      const Eigen::Vector3d p = pic.SectionPixelCentreMm(c, r);
      const bool inside = p.x() > -10 && p.x() < 10 && p.y() > -10 && p.y() < 10;
      const Rgb rgb = pic.At(pic.left + c, pic.top + r);
      const uint16_t q = Quadrant(p);
      const Rgb expected = !inside ? Rgb{0, 0, 0} : q == kA ? kRgbA : q == kB ? kRgbB : kRgbC;
      EXPECT_EQ(rgb, expected) << "x " << p.x() << " y " << p.y();
    }
  }
}

// Coronal from behind (+x right, z up), sagittal from the right (+y right,
// z up).
TEST_F(MeshCutTest, CoronalAndSagittalCutsAreOrientedAsDocumented) {
  const MeshCutPicture coronal = Cut(CutAxis::kCoronal, 5);
  EXPECT_EQ(AtFraction(coronal, 0.3, 0.5), kRgbA);
  EXPECT_EQ(AtFraction(coronal, 0.7, 0.3), kRgbD);
  EXPECT_EQ(AtFraction(coronal, 0.7, 0.7), kRgbC);
  EXPECT_EQ(At(coronal, -5, 5, 5), kRgbA);
  EXPECT_EQ(At(coronal, 5, 5, 5), kRgbD);

  const MeshCutPicture sagittal = Cut(CutAxis::kSagittal, 5);
  EXPECT_EQ(AtFraction(sagittal, 0.3, 0.3), kRgbB);
  EXPECT_EQ(AtFraction(sagittal, 0.3, 0.7), kRgbB);
  EXPECT_EQ(AtFraction(sagittal, 0.7, 0.3), kRgbD);
  EXPECT_EQ(AtFraction(sagittal, 0.7, 0.7), kRgbC);
  EXPECT_EQ(At(sagittal, 5, -5, 5), kRgbB);
  EXPECT_EQ(At(sagittal, 5, 5, -5), kRgbC);
}

// The cut polygons' outlines: in the fill colour darkened, along the
// element faces x = -6 (a node plane), and not everywhere.
TEST_F(MeshCutTest, ElementEdgesAreDarkenedFillColour) {
  const MeshCutPicture pic = Cut(CutAxis::kAxial, -5, {}, true);
  int plain = 0, dark = 0;
  for (int r = 0; r < pic.height; ++r) {
    for (int c = 0; c < pic.width; ++c) {
      const Eigen::Vector3d p = pic.SectionPixelCentreMm(c, r);
      if (!(p.x() > -9.5 && p.x() < -0.5 && std::abs(p.y()) < 9.5)) continue;
      const Rgb rgb = pic.At(pic.left + c, pic.top + r);
      plain += rgb == kRgbA;
      dark += rgb == Shaded(kRgbA);
      EXPECT_TRUE(rgb == kRgbA || rgb == Shaded(kRgbA)) << Show(rgb);
    }
  }
  EXPECT_GT(dark, 0);
  EXPECT_GT(plain, 0);
  // The face x = -6 runs between pixel centres -6.25 and -5.75: one of the
  // two is on the line in every row across the box.
  for (double y = -9.25; y < 9.5; y += 0.5) {
    const std::array<int, 2> px = pic.ImagePixel({-6.25, y, -5});
    EXPECT_TRUE(pic.At(px[0], px[1]) == Shaded(kRgbA) || pic.At(px[0] + 1, px[1]) == Shaded(kRgbA))
        << "y " << y;
  }
}

// The label volume's boundaries in white: on the left / upper side of each
// change, the box's outline included; nothing white elsewhere.
TEST_F(MeshCutTest, VolumeContoursAreWhiteWhereTheLabelChanges) {
  CutSource source;
  source.volume = &volume_;
  const MeshCutPicture pic = Cut(CutAxis::kAxial, -5, source);
  EXPECT_EQ(pic.contour_source, "label volume");
  EXPECT_EQ(At(pic, -0.25, 5, -5), kContourWhite);  // A | C
  EXPECT_EQ(At(pic, 0.25, 5, -5), kRgbC);
  EXPECT_EQ(At(pic, 5, 0.25, -5), kContourWhite);  // C over B
  EXPECT_EQ(At(pic, 5, -0.25, -5), kRgbB);
  EXPECT_EQ(At(pic, 9.75, 5, -5), kContourWhite);    // C | outside
  EXPECT_EQ(At(pic, -10.25, 5, -5), kContourWhite);  // outside | A
  EXPECT_EQ(At(pic, -5, 5, -5), kRgbA);
  int white = 0;
  for (int r = 0; r < pic.height; ++r) {
    for (int c = 0; c < pic.width; ++c) white += pic.At(pic.left + c, pic.top + r) == kContourWhite;
  }
  // The box's outline (four sides of 40 pixels, the lower right corner
  // shared by two) and the interfaces x = 0 (40 rows) and y = 0 (20
  // columns), less the pixel each shares with the outline.
  EXPECT_EQ(white, 159 + 39 + 19);
}

// An axial cut at a plate's height takes the plate's contours (a disc of
// radius 4 mm); off the plates, the volume's.
TEST_F(MeshCutTest, PlateContoursAtPlateHeightsVolumeContoursBetween) {
  PlateStack plates = testing::PaintPlateStack(
      0.5, 40, 40, {-5, 3},
      [](int, double x, double y, double) { return std::hypot(x, y) < 4 ? kB : kA; });
  plates.colours = colours_;
  CutSource source;
  source.volume = &volume_;
  source.plates = &plates;
  MeshCutPicture pic = Cut(CutAxis::kAxial, -5, source);
  EXPECT_EQ(pic.contour_source, "plate 1");
  // The plates' lattice: the grids coincide.
  EXPECT_NEAR(std::remainder(pic.u0_mm - plates.origin_mm.x(), 0.5), 0, 1e-9);
  EXPECT_NEAR(std::remainder(pic.v0_mm - plates.origin_mm.y(), 0.5), 0, 1e-9);
  EXPECT_EQ(At(pic, 3.75, 0.25, -5), kContourWhite);  // r = 3.76 in, 4.26 out
  EXPECT_EQ(At(pic, 4.25, 0.25, -5), kRgbC);
  EXPECT_EQ(At(pic, 0.25, 4.25, -5), kContourWhite);  // out, over in
  EXPECT_EQ(At(pic, -0.25, 5, -5), kRgbA);            // the volume's interface: not drawn
  EXPECT_EQ(At(pic, -0.25, 0.25, -5), kRgbA);

  pic = Cut(CutAxis::kAxial, -4, source);
  EXPECT_EQ(pic.contour_source, "label volume");
  EXPECT_EQ(At(pic, -0.25, 5, -4), kContourWhite);
  EXPECT_EQ(At(pic, 0.25, 4.25, -4), kRgbC);

  // A plate lattice offset from (k + 1/2) h is followed.
  plates.origin_mm += Eigen::Vector2d(0.1, -0.2);
  pic = Cut(CutAxis::kAxial, 3, source);
  EXPECT_EQ(pic.contour_source, "plate 2");
  EXPECT_NEAR(std::remainder(pic.u0_mm - plates.origin_mm.x(), 0.5), 0, 1e-9);
  EXPECT_NEAR(std::remainder(pic.v0_mm - plates.origin_mm.y(), 0.5), 0, 1e-9);
}

// The regions x > 0 merged into "Surrounding tissue" (label 0): mid grey,
// and the source's structures there (E and F, no region's) merged too, so
// no contour between them.
TEST_F(MeshCutTest, SurroundingTissueIsGreyAndMergedStructuresHaveNoContours) {
  mesh_.region_names = {"A", "Surrounding tissue"};
  for (int& r : mesh_.element_region) r = r == 0 ? 0 : 1;
  region_labels_ = {kA, 0};
  for (int k = 0; k < 40; ++k) {
    for (int j = 0; j < 40; ++j) {
      for (int i = 0; i < 40; ++i) {
        const Eigen::Vector3d p = volume_.VoxelCentreMm(i, j, k);
        if (p.x() > 0) volume_.set(i, j, k, p.y() < 0 ? 5 : 6);
      }
    }
  }
  CutSource source;
  source.volume = &volume_;
  const MeshCutPicture pic = Cut(CutAxis::kAxial, -5, source);
  EXPECT_EQ(At(pic, 5, 5, -5), kSurroundingGrey);
  EXPECT_EQ(At(pic, 5, 0.25, -5), kSurroundingGrey);  // E | F: merged, no contour
  EXPECT_EQ(At(pic, -0.25, 5, -5), kContourWhite);    // A | the rest
  EXPECT_EQ(At(pic, -5, 5, -5), kRgbA);

  // Without a label-0 region, structures no region carries (E, F) are
  // background: a contour around them, none between them.
  region_labels_ = {kA, kB};
  const MeshCutPicture dropped = Cut(CutAxis::kAxial, -5, source);
  EXPECT_EQ(At(dropped, -0.25, 5, -5), kContourWhite);
  EXPECT_EQ(At(dropped, 5, 0.25, -5), kRgbB);
}

TEST_F(MeshCutTest, QuadraticMeshGivesTheSamePicture) {
  CutSource source;
  source.volume = &volume_;
  const MeshCutPicture linear = Cut(CutAxis::kCoronal, -3, source, true);
  mesh_ = MakeQuadratic(mesh_);
  ASSERT_TRUE(mesh_.quadratic());
  const MeshCutPicture quadratic = Cut(CutAxis::kCoronal, -3, source, true);
  EXPECT_EQ(quadratic.image.rgb, linear.image.rgb);
}

TEST_F(MeshCutTest, BadCutsAreErrorsNamingTheField) {
  MeshCutOptions options;
  options.position_mm = 30;
  MeshCutPicture pic;
  Status s = RenderMeshCut(mesh_, region_labels_, colours_, {}, options, &pic);
  EXPECT_EQ(s.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(s.field(), "position_mm");
  EXPECT_NE(s.message().find("axial cut at z = 30 mm"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("z extent is [-10.0, 10.0] mm"), std::string::npos) << s.message();

  options.axis = CutAxis::kSagittal;
  options.position_mm = -10.5;
  s = RenderMeshCut(mesh_, region_labels_, colours_, {}, options, &pic);
  EXPECT_EQ(s.field(), "position_mm");
  EXPECT_NE(s.message().find("sagittal cut at x = -10.5 mm"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("x extent"), std::string::npos) << s.message();
  // On the mesh's surface is still a cut.
  options.position_mm = -10;
  EXPECT_TRUE(RenderMeshCut(mesh_, region_labels_, colours_, {}, options, &pic).ok());

  options.position_mm = 0;
  options.pixel_mm = 0;
  s = RenderMeshCut(mesh_, region_labels_, colours_, {}, options, &pic);
  EXPECT_EQ(s.field(), "pixel_mm");
  options.pixel_mm = 0.0005;  // 40,000 pixels a side
  s = RenderMeshCut(mesh_, region_labels_, colours_, {}, options, &pic);
  EXPECT_EQ(s.field(), "pixel_mm");
  EXPECT_NE(s.message().find("at most"), std::string::npos) << s.message();
  options.pixel_mm = 0.5;

  s = RenderMeshCut(mesh_, {kA, kB, kC, 9}, colours_, {}, options, &pic);
  EXPECT_EQ(s.field(), "region_labels[3]");
  s = RenderMeshCut(mesh_, {kA, kB}, colours_, {}, options, &pic);
  EXPECT_EQ(s.field(), "region_labels");

  const Mesh hexes =
      BoxMesh(Eigen::Vector3d::Constant(4), 2, Eigen::Vector3d::Zero(), ElementType::kHex8);
  ASSERT_TRUE(hexes.hexahedral());
  s = RenderMeshCut(hexes, {kA}, colours_, {}, options, &pic);
  EXPECT_EQ(s.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(s.field(), "mesh");
  EXPECT_NE(s.message().find("hexahedral"), std::string::npos) << s.message();
}

TEST_F(MeshCutTest, PngReadsBackWithItsPixelsAndNotice) {
  const fs::path dir = TempRoot() / "cut";
  fs::remove_all(dir);
  fs::create_directories(dir);
  CutSource source;
  source.volume = &volume_;
  MeshCutOptions options;
  options.axis = CutAxis::kCoronal;
  options.position_mm = 2.5;
  options.notice = kSyntheticAtlasNotice;
  MeshCutPicture pic;
  ASSERT_TRUE(RenderMeshCut(mesh_, region_labels_, colours_, source, options, &pic).ok());
  const fs::path png = dir / CutFileName(options.axis, options.position_mm);
  EXPECT_EQ(png.filename(), "cut_coronal_y+002.5mm.png");
  ASSERT_TRUE(WriteMeshCut(mesh_, region_labels_, colours_, source, options, png).ok());
  RgbImage read;
  ASSERT_TRUE(ReadRgbPng(png, &read).ok());
  EXPECT_EQ(read.width, pic.image.width);
  EXPECT_EQ(read.height, pic.image.height);
  EXPECT_EQ(read.rgb, pic.image.rgb);
  bool notice = false, title = false;
  for (const auto& [key, text] : read.text) {
    notice = notice || (key == "Comment" && text == kSyntheticAtlasNotice);
    title = title || (key == "Title" && text.find("coronal y +2.5 mm") != std::string::npos);
  }
  EXPECT_TRUE(notice);
  EXPECT_TRUE(title);
  // Written whole: nothing beside it.
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) files += entry.is_regular_file();
  EXPECT_EQ(files, 1);
  fs::remove_all(TempRoot());
}

TEST(CutFileNameTest, SignedPositionToATenth) {
  EXPECT_EQ(CutFileName(CutAxis::kAxial, 5), "cut_axial_z+005.0mm.png");
  EXPECT_EQ(CutFileName(CutAxis::kAxial, -16), "cut_axial_z-016.0mm.png");
  EXPECT_EQ(CutFileName(CutAxis::kCoronal, -20.04), "cut_coronal_y-020.0mm.png");
  EXPECT_EQ(CutFileName(CutAxis::kSagittal, 25), "cut_sagittal_x+025.0mm.png");
  EXPECT_EQ(CutFileName(CutAxis::kSagittal, -0.01), "cut_sagittal_x+000.0mm.png");
  EXPECT_EQ(CutFileName(CutAxis::kAxial, 123.45), "cut_axial_z+123.5mm.png");
}

// Five plates of 20 x 12 pixels, plate p's left half label p + 1, its
// right half label 10.
class ContactSheetTest : public ::testing::Test {
 protected:
  void SetUp() override {
    plates_ = testing::PaintPlateStack(
        1.0, 20, 12, {-6, -3, 0, 2.5, 5},
        [](int p, double x, double, double) { return static_cast<uint16_t>(x < 0 ? p + 1 : 10); });
    ASSERT_TRUE(ColourTable::FromEntries({{1, "one", 250, 0, 0},
                                          {2, "two", 0, 250, 0},
                                          {3, "three", 0, 0, 250},
                                          {4, "four", 250, 250, 0},
                                          {5, "five", 0, 250, 250},
                                          {10, "ten", 120, 60, 30}},
                                         &plates_.colours)
                    .ok());
  }
  Rgb ColourOf(uint16_t label) const {
    const ColourEntry* e = plates_.colours.FindByLabel(label);
    return e == nullptr ? Rgb{0, 0, 0} : Rgb{e->r, e->g, e->b};
  }
  static Rgb Pixel(const RgbImage& image, int c, int r) {
    const uint8_t* px = &image.rgb[(static_cast<size_t>(r) * image.width + c) * 3];
    return {px[0], px[1], px[2]};
  }
  PlateStack plates_;
};

TEST_F(ContactSheetTest, TilesBottomPlateFirstInItsColoursWithCaptions) {
  const fs::path dir = TempRoot() / "sheet";
  fs::remove_all(dir);
  fs::create_directories(dir);
  ASSERT_TRUE(WritePlateContactSheet(plates_, dir / "plates.png", kSyntheticAtlasNotice).ok());
  RgbImage sheet;
  ASSERT_TRUE(ReadRgbPng(dir / "plates.png", &sheet).ok());
  fs::remove_all(TempRoot());

  // 3 columns, 2 rows; each cell as wide as its widest caption ("z 2.5
  // mm": 8 glyphs of 6 pixels, plus 2), 12 pixels of plate and a 13-pixel
  // caption band tall, 4-pixel gaps.
  const ContactSheetLayout l = LayOutContactSheet(plates_);
  EXPECT_EQ(l.columns, 3);
  EXPECT_EQ(l.rows, 2);
  EXPECT_EQ(l.step, 1);
  EXPECT_EQ(l.cell_width, 50);
  EXPECT_EQ(sheet.width, 4 + 3 * (50 + 4));
  EXPECT_EQ(sheet.height, 4 + 2 * (12 + 13 + 4));
  EXPECT_EQ(l.TileLeft(3), 4);
  EXPECT_EQ(l.TileTop(3), 4 + 12 + 13 + 4);
  EXPECT_EQ(l.TileLeft(2), 4 + 2 * 54);
  EXPECT_EQ(l.TileTop(2), 4);

  for (int p = 0; p < plates_.num_plates(); ++p) {
    for (int r = 0; r < 12; ++r) {
      for (int c = 0; c < 20; ++c) {
        ASSERT_EQ(Pixel(sheet, l.TileLeft(p) + c, l.TileTop(p) + r), ColourOf(plates_.at(p, c, r)))
            << "plate " << p << " pixel " << c << ", " << r;
      }
    }
    // The left half in the plate's own colour, the right in label 10's.
    EXPECT_EQ(Pixel(sheet, l.TileLeft(p), l.TileTop(p)), ColourOf(p + 1));
    EXPECT_EQ(Pixel(sheet, l.TileLeft(p) + 19, l.TileTop(p) + 11), ColourOf(10));
    // Grey beside the tile within its cell; the caption's text under it.
    EXPECT_EQ(Pixel(sheet, l.TileLeft(p) + 20, l.TileTop(p)), kGapGrey);
    int text = 0;
    for (int r = 0; r < l.caption_height; ++r) {
      for (int c = 0; c < l.cell_width; ++c) {
        text += Pixel(sheet, l.TileLeft(p) + c, l.TileTop(p) + 12 + r) == kTextColour;
      }
    }
    EXPECT_GT(text, 20) << "plate " << p;
  }
  EXPECT_EQ(Pixel(sheet, 0, 0), kGapGrey);
  // The sixth cell is empty.
  EXPECT_EQ(Pixel(sheet, l.TileLeft(5) + 5, l.TileTop(5) + 5), kGapGrey);
  bool notice = false;
  for (const auto& [key, text] : sheet.text) {
    notice = notice || (key == "Comment" && text == kSyntheticAtlasNotice);
  }
  EXPECT_TRUE(notice);
}

// Four plates 2100 pixels wide: two columns would be 4212 pixels, so every
// second pixel is shown.
TEST_F(ContactSheetTest, WideStackIsSubsampled) {
  PlateStack wide =
      testing::PaintPlateStack(0.1, 2100, 5, {0, 1, 2, 3}, [](int p, double x, double, double) {
        const int stripe = static_cast<int>(std::floor(x * 3)) + p;
        return static_cast<uint16_t>(1 + ((stripe % 5) + 5) % 5);
      });
  wide.colours = plates_.colours;
  RgbImage sheet;
  ASSERT_TRUE(RenderPlateContactSheet(wide, "", &sheet).ok());
  const ContactSheetLayout l = LayOutContactSheet(wide);
  EXPECT_EQ(l.columns, 2);
  EXPECT_EQ(l.step, 2);
  EXPECT_EQ(l.tile_width, 1050);
  EXPECT_EQ(l.tile_height, 3);
  EXPECT_EQ(sheet.width, 4 + 2 * (1050 + 4));
  EXPECT_LE(sheet.width, kMaxSheetWidth);
  for (int p = 0; p < 4; ++p) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 1050; ++c) {
        ASSERT_EQ(Pixel(sheet, l.TileLeft(p) + c, l.TileTop(p) + r),
                  ColourOf(wide.at(p, 2 * c, 2 * r)))
            << p << " " << c << " " << r;
      }
    }
  }
  for (const auto& [key, text] : sheet.text) EXPECT_NE(key, "Comment");
}

TEST_F(ContactSheetTest, LabelWithoutColourIsAnError) {
  plates_.labels[2][5] = 7;
  RgbImage sheet;
  const Status s = RenderPlateContactSheet(plates_, "", &sheet);
  EXPECT_EQ(s.field(), "plates.colours");
  EXPECT_NE(s.message().find("label 7 on plate 3"), std::string::npos) << s.message();
}

// The pictures of a hand-made build result: the box of MeshCutTest with
// plates at seven heights.
class AtlasPicturesTest : public MeshCutTest {
 protected:
  void SetUp() override {
    MeshCutTest::SetUp();
    result_.synthetic = true;
    result_.colours = colours_;
    result_.volume = volume_;
    result_.mesh = mesh_;
    result_.region_labels = region_labels_;
    result_.plates = testing::PaintPlateStack(0.5, 40, 40, {-8, -6, -3, 0, 3, 6, 8},
                                              [](int, double x, double y, double z) {
                                                return Quadrant({x, y, z});
                                              });
    result_.plates->colours = colours_;
    dir_ = TempRoot() / "pictures";
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(TempRoot()); }

  std::set<std::string> Files() const {
    std::set<std::string> files;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      files.insert(entry.path().filename().string());
    }
    return files;
  }

  AtlasBuildResult result_;
  fs::path dir_;
};

// Axial at plates 7 / 6, 21 / 6, 35 / 6 (rounded down): z = -6, 0, 6;
// coronal through the mesh's centre (no thalamus); sagittal 0.4 of the
// half-width right of the centre: x = 4.
TEST_F(AtlasPicturesTest, DefaultCutsAndTheContactSheet) {
  std::vector<std::string> written;
  const Status s = WriteAtlasPictures(result_, dir_, {}, &written);
  ASSERT_TRUE(s.ok()) << s.ToString();
  const std::vector<std::string> expected = {"plates.png",
                                             "cut_axial_z-006.0mm.png",
                                             "cut_axial_z+000.0mm.png",
                                             "cut_axial_z+006.0mm.png",
                                             "cut_coronal_y+000.0mm.png",
                                             "cut_sagittal_x+004.0mm.png"};
  EXPECT_EQ(written, expected);
  EXPECT_EQ(Files(), std::set<std::string>(expected.begin(), expected.end()));

  // The axial cut at plate 6 (z = 6) shows D in the upper right, with the
  // plate's contours, and says what it is.
  RgbImage cut;
  ASSERT_TRUE(ReadRgbPng(dir_ / "cut_axial_z+006.0mm.png", &cut).ok());
  MeshCutOptions options;
  options.position_mm = 6;
  options.notice = kSyntheticAtlasNotice;
  MeshCutPicture pic;
  CutSource source{&result_.volume, &*result_.plates};
  ASSERT_TRUE(RenderMeshCut(mesh_, region_labels_, colours_, source, options, &pic).ok());
  EXPECT_EQ(pic.contour_source, "plate 6");
  EXPECT_EQ(cut.rgb, pic.image.rgb);
  EXPECT_EQ(At(pic, -0.25, 5, 6), kContourWhite);
  bool notice = false;
  for (const auto& [key, text] : cut.text) notice = notice || key == "Comment";
  EXPECT_TRUE(notice);
}

TEST_F(AtlasPicturesTest, CoronalCutThroughTheThalamusAndChosenCuts) {
  // D renamed a thalamic nucleus: its voxels' centroid is at y = 5.
  ASSERT_TRUE(ColourTable::FromEntries({{kA, "A", 200, 40, 40},
                                        {kB, "B", 40, 200, 40},
                                        {kC, "C", 40, 40, 200},
                                        {kD, "Thalamus: test", 200, 200, 40}},
                                       &result_.colours)
                  .ok());
  result_.plates.reset();
  result_.synthetic = false;
  std::vector<std::string> written;
  ASSERT_TRUE(WriteAtlasPictures(result_, dir_, {}, &written).ok());
  // No plates: no sheet, axial cuts at 1/6, 1/2, 5/6 of z in [-10, 10].
  EXPECT_EQ(written,
            (std::vector<std::string>{"cut_axial_z-007.0mm.png", "cut_axial_z+000.0mm.png",
                                      "cut_axial_z+007.0mm.png", "cut_coronal_y+005.0mm.png",
                                      "cut_sagittal_x+004.0mm.png"}));
  RgbImage cut;
  ASSERT_TRUE(ReadRgbPng(dir_ / "cut_coronal_y+005.0mm.png", &cut).ok());
  for (const auto& [key, text] : cut.text) EXPECT_NE(key, "Comment");  // not synthetic

  fs::remove_all(dir_);
  AtlasPictureOptions options;
  options.axial_z_mm = {3, 3};
  options.sagittal_x_mm = {-2};
  ASSERT_TRUE(WriteAtlasPictures(result_, dir_, options, &written).ok());
  EXPECT_EQ(written,
            (std::vector<std::string>{"cut_axial_z+003.0mm.png", "cut_sagittal_x-002.0mm.png"}));
  EXPECT_EQ(Files().size(), 2u);

  options.sagittal_x_mm = {40};
  const Status s = WriteAtlasPictures(result_, dir_, options, &written);
  EXPECT_EQ(s.field(), "position_mm");
  EXPECT_NE(s.message().find("sagittal cut at x = 40 mm"), std::string::npos) << s.message();
  options.pixel_mm = -1;
  EXPECT_EQ(WriteAtlasPictures(result_, dir_, options, &written).field(), "pixel_mm");
}

// A mesh the size of the default atlas's (about half a million
// tetrahedra): one cut must take well under a second.
TEST(MeshCutSpeedTest, HalfAMillionTetrahedra) {
  Mesh mesh = BoxMesh({120, 160, 120}, 3, {-60, -80, -60});
  std::printf("%d tetrahedra\n", mesh.num_elements());
  ColourTable colours;
  ASSERT_TRUE(ColourTable::FromEntries({{1, "A", 200, 40, 40}}, &colours).ok());
  MeshCutOptions options;
  for (CutAxis axis : {CutAxis::kAxial, CutAxis::kCoronal, CutAxis::kSagittal}) {
    options.axis = axis;
    options.position_mm = 1;
    MeshCutPicture pic;
    const auto start = std::chrono::steady_clock::now();
    ASSERT_TRUE(RenderMeshCut(mesh, {1}, colours, {}, options, &pic).ok());
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("%s cut: %d x %d pixels, %.3f s\n", CutAxisName(axis), pic.width, pic.height, s);
    EXPECT_LT(s, 1.0);
  }
}

}  // namespace
}  // namespace pba
