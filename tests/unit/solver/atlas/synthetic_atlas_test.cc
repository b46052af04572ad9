#include "atlas/synthetic_atlas.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>

#include "atlas/colour_table.h"

namespace pba {
namespace {

using V3 = Eigen::Vector3d;

// 1.5 mm voxels keep the suite fast; the smallest structures (mamillary and
// geniculate bodies, about 2.5 mm semi-axes) still get dozens of voxels.
constexpr double kVoxelMm = 1.5;
// Every label must cover at least this many voxels (both hemispheres) at
// kVoxelMm: a sphere of radius 2.5 mm is about 19 voxels per side.
constexpr int64_t kMinVoxels = 20;

class SyntheticAtlasTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    SyntheticAtlasOptions options;
    options.voxel_size_mm = kVoxelMm;
    atlas_ = std::make_unique<LabelVolume>(MakeSyntheticAtlas(options));
  }
  static void TearDownTestSuite() { atlas_.reset(); }
  static const LabelVolume& atlas() { return *atlas_; }

  // Centroid of the left-hemisphere part (x < 0) of a structure.
  static LabelStats Left(const std::vector<uint16_t>& labels) {
    return ComputeLabelStats(atlas(), labels, [](const V3& p) { return p.x() < 0; });
  }

  static std::unique_ptr<LabelVolume> atlas_;
};
std::unique_ptr<LabelVolume> SyntheticAtlasTest::atlas_;

std::vector<uint16_t> ThalamicNuclei() {
  std::vector<uint16_t> labels;
  for (int l = kThalamusAnterior; l <= kThalamusVentralPosteromedial; ++l) labels.push_back(l);
  return labels;
}

TEST_F(SyntheticAtlasTest, GridIsCentredOnTheMidline) {
  const LabelVolume& v = atlas();
  EXPECT_EQ(v.nx() % 2, 1);
  EXPECT_NEAR(v.VoxelCentreMm((v.nx() - 1) / 2, 0, 0).x(), 0.0, 1e-12);
  EXPECT_EQ(v.spacing_mm(), V3::Constant(kVoxelMm));
}

TEST_F(SyntheticAtlasTest, EveryLabelIsPaintedWithANonTrivialVolume) {
  const std::vector<int64_t> counts = CountLabels(atlas());
  const ColourTable& table = ColourTable::Builtin();
  int64_t smallest = INT64_MAX;
  std::string smallest_name;
  for (const ColourEntry& e : table.entries()) {
    EXPECT_GE(counts[e.label], kMinVoxels) << e.name;
    if (counts[e.label] < smallest) {
      smallest = counts[e.label];
      smallest_name = e.name;
    }
  }
  for (size_t l = kNumAtlasLabels + 1; l < counts.size(); ++l) {
    ASSERT_EQ(counts[l], 0) << "label " << l << " is not in the colour table";
  }
  std::printf("voxels at %.1f mm: brain %lld, white matter %lld, smallest %s %lld\n", kVoxelMm,
              static_cast<long long>(atlas().num_voxels() - counts[0]),
              static_cast<long long>(counts[kWhiteMatter]), smallest_name.c_str(),
              static_cast<long long>(smallest));
  for (const ColourEntry& e : table.entries()) {
    std::printf("  %2d %-34s %7lld\n", e.label, e.name.c_str(),
                static_cast<long long>(counts[e.label]));
  }
}

TEST_F(SyntheticAtlasTest, EverythingLiesInsideTheWholeBrainEllipsoid) {
  const LabelVolume& v = atlas();
  int64_t outside = 0, inside = 0;
  for (int k = 0; k < v.nz(); ++k) {
    for (int j = 0; j < v.ny(); ++j) {
      for (int i = 0; i < v.nx(); ++i) {
        if (v.at(i, j, k) == kBackground) continue;
        const V3 p = v.VoxelCentreMm(i, j, k);
        const double rho2 = std::pow((p.x() - 2) / 67, 2) + std::pow((p.y() + 29) / 93, 2) +
                            std::pow((p.z() - 5) / 59, 2);
        (rho2 <= 1 ? inside : outside)++;
      }
    }
  }
  EXPECT_EQ(outside, 0);
  // And it fills most of it: the ellipsoid holds 4/3 pi 67 93 59 mm^3.
  const double ellipsoid_voxels = 4.0 / 3 * M_PI * 67 * 93 * 59 / std::pow(kVoxelMm, 3);
  EXPECT_GT(inside, 0.9 * ellipsoid_voxels);
}

