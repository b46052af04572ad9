#include "atlas/loft.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <random>
#include <vector>

#include "atlas/synthetic_atlas.h"
#include "common/plate_stacks.h"

namespace pba {
namespace {

namespace fs = std::filesystem;

// A stack of `z_mm.size()` plates of width x height pixels centred on
// (0, 0), pixel (c, r) at (origin.x + c h, origin.y - r h), labelled by
// paint(plate, x, y).
PlateStack MakeStack(double pixel, int width, int height, const std::vector<double>& z_mm,
                     const std::function<uint16_t(int, double, double)>& paint) {
  return testing::PaintPlateStack(
      pixel, width, height, z_mm,
      [&](int p, double x, double y, double) { return paint(p, x, y); });
}

// 4-connected components of `label` in layer k.
int CountComponents(const LabelVolume& v, int k, uint16_t label) {
  std::vector<char> seen(static_cast<size_t>(v.nx()) * v.ny(), 0);
  int components = 0;
  std::vector<std::pair<int, int>> todo;
  for (int j0 = 0; j0 < v.ny(); ++j0) {
    for (int i0 = 0; i0 < v.nx(); ++i0) {
      if (v.at(i0, j0, k) != label || seen[j0 * v.nx() + i0]) continue;
      ++components;
      seen[j0 * v.nx() + i0] = 1;
      todo.assign(1, {i0, j0});
      while (!todo.empty()) {
        const auto [i, j] = todo.back();
        todo.pop_back();
        const int di[] = {1, -1, 0, 0}, dj[] = {0, 0, 1, -1};
        for (int n = 0; n < 4; ++n) {
          const int a = i + di[n], b = j + dj[n];
          if (!v.Contains(a, b, k) || v.at(a, b, k) != label || seen[b * v.nx() + a]) continue;
          seen[b * v.nx() + a] = 1;
          todo.push_back({a, b});
        }
      }
    }
  }
  return components;
}

int64_t CountInLayer(const LabelVolume& v, int k, uint16_t label) {
  int64_t n = 0;
  for (int j = 0; j < v.ny(); ++j) {
    for (int i = 0; i < v.nx(); ++i) n += v.at(i, j, k) == label;
  }
  return n;
}

int LayerOf(const LabelVolume& v, double z_mm) {
  return static_cast<int>(std::lround((z_mm - v.origin_mm().z()) / v.spacing_mm().z()));
}

TEST(LoftTest, RejectsBadOptionsAndStacksNamingTheField) {
  const PlateStack good =
      MakeStack(1.0, 4, 4, {0, 2}, [](int, double, double) { return uint16_t{1}; });
  LabelVolume v;
  LoftOptions options;
  options.voxel_size_mm = 0;
  EXPECT_EQ(LoftPlates(good, options, &v).field(), "voxel_size_mm");
  options = LoftOptions();
  options.max_extrapolation_mm = -1;
  EXPECT_EQ(LoftPlates(good, options, &v).field(), "max_extrapolation_mm");
  options = LoftOptions();
  PlateStack one = good;
  one.z_mm.pop_back();
  one.labels.pop_back();
  EXPECT_EQ(LoftPlates(one, options, &v).field(), "stack.z_mm");
  PlateStack bad_pixel = good;
  bad_pixel.pixel_size_mm = -1;
  EXPECT_EQ(LoftPlates(bad_pixel, options, &v).field(), "stack.pixel_size_mm");
  PlateStack short_plate = good;
  short_plate.labels[1].pop_back();
  EXPECT_EQ(LoftPlates(short_plate, options, &v).field(), "stack.labels[1]");
  PlateStack unordered = good;
  unordered.z_mm[1] = 0;
  EXPECT_EQ(LoftPlates(unordered, options, &v).field(), "stack.z_mm[1]");
  EXPECT_TRUE(LoftPlates(good, options, &v).ok());
}

// Plates of a sphere of radius 20 mm every 4 mm (z = -18 ... 18) lofted at
// 0.25 mm. Between plates the interpolated signed distance of two discs,
// rho - ((1 - t) r_a + t r_b), gives a frustum (the radius is the chord of
// the circle r(z) = sqrt(R^2 - z^2)); each end caps by the taper rule,
// radius r_e (1 - 2t) / (1 - t) over 2 mm, volume 4 pi r_e^2 (3 - 4 ln 2).
// That model is 32973 mm^3, 1.6 % below 4/3 pi R^3 = 33510 mm^3 (chords
// lie inside a concave profile). The loft must match the model to 0.5 %
// (pixel and voxel discretisation) and the sphere to 2.5 %.
TEST(LoftTest, SphereFromDiscsMatchesTheFrustumModel) {
  const double radius = 20, pixel = 0.2;
  std::vector<double> z;
  for (double h = -18; h <= 18; h += 4) z.push_back(h);
  const PlateStack stack = MakeStack(pixel, 230, 230, z, [&](int p, double x, double y) {
    return uint16_t(x * x + y * y <= radius * radius - z[p] * z[p] ? 1 : 0);
  });
  LoftOptions options;
  options.voxel_size_mm = 0.25;
  LabelVolume v;
  ASSERT_TRUE(LoftPlates(stack, options, &v).ok());
  EXPECT_NEAR(v.origin_mm().z(), -20 + 0.0, 1e-9);  // 2 mm (half the spacing) below
  const double lofted = CountLabels(v)[1] * v.voxel_volume_mm3();
  double model = 0;
  for (size_t p = 0; p + 1 < z.size(); ++p) {
    const double a = std::sqrt(radius * radius - z[p] * z[p]);
    const double b = std::sqrt(radius * radius - z[p + 1] * z[p + 1]);
    model += M_PI * 4 * (a * a + a * b + b * b) / 3;
  }
  const double r_end = std::sqrt(radius * radius - 18 * 18);
  model += 2 * 4 * M_PI * r_end * r_end * (3 - 4 * std::log(2.0));
  const double sphere = 4.0 / 3 * M_PI * radius * radius * radius;
  std::printf("sphere loft: %.0f mm^3, frustum model %.0f (%+.2f %%), sphere %.0f (%+.2f %%)\n",
              lofted, model, 100 * (lofted / model - 1), sphere, 100 * (lofted / sphere - 1));
  EXPECT_NEAR(lofted / model, 1, 0.005);
  EXPECT_NEAR(lofted / sphere, 1, 0.025);
  // Nothing beyond the caps.
  EXPECT_EQ(CountInLayer(v, 0, 1), 0);
  EXPECT_EQ(CountInLayer(v, v.nz() - 1, 1), 0);
}

// A "Y": one disc on one plate, two separate discs on the next. Going from
// the single disc the slices are one blob, then two, never none and never
// three; the same holds for a merge (the plates swapped).
TEST(LoftTest, SplitsAndMergesBetweenPlates) {
  for (const bool split : {true, false}) {
    SCOPED_TRACE(split ? "split" : "merge");
    const auto one = [](double x, double y) { return x * x + y * y <= 36; };
    const auto two = [](double x, double y) {
      return (x - 9) * (x - 9) + y * y <= 25 || (x + 9) * (x + 9) + y * y <= 25;
    };
    const PlateStack stack = MakeStack(0.25, 160, 96, {0, 8}, [&](int p, double x, double y) {
      return uint16_t((p == 0) == split ? one(x, y) : two(x, y));
    });
    LoftOptions options;
    options.voxel_size_mm = 0.25;
    LabelVolume v;
    ASSERT_TRUE(LoftPlates(stack, options, &v).ok());
    const int k0 = LayerOf(v, 0), k1 = LayerOf(v, 8);
    ASSERT_EQ(k1 - k0, 32);
    const int64_t end_area = std::min(CountInLayer(v, k0, 1), CountInLayer(v, k1, 1));
    std::vector<int> components;
    for (int k = k0; k <= k1; ++k) {
      components.push_back(CountComponents(v, k, 1));
      EXPECT_GT(CountInLayer(v, k, 1), end_area / 2) << "layer " << k;
    }
    if (!split) std::reverse(components.begin(), components.end());
    EXPECT_EQ(components.front(), 1);
    EXPECT_EQ(components.back(), 2);
    for (size_t s = 1; s < components.size(); ++s) {
      EXPECT_GE(components[s], components[s - 1]) << s;
      EXPECT_LE(components[s], 2) << s;
    }
    int first_two = 0;
    while (components[first_two] == 1) ++first_two;
    std::printf("%s: one blob for %d of 33 slices, then two\n", split ? "split" : "merge",
                first_two);
  }
}

// A structure on one plate only tapers to a point midway to the next.
TEST(LoftTest, StructureEndingBetweenPlatesTapersToMidway) {
  const PlateStack stack = MakeStack(0.25, 80, 80, {0, 8, 16}, [](int p, double x, double y) {
    return uint16_t(p == 1 && x * x + y * y <= 36 ? 1 : 0);
  });
  LoftOptions options;
  options.voxel_size_mm = 0.25;
  LabelVolume v;
  ASSERT_TRUE(LoftPlates(stack, options, &v).ok());
  int lowest = v.nz(), highest = -1;
  for (int k = 0; k < v.nz(); ++k) {
    if (CountInLayer(v, k, 1) == 0) continue;
    lowest = std::min(lowest, k);
    highest = std::max(highest, k);
  }
  const double z_low = v.VoxelCentreMm(0, 0, lowest).z();
  const double z_high = v.VoxelCentreMm(0, 0, highest).z();
  EXPECT_NEAR(z_low, 4, 0.5);
  EXPECT_NEAR(z_high, 12, 0.5);
  // Halfway to the end, the radius has dropped to 6 (1 - 2t)/(1 - t) = 4 mm.
  const double area = CountInLayer(v, LayerOf(v, 10), 1) * 0.0625;
  EXPECT_NEAR(area, M_PI * 16, M_PI * 16 * 0.08);
}

// Uniform points in a box, from a fixed seed (portable: 53 bits of the
// generator per coordinate).
class Points {
 public:
  Points(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) : lo_(lo), hi_(hi) {}
  Eigen::Vector3d Next() {
    Eigen::Vector3d x;
    for (int a = 0; a < 3; ++a) {
      x[a] = lo_[a] + (hi_[a] - lo_[a]) * static_cast<double>(random_() >> 11) * 0x1.0p-53;
    }
    return x;
  }