TEST_F(SyntheticAtlasTest, HemispheresMirrorInTheMidline) {
  const LabelVolume& v = atlas();
  int64_t compared = 0;
  for (int k = 0; k < v.nz(); ++k) {
    for (int j = 0; j < v.ny(); ++j) {
      for (int i = 0; i < v.nx() / 2; ++i) {
        ASSERT_EQ(v.at(i, j, k), v.at(v.nx() - 1 - i, j, k)) << i << " " << j << " " << k;
        if (v.at(i, j, k) != kBackground) ++compared;
      }
    }
  }
  EXPECT_GT(compared, 100000);
}

// Tolerance of the centroids: 5 mm, about three voxels. The reference
// centroids are of moment ellipsoids fitted to irregular shapes, and the
// synthetic structures are clipped where a later one overwrites them (the
// pallidum bites into the putamen, the third ventricle into the thalamus).
// The caudate gets 8 mm: its tail was placed to follow the ventricle, which
// drags its centroid back and laterally.
struct CentroidCase {
  const char* name;
  std::vector<uint16_t> labels;
  V3 expected;
  double tolerance_mm;
};

TEST_F(SyntheticAtlasTest, CentroidsMatchTheReferenceAnatomy) {
  const std::vector<CentroidCase> cases = {
      {"putamen", {kPutamen}, V3(-24, -5, 6), 5},
      {"caudate", {kNucleusCaudatus}, V3(-13, -2, 16), 8},
      {"thalamus", ThalamicNuclei(), V3(-9, -25, 4), 5},
      {"globus pallidus", {kGlobusPallidusLateralis, kGlobusPallidusMedialis}, V3(-18, -10, 2), 5},
      {"hippocampus", {kHippocampus}, V3(-21, -25, -15), 5},
      {"nucleus accumbens", {kNucleusAccumbensSepti}, V3(-11, 7, 0), 5},
  };
  for (const CentroidCase& c : cases) {
    const LabelStats s = Left(c.labels);
    ASSERT_GT(s.voxel_count, 0) << c.name;
    const double off = (s.centroid_mm - c.expected).norm();
    std::printf("%-18s centroid (%6.1f %6.1f %6.1f), %.1f mm from the reference, %.0f mm^3\n",
                c.name, s.centroid_mm.x(), s.centroid_mm.y(), s.centroid_mm.z(), off, s.volume_mm3);
    EXPECT_LT(off, c.tolerance_mm) << c.name;
  }
}

// The lateral ventricle (left, away from the midline third ventricle and
// above the fourth) is C-shaped: its centroid is in the hollow of the C, and
// the chord from the frontal horn tip to the temporal horn tip leaves it.
TEST_F(SyntheticAtlasTest, LateralVentricleIsCShaped) {
  const LabelVolume& v = atlas();
  const auto lateral = [](const V3& p) { return p.x() < -4 && p.z() > -20; };
  const LabelStats s = ComputeLabelStats(v, {kVentricles}, lateral);
  ASSERT_GT(s.voxel_count, 0);
  EXPECT_NE(v.SampleNearest(s.centroid_mm), kVentricles);

  V3 front(0, -1e9, 0), low(0, 0, 1e9);
  for (int k = 0; k < v.nz(); ++k) {
    for (int j = 0; j < v.ny(); ++j) {
      for (int i = 0; i < v.nx(); ++i) {
        const V3 p = v.VoxelCentreMm(i, j, k);
        if (v.at(i, j, k) != kVentricles || !lateral(p)) continue;
        if (p.y() > front.y()) front = p;
        if (p.z() < low.z()) low = p;
      }
    }
  }
  EXPECT_GT(front.y(), 20);  // the frontal horn reaches in front of the AC
  EXPECT_LT(low.z(), -5);    // the temporal horn reaches below it
  int outside = 0;
  for (int s = 1; s < 100; ++s) {
    if (v.SampleNearest(front + (low - front) * s / 100.0) != kVentricles) ++outside;
  }
  EXPECT_GT(outside, 50);
}

// The corpus callosum arches over the ventricles: on the midline its
// centroid is not callosum, and callosum lies above it.
TEST_F(SyntheticAtlasTest, CorpusCallosumIsArched) {
  const LabelVolume& v = atlas();
  const LabelStats s =
      ComputeLabelStats(v, {kCorpusCallosum}, [](const V3& p) { return std::abs(p.x()) < 0.1; });
  ASSERT_GT(s.voxel_count, 0);
  EXPECT_NE(v.SampleNearest(s.centroid_mm), kCorpusCallosum);
  bool above = false;
  for (double dz = 1; dz < 30; dz += 0.5) {
    above |= v.SampleNearest(s.centroid_mm + V3(0, 0, dz)) == kCorpusCallosum;
  }
  EXPECT_TRUE(above);
  // 6-10 mm thick on the midline under the body (y = -5).
  std::array<int, 3> ijk;
  ASSERT_TRUE(v.NearestVoxel(V3(0, -5, 0), &ijk));
  int thickness = 0;
  for (int k = 0; k < v.nz(); ++k) thickness += v.at(ijk[0], ijk[1], k) == kCorpusCallosum;
  EXPECT_GE(thickness * kVoxelMm, 6 - kVoxelMm);
  EXPECT_LE(thickness * kVoxelMm, 10 + kVoxelMm);
}

// The thalamic nuclei fill the thalamus ellipsoid, except where a structure
// painted after them sits (third ventricle, hypothalamus, small nuclei), and
// do not leave it.
TEST_F(SyntheticAtlasTest, ThalamicNucleiPartitionTheThalamus) {
  const LabelVolume& v = atlas();
  const std::vector<uint16_t> nuclei = ThalamicNuclei();
  const std::set<uint16_t> nucleus_set(nuclei.begin(), nuclei.end());
  const std::set<uint16_t> painted_later = {kVentricles,
                                            kHypothalamusLat,
                                            kHypothalamusPol,
                                            kHypothalamusSo,
                                            kHypothalamusVm,
                                            kCorpusMamillare,
                                            kNucleusRuberTop,
                                            kNucleusRuberBottom,
                                            kNucleusSubthalamicus,
                                            kSubstantiaNigra,
                                            kCorpusGeniculatumLaterale,
                                            kCorpusGeniculatumMediale};
  std::map<uint16_t, int64_t> per_nucleus;
  int64_t in_ellipsoid = 0, thalamic = 0;
  for (int k = 0; k < v.nz(); ++k) {
    for (int j = 0; j < v.ny(); ++j) {
      for (int i = 0; i < v.nx(); ++i) {
        const V3 p = v.VoxelCentreMm(i, j, k);
        const uint16_t l = v.at(i, j, k);
        const bool inside = InsideSyntheticThalamus(p);
        if (nucleus_set.count(l)) {
          ASSERT_TRUE(inside) << p.transpose();
          ++per_nucleus[l];
        }
        if (!inside) continue;
        ++in_ellipsoid;
        if (nucleus_set.count(l)) {
          ++thalamic;
        } else {
          ASSERT_TRUE(painted_later.count(l)) << "label " << l << " at " << p.transpose();
        }
      }
    }
  }
  for (uint16_t l : nuclei) EXPECT_GE(per_nucleus[l], kMinVoxels) << l;
  // Both thalami: 2 x 4/3 pi 20 12 9 mm^3, minus what the midline cuts off.
  const double ellipsoid_voxels = 2 * 4.0 / 3 * M_PI * 20 * 12 * 9 / std::pow(kVoxelMm, 3);
  EXPECT_GT(in_ellipsoid, 0.8 * ellipsoid_voxels);
  EXPECT_GT(thalamic, 0.8 * in_ellipsoid);
}

TEST(SyntheticAtlasOptionsTest, ValidateNamesTheBadField) {
  SyntheticAtlasOptions options;
  EXPECT_TRUE(options.Validate().ok());
  options.voxel_size_mm = 0;
  EXPECT_EQ(options.Validate().field(), "voxel_size_mm");
  options = {};
  options.cortex_thickness_mm = 40;
  EXPECT_EQ(options.Validate().field(), "cortex_thickness_mm");
}

}  // namespace
}  // namespace pba