 private:
  Eigen::Vector3d lo_, hi_;
  std::mt19937_64 random_{20240611};
};

// The continuous loft of a vertical cylinder (the same disc on every plate,
// 0.1 mm pixels) between the 1 mm voxel centres: its label follows the
// circle, where the nearest voxel's follows the staircase. Within 1 mm of
// the surface the field is misclassified at a small fraction of the points
// the nearest voxel is, and its signed distance is the distance to the
// circle to within a pixel inside it (outside, the field ends with the
// disc's box, a pixel beyond it).
TEST(LoftFieldTest, LabelBetweenVoxelCentresFollowsTheShape) {
  const double radius = 7.3;
  const PlateStack stack = MakeStack(
      0.1, 200, 200, {-6, -3, 0, 3, 6},
      [&](int, double x, double y) { return uint16_t(x * x + y * y <= radius * radius ? 2 : 0); });
  LoftField field;
  ASSERT_TRUE(field.Build(stack, LoftOptions()).ok());
  ASSERT_EQ(field.labels(), std::vector<int>{2});
  Points points(Eigen::Vector3d(-9, -9, -5), Eigen::Vector3d(9, 9, 5));
  int64_t near = 0, wrong_field = 0, wrong_voxel = 0;
  double worst_distance = 0;
  while (near < 100000) {
    const Eigen::Vector3d x = points.Next();
    const double rho = x.head<2>().norm();
    if (std::abs(rho - radius) > 1) continue;
    ++near;
    const int inside = rho < radius ? 2 : 0;
    wrong_field += field.Label(x) != inside;
    wrong_voxel += field.volume().SampleNearest(x) != inside;
    const double d = field.SignedDistance(2, x);
    if (rho < radius) worst_distance = std::max(worst_distance, std::abs(d - (rho - radius)));
    ASSERT_EQ(field.SignedDistance(LoftField::kForeground, x), d);
    ASSERT_EQ(field.SignedDistance(0, x), -d);
  }
  std::printf(
      "cylinder, points within 1 mm of its surface: %.3f %% misclassified by the field, %.3f %% "
      "by the nearest voxel; signed distance within %.3f mm of the circle's\n",
      100.0 * wrong_field / near, 100.0 * wrong_voxel / near, worst_distance);
  EXPECT_LT(wrong_field, wrong_voxel / 10);
  EXPECT_LT(worst_distance, 0.1);
  // A label on no plate, and points beyond the stack, are outside.
  EXPECT_EQ(field.SignedDistance(7, Eigen::Vector3d::Zero()),
            std::numeric_limits<double>::infinity());
  EXPECT_EQ(field.Label(Eigen::Vector3d(0, 0, 20)), 0);
  EXPECT_EQ(field.Label(Eigen::Vector3d(15, 0, 0)), 0);
  EXPECT_EQ(field.Label(Eigen::Vector3d(0, 0, 0)), 2);
}

class LoftAtlasTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    SyntheticAtlasOptions options;
    options.voxel_size_mm = 1.5;
    atlas_ = std::make_unique<LabelVolume>(MakeSyntheticAtlas(options));
    root_ = fs::temp_directory_path() / ("pba_loft_test_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
    stack_ = std::make_unique<PlateStack>();
    status_ = WritePlates(*atlas_, ColourTable::Builtin(), PlateOptions(), root_ / "stack");
    if (status_.ok()) status_ = ReadPlates(root_ / "stack", stack_.get());
  }
  static void TearDownTestSuite() {
    fs::remove_all(root_);
    atlas_.reset();
    stack_.reset();
  }
  static std::unique_ptr<LabelVolume> atlas_;
  static std::unique_ptr<PlateStack> stack_;
  static fs::path root_;
  static Status status_;
};
std::unique_ptr<LabelVolume> LoftAtlasTest::atlas_;
std::unique_ptr<PlateStack> LoftAtlasTest::stack_;
fs::path LoftAtlasTest::root_;
Status LoftAtlasTest::status_;

// At each plate's height (a voxel layer: 1 mm voxels, integer plate
// heights) the loft reproduces the plate. The 1 mm voxel centres sit on
// the corners of 0.5 mm pixels, so a voxel covers 2 x 2 pixels and its
// "nearest" pixel is a tie-break. Checks: a voxel whose pixels within one
// voxel (1 mm) all carry one label has that label (no exception); a voxel
// takes one of the labels of the pixels it covers, allowing 0.1 % of the
// brain voxels of those layers (thin structures, where the bilinear field
// of a neighbour could win; none in the synthetic atlas); the
// nearest-pixel mismatch is printed.
TEST_F(LoftAtlasTest, PlatesAreReproducedAtTheirHeights) {
  ASSERT_TRUE(status_.ok()) << status_.ToString();
  const PlateStack& s = *stack_;
  LoftOptions options;
  options.voxel_size_mm = 1.0;
  LabelVolume v;
  ASSERT_TRUE(LoftPlates(s, options, &v).ok());
  const auto pixel = [&](int p, int c, int r) {
    return c >= 0 && r >= 0 && c < s.width && r < s.height ? s.at(p, c, r) : uint16_t{0};
  };
  int64_t interior = 0, uncovered = 0, nearest_mismatch = 0, brain = 0;
  const double reach = options.voxel_size_mm / s.pixel_size_mm;
  for (int p = 0; p < s.num_plates(); ++p) {
    const int k = LayerOf(v, s.z_mm[p]);
    ASSERT_NEAR(v.VoxelCentreMm(0, 0, k).z(), s.z_mm[p], 1e-9);
    for (int j = 0; j < v.ny(); ++j) {
      for (int i = 0; i < v.nx(); ++i) {
        const Eigen::Vector3d x = v.VoxelCentreMm(i, j, k);
        const double c = (x.x() - s.origin_mm.x()) / s.pixel_size_mm;
        const double r = (s.origin_mm.y() - x.y()) / s.pixel_size_mm;
        const uint16_t nearest = pixel(p, std::floor(c + 0.5), std::floor(r + 0.5));
        const uint16_t lofted = v.at(i, j, k);
        brain += nearest != 0 || lofted != 0;
        nearest_mismatch += nearest != lofted;
        bool covered = false, uniform = true;
        for (int rr = std::ceil(r - reach); rr <= std::floor(r + reach); ++rr) {
          for (int cc = std::ceil(c - reach); cc <= std::floor(c + reach); ++cc) {
            const uint16_t l = pixel(p, cc, rr);
            uniform &= l == nearest;
            const bool inside_voxel =
                std::abs(cc - c) < 0.5 * reach && std::abs(rr - r) < 0.5 * reach;
            covered |= inside_voxel && l == lofted;
          }
        }
        interior += uniform && lofted != nearest;
        uncovered += !covered;
      }
    }
  }
  std::printf(
      "plates reproduced (%lld brain voxels in 27 layers): %.2f %% differ from the "
      "nearest pixel, %.2f %% from every pixel they cover, %lld away from boundaries\n",
      static_cast<long long>(brain), 100.0 * nearest_mismatch / brain, 100.0 * uncovered / brain,
      static_cast<long long>(interior));
  EXPECT_EQ(interior, 0);
  EXPECT_LE(uncovered, 0.001 * brain);
}

// Atlas (1.5 mm) -> 27 plates -> loft (1.5 mm), compared with the atlas on
// its own grid. Dice bound 0.8 for the big structures (white matter,
// putamen, the thalamus nuclei together, ventricles): their sections change
// little over the 3-5 mm between plates; small or thin structures (fornix,
// nuclei of a few mm) are only printed.
TEST_F(LoftAtlasTest, RoundTripThroughPlatesKeepsTheStructures) {
  ASSERT_TRUE(status_.ok()) << status_.ToString();
  const auto start = std::chrono::steady_clock::now();
  LoftOptions options;
  options.voxel_size_mm = 1.5;
  LabelVolume loft;
  ASSERT_TRUE(LoftPlates(*stack_, options, &loft).ok());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const LabelVolume& a = *atlas_;
  EXPECT_NEAR((loft.origin_mm() - a.origin_mm()).head<2>().norm(), 0, 1e-6);
  // Overlap counts over the atlas grid, the loft sampled at its voxels.
  std::vector<int64_t> in_atlas(65536, 0), in_loft(65536, 0), both(65536, 0);
  std::vector<uint16_t> sampled(a.num_voxels());
  for (int k = 0; k < a.nz(); ++k) {
    for (int j = 0; j < a.ny(); ++j) {
      for (int i = 0; i < a.nx(); ++i) {
        const uint16_t x = a.at(i, j, k), y = loft.SampleNearest(a.VoxelCentreMm(i, j, k));
        sampled[a.Index(i, j, k)] = y;
        ++in_atlas[x];
        ++in_loft[y];
        both[x] += x == y;
      }
    }
  }
  const auto dice = [&](const std::vector<uint16_t>& group) {
    std::vector<char> g(65536, 0);
    for (uint16_t l : group) g[l] = 1;
    int64_t na = 0, nl = 0, nb = 0;
    for (int64_t v = 0; v < a.num_voxels(); ++v) {
      const bool x = g[a.labels()[v]], y = g[sampled[v]];
      na += x;
      nl += y;
      nb += x && y;
    }
    return na + nl > 0 ? 2.0 * nb / (na + nl) : 1.0;
  };
  const double voxel = a.voxel_volume_mm3();
  std::printf("%-3s %-34s %10s %10s %8s %6s\n", "id", "label", "atlas mm3", "loft mm3", "vol %",
              "Dice");
  double dice_sum = 0, worst = 2;
  int labels = 0;
  std::string worst_name;
  for (const ColourEntry& e : ColourTable::Builtin().entries()) {
    const double d = dice({e.label});
    std::printf(
        "%-3d %-34s %10.0f %10.0f %+8.1f %6.3f\n", e.label, e.name.c_str(),
        in_atlas[e.label] * voxel, in_loft[e.label] * voxel,
        100.0 * (in_loft[e.label] - in_atlas[e.label]) / std::max<int64_t>(1, in_atlas[e.label]),
        d);
    if (in_atlas[e.label] == 0) continue;
    ++labels;
    dice_sum += d;
    if (d < worst) {
      worst = d;
      worst_name = e.name;
    }
  }
  std::vector<uint16_t> thalamus;
  for (int l = kThalamusAnterior; l <= kThalamusVentralPosteromedial; ++l) thalamus.push_back(l);
  const double d_wm = dice({kWhiteMatter}), d_put = dice({kPutamen});
  const double d_thal = dice(thalamus), d_vent = dice({kVentricles});
  std::printf(
      "loft round trip: %d labels, mean Dice %.3f, worst %s %.3f; white matter %.3f, "
      "putamen %.3f, thalamus %.3f, ventricles %.3f; loft %.2f s\n",
      labels, dice_sum / labels, worst_name.c_str(), worst, d_wm, d_put, d_thal, d_vent, seconds);
  EXPECT_GT(d_wm, 0.8);
  EXPECT_GT(d_put, 0.8);
  EXPECT_GT(d_thal, 0.8);
  EXPECT_GT(d_vent, 0.8);
  // Every label of the plates is in the loft.
  const std::vector<int64_t> lofted = CountLabels(loft);
  std::vector<char> on_plates(65536, 0);
  for (const auto& plate : stack_->labels) {
    for (uint16_t l : plate) on_plates[l] = 1;
  }
  for (int l = 1; l < 65536; ++l) {
    if (on_plates[l]) {
      EXPECT_GT(lofted[l], 0) << "label " << l;
    }
  }
}

// The continuous field is the voxelisation's rule: at every voxel centre
// of the synthetic atlas's loft, at 1 and 1.5 mm, Label gives the voxel's
// label, and so does the rule over all labels (on every voxel at 1.5 mm).
TEST_F(LoftAtlasTest, FieldEqualsTheVoxelisationAtVoxelCentres) {
  ASSERT_TRUE(status_.ok()) << status_.ToString();
  for (const double voxel : {1.0, 1.5}) {
    SCOPED_TRACE(voxel);
    LoftOptions options;
    options.voxel_size_mm = voxel;
    LoftField field;
    ASSERT_TRUE(field.Build(*stack_, options).ok());
    LabelVolume lofted;
    ASSERT_TRUE(LoftPlates(*stack_, options, &lofted).ok());
    const LabelVolume& v = field.volume();
    ASSERT_EQ(v.dims(), lofted.dims());
    ASSERT_EQ(v.labels(), lofted.labels());
    int64_t differ = 0, differ_all = 0, brain = 0;
    for (int k = 0; k < v.nz(); ++k) {
      for (int j = 0; j < v.ny(); ++j) {
        for (int i = 0; i < v.nx(); ++i) {
          const Eigen::Vector3d x = v.VoxelCentreMm(i, j, k);
          brain += v.at(i, j, k) != 0;
          differ += field.Label(x) != v.at(i, j, k);
          if (voxel == 1.5) differ_all += field.LabelOverAllLabels(x) != v.at(i, j, k);
        }
      }
    }
    std::printf("%g mm: %lld voxels (%lld brain), %lld differ; fields %.1f MB\n", voxel,
                static_cast<long long>(v.num_voxels()), static_cast<long long>(brain),
                static_cast<long long>(differ), field.field_bytes() / 1e6);
    EXPECT_EQ(differ, 0);
    EXPECT_EQ(differ_all, 0);
  }
}

// Between voxel centres Label evaluates only the labels of the eight
// voxels around the point: the same as the rule over every label but where
// a label wins between those centres and at none of them. Counted at
// random points of the brain's box; the time of each is printed.
TEST_F(LoftAtlasTest, LabelOfNearbyVoxelsAgreesWithAllLabels) {
  ASSERT_TRUE(status_.ok()) << status_.ToString();
  LoftField field;
  ASSERT_TRUE(field.Build(*stack_, LoftOptions()).ok());
  const LabelVolume& v = field.volume();
  const Eigen::Vector3d lo = v.origin_mm();
  const Eigen::Vector3d hi = v.VoxelCentreMm(v.nx() - 1, v.ny() - 1, v.nz() - 1);
  constexpr int kPoints = 1000000;
  std::vector<Eigen::Vector3d> x;
  Points points(lo, hi);
  for (int n = 0; n < kPoints; ++n) x.push_back(points.Next());
  std::vector<int> fast(kPoints), all(kPoints);
  const auto time = [&](const auto& label, std::vector<int>* out) {
    const auto start = std::chrono::steady_clock::now();
    for (int n = 0; n < kPoints; ++n) (*out)[n] = label(x[n]);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() /
           kPoints;
  };
  const double t_fast = time([&](const Eigen::Vector3d& p) { return field.Label(p); }, &fast);
  const double t_all =
      time([&](const Eigen::Vector3d& p) { return field.LabelOverAllLabels(p); }, &all);
  int64_t brain = 0, differ = 0;
  for (int n = 0; n < kPoints; ++n) {
    brain += all[n] != 0;
    differ += fast[n] != all[n];
  }
  std::printf(
      "%lld of %lld random points in the brain differ from the rule over all %zu labels "
      "(%.4f %%); %.0f ns a point, %.0f ns over all labels\n",
      static_cast<long long>(differ), static_cast<long long>(brain), field.labels().size(),
      100.0 * differ / brain, 1e9 * t_fast, 1e9 * t_all);
  EXPECT_LE(differ, brain / 1000);
}

}  // namespace
}  // namespace pba
