#include "atlas/synthetic_atlas.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <numbers>
#include <vector>

#include "atlas/colour_table.h"
#include "core/format.h"

namespace pba {
namespace {

using V3 = Eigen::Vector3d;

// Step 1: the stated whole-brain ellipsoid [mm].
const V3 kBrainCentre(2, -29, 5);
const V3 kBrainSemiAxes(67, 93, 59);
constexpr double kFissureHalfWidth = 1.0;  // [mm]

// All shapes are written for the left hemisphere and evaluated at the
// mirror image q = (-|x|, y, z) of a point.
V3 LeftImage(const V3& p) { return V3(-std::abs(p.x()), p.y(), p.z()); }

// Normalised radius of q in the brain ellipsoid (1 on its surface).
double BrainRho(const V3& q) { return (q - kBrainCentre).cwiseQuotient(kBrainSemiAxes).norm(); }

// Approximate distance of q inside the ellipsoid surface: (1 - rho) over
// |grad rho|, first order in the distance and good near the surface.
double BrainDepth(const V3& q) {
  const double rho = BrainRho(q);
  if (rho < 0.5) return 1e9;
  const V3 grad =
      (q - kBrainCentre).cwiseQuotient(kBrainSemiAxes.cwiseProduct(kBrainSemiAxes)) / rho;
  return (1 - rho) / grad.norm();
}

struct Ellipsoid {
  V3 centre;
  V3 semi;                                             // along the columns of axes
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // orthonormal columns
  // Coordinates of q in units of the semi-axes.
  V3 Local(const V3& q) const { return (axes.transpose() * (q - centre)).cwiseQuotient(semi); }
  bool Contains(const V3& q) const { return Local(q).squaredNorm() <= 1; }
  double Reach() const { return semi.maxCoeff(); }
};

Ellipsoid AxisAligned(const V3& centre, const V3& semi) { return {centre, semi}; }

// The thalamus of step 12: long axis anterior, turned 15 degrees about z so
// the front end is medial (towards x = 0 from the left).
Ellipsoid Thalamus() {
  const double a = 15 * std::numbers::pi / 180;
  Eigen::Matrix3d axes;
  axes.col(0) = V3(std::sin(a), std::cos(a), 0);   // anterior
  axes.col(1) = V3(-std::cos(a), std::sin(a), 0);  // lateral (towards -x)
  axes.col(2) = V3(0, 0, 1);                       // superior
  return {V3(-9, -25, 4), V3(20, 12, 9), axes};
}

// A swept tube: centreline polyline with a radius per point, linear in
// between. Inside = distance to some segment <= radius interpolated at the
// foot point.
struct Tube {
  std::vector<V3> points;
  std::vector<double> radii;

  bool Contains(const V3& q) const {
    for (size_t s = 0; s + 1 < points.size(); ++s) {
      const V3 d = points[s + 1] - points[s];
      const double t = std::clamp((q - points[s]).dot(d) / d.squaredNorm(), 0.0, 1.0);
      const double r = radii[s] + t * (radii[s + 1] - radii[s]);
      if ((q - points[s] - t * d).squaredNorm() <= r * r) return true;
    }
    return false;
  }
};

// Catmull-Rom interpolation of the control points, `sub` pieces per span,
// so the swept tubes bend smoothly.
Tube Smooth(const std::vector<V3>& p, const std::vector<double>& r, int sub = 6) {
  Tube tube;
  const int n = static_cast<int>(p.size());
  for (int s = 0; s + 1 < n; ++s) {
    const V3 m0 = 0.5 * (p[s + 1] - p[std::max(s - 1, 0)]);
    const V3 m1 = 0.5 * (p[std::min(s + 2, n - 1)] - p[s]);
    for (int k = 0; k < sub; ++k) {
      const double t = static_cast<double>(k) / sub, t2 = t * t, t3 = t2 * t;
      tube.points.push_back((2 * t3 - 3 * t2 + 1) * p[s] + (t3 - 2 * t2 + t) * m0 +
                            (-2 * t3 + 3 * t2) * p[s + 1] + (t3 - t2) * m1);
      tube.radii.push_back(r[s] + t * (r[s + 1] - r[s]));
    }
  }
  tube.points.push_back(p.back());
  tube.radii.push_back(r.back());
  return tube;
}

void TubeBounds(const Tube& tube, V3* lo, V3* hi) {
  const double rmax = *std::max_element(tube.radii.begin(), tube.radii.end());
  *lo = V3::Constant(1e9);
  *hi = V3::Constant(-1e9);
  for (const V3& p : tube.points) {
    *lo = lo->cwiseMin(p - V3::Constant(rmax));
    *hi = hi->cwiseMax(p + V3::Constant(rmax));
  }
}

// Corpus callosum: a tube in the sagittal (y, z) plane, extruded to
// |x| <= kCallosumHalfWidth with its centreline lowered by kCallosumDroop
// per mm off the midline.
constexpr double kCallosumHalfWidth = 20;  // [mm]
constexpr double kCallosumDroop = 0.15;
Tube CallosumSagittal() {  // x = 0 in every point
  return Smooth({V3(0, 22, -2), V3(0, 31, 4), V3(0, 33, 13), V3(0, 26, 22), V3(0, 12, 27),
                 V3(0, -5, 28), V3(0, -22, 26), V3(0, -34, 21), V3(0, -40, 13), V3(0, -36, 7)},
                {2.5, 4, 5, 4, 3.5, 3.5, 3.5, 4, 5, 3});
}

// Lowest z of the interhemispheric fissure at each y: just above the
// callosum where it is, down to the base in front of it and to the
// tentorium level behind it.
double FissureFloor(const Tube& callosum, double y) {
  double floor = -1e9;
  for (size_t s = 0; s < callosum.points.size(); ++s) {
    const V3& c = callosum.points[s];
    if (std::abs(c.y() - y) <= 2) floor = std::max(floor, c.z() + callosum.radii[s] + 1);
  }
  if (floor > -1e9) return floor;
  return y > 0 ? -60.0 : -22.0;
}

struct Seed {
  AtlasLabel label;
  V3 point;
};

// Gyri of the cortical mantle, left hemisphere; nearest seed wins.
const std::vector<Seed>& CortexSeeds() {
  static const std::vector<Seed> seeds = {
      {kInferiorFrontalGyrus, V3(-52, 25, 2)},
      {kMiddleFrontalGyrus, V3(-36, 35, 35)},
      {kMedialFrontalGyrus, V3(-3, 30, 40)},
      {kMedialFrontalGyrus, V3(-3, 52, 15)},
      {kMiddleTemporalGyrus, V3(-64, -30, -6)},
      {kInferiorTemporalGyrus, V3(-54, -32, -30)},
      {kMiddleOccipitalGyrus, V3(-38, -100, 12)},
      {kInferiorOccipitalGyrus, V3(-30, -102, -14)},
      {kCuneus, V3(-3, -100, 18)},
      {kLingualGyrus, V3(-5, -95, -10)},
      // The rest of the mantle.
      {kCorticalAreas, V3(-20, 45, 50)},    // superior frontal
      {kCorticalAreas, V3(-40, -10, 52)},   // precentral
      {kCorticalAreas, V3(-40, -38, 55)},   // postcentral
      {kCorticalAreas, V3(-25, -72, 55)},   // superior parietal
      {kCorticalAreas, V3(-55, -58, 35)},   // inferior parietal
      {kCorticalAreas, V3(-62, -8, 12)},    // superior temporal
      {kCorticalAreas, V3(-50, 8, -22)},    // temporal pole
      {kCorticalAreas, V3(-25, 40, -20)},   // orbital
      {kCorticalAreas, V3(-3, -10, 45)},    // cingulate, paracentral
      {kCorticalAreas, V3(-3, -62, 45)},    // precuneus
      {kCorticalAreas, V3(-35, -55, -42)},  // fusiform, cerebellar
      {kCorticalAreas, V3(-8, -60, -50)},   // base
  };
  return seeds;
}

AtlasLabel NearestSeed(const std::vector<Seed>& seeds, const V3& q) {
  AtlasLabel best = kBackground;
  double best_d2 = 1e300;
  for (const Seed& s : seeds) {
    const double d2 = (q - s.point).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best = s.label;
    }
  }
  return best;
}

// Thalamic nuclei seeds in the thalamus' normalised frame (anterior,
// lateral, superior), each coordinate in units of the semi-axis.
const std::vector<Seed>& ThalamusSeeds() {
  static const std::vector<Seed> seeds = {
      {kThalamusAnterior, V3(0.75, 0.0, 0.5)},
      {kThalamusVentralAnterior, V3(0.45, 0.35, -0.3)},
      {kThalamusVentralLateral, V3(0.1, 0.5, -0.1)},
      {kThalamusVentralPosterolateral, V3(-0.25, 0.55, -0.4)},
      {kThalamusVentralPosteromedial, V3(-0.25, 0.1, -0.5)},
      {kThalamusLateralDorsal, V3(0.3, 0.4, 0.6)},
      {kThalamusLateralPosterior, V3(-0.3, 0.45, 0.5)},
      {kThalamusDorsomedial, V3(0.15, -0.45, 0.3)},
      {kThalamusCentromedianum, V3(-0.2, -0.2, -0.1)},
      {kThalamusPulvinar, V3(-0.75, 0.15, 0.1)},
      {kThalamusOthers, V3(0.3, -0.4, -0.6)},  // midline and intralaminar rest
  };
  return seeds;
}

const std::vector<Seed>& HypothalamusSeeds() {
  static const std::vector<Seed> seeds = {
      {kHypothalamusPol, V3(-3, -1, -5)},   // preoptic: front
      {kHypothalamusSo, V3(-6, -5, -10)},   // supraoptic: front, low, lateral
      {kHypothalamusVm, V3(-2, -11, -9)},   // ventromedial
      {kHypothalamusLat, V3(-7, -11, -5)},  // lateral area
  };
  return seeds;
}

// Paints shapes into the volume, left hemisphere and its mirror.
class Painter {
 public:
  explicit Painter(LabelVolume* volume) : v_(*volume) {}

  // For every brain voxel whose left image q lies in the box [lo, hi],
  // writes label_at(q) unless it is 0.
  void Paint(V3 lo, V3 hi, const std::function<uint16_t(const V3&)>& label_at) {
    hi.x() = std::min(hi.x(), 0.0);
    if (lo.x() > hi.x()) return;
    const auto range = [&](int axis, double a, double b, int* first, int* last) {
      const double o = v_.origin_mm()[axis], h = v_.spacing_mm()[axis];
      *first = std::max(0, static_cast<int>(std::ceil((a - o) / h)));
      *last = std::min(v_.dims()[axis] - 1, static_cast<int>(std::floor((b - o) / h)));
    };
    int i0, i1, i2, i3, j0, j1, k0, k1;
    range(0, lo.x(), hi.x(), &i0, &i1);
    range(0, -hi.x(), -lo.x(), &i2, &i3);
    i2 = std::max(i2, i1 + 1);  // the midline column once
    range(1, lo.y(), hi.y(), &j0, &j1);
    range(2, lo.z(), hi.z(), &k0, &k1);
    for (int k = k0; k <= k1; ++k) {
      for (int j = j0; j <= j1; ++j) {
        for (int pass = 0; pass < 2; ++pass) {
          const int a = pass == 0 ? i0 : i2, b = pass == 0 ? i1 : i3;
          for (int i = a; i <= b; ++i) {
            if (v_.at(i, j, k) == kBackground) continue;
            const uint16_t label = label_at(LeftImage(v_.VoxelCentreMm(i, j, k)));
            if (label != kBackground) v_.set(i, j, k, label);
          }
        }
      }
    }
  }

  void PaintEllipsoid(const Ellipsoid& e, uint16_t label) {
    const V3 r = V3::Constant(e.Reach());
    Paint(e.centre - r, e.centre + r, [&](const V3& q) { return e.Contains(q) ? label : 0; });
  }

  void PaintTube(const Tube& tube, uint16_t label) {
    V3 lo, hi;
    TubeBounds(tube, &lo, &hi);
    Paint(lo, hi, [&](const V3& q) { return tube.Contains(q) ? label : 0; });
  }

 private:
  LabelVolume& v_;
};

// Step 1: white matter, fissure, cortical mantle.
void PaintBrain(const SyntheticAtlasOptions& options, const Tube& callosum, LabelVolume* v) {
  std::vector<double> floor(v->ny());
  for (int j = 0; j < v->ny(); ++j)
    floor[j] = FissureFloor(callosum, v->VoxelCentreMm(0, j, 0).y());
  const double t = options.cortex_thickness_mm;
  for (int k = 0; k < v->nz(); ++k) {
    for (int j = 0; j < v->ny(); ++j) {
      for (int i = 0; i < v->nx(); ++i) {
        const V3 q = LeftImage(v->VoxelCentreMm(i, j, k));
        if (BrainRho(q) > 1) continue;
        const double off_midline = -q.x() - kFissureHalfWidth;  // < 0 in the fissure plane
        const double below_floor = floor[j] - q.z();            // > 0 under the fissure
        if (off_midline < 0 && below_floor <= 0) continue;      // the fissure itself
        const double fissure_depth = off_midline < 0    ? below_floor
                                     : below_floor <= 0 ? off_midline
                                                        : std::hypot(off_midline, below_floor);
        const double depth = std::min(BrainDepth(q), fissure_depth);
        v->set(i, j, k, depth < t ? NearestSeed(CortexSeeds(), q) : kWhiteMatter);
      }
    }
  }
}

}  // namespace

Status SyntheticAtlasOptions::Validate() const {
  if (!(voxel_size_mm >= 0.25 && voxel_size_mm <= 5)) {
    return Status::InvalidArgument("voxel_size_mm",
                                   Format("%g is outside [0.25, 5] mm", voxel_size_mm));
  }
  if (!(cortex_thickness_mm >= 1 && cortex_thickness_mm <= 15)) {
    return Status::InvalidArgument("cortex_thickness_mm",
                                   Format("%g is outside [1, 15] mm", cortex_thickness_mm));
  }
  return Status::Ok();
}

bool InsideSyntheticBrain(const Eigen::Vector3d& p_mm) { return BrainRho(LeftImage(p_mm)) <= 1; }

bool InsideSyntheticThalamus(const Eigen::Vector3d& p_mm) {
  return Thalamus().Contains(LeftImage(p_mm));
}

LabelVolume MakeSyntheticAtlas(const SyntheticAtlasOptions& options) {
  if (!options.Validate().ok()) std::abort();
  const double h = options.voxel_size_mm;
  // Brain extent plus a voxel: |x| <= 65, y in [-122, 64], z in [-54, 64].
  const int kx = static_cast<int>(std::ceil(66 / h));
  const int j_lo = static_cast<int>(std::floor(-123 / h)),
            j_hi = static_cast<int>(std::ceil(65 / h));
  const int k_lo = static_cast<int>(std::floor(-55 / h)),
            k_hi = static_cast<int>(std::ceil(65 / h));
  LabelVolume v({2 * kx + 1, j_hi - j_lo + 1, k_hi - k_lo + 1}, V3(-kx * h, j_lo * h, k_lo * h),
                V3::Constant(h));
  Painter painter(&v);
  const Tube callosum = CallosumSagittal();

  PaintBrain(options, callosum, &v);  // 1

  painter.PaintEllipsoid(AxisAligned(V3(-37, -4, 4), V3(2.5, 20, 14)), kInsula);  // 2

  const Tube hippocampus = Smooth(
      {V3(-21, -10, -20), V3(-24, -20, -17), V3(-23, -30, -12), V3(-20, -38, -6), V3(-17, -41, -2)},
      {5, 4.5, 4, 3.2, 2.5});
  painter.PaintTube(
      Smooth({V3(-18, -8, -27), V3(-20, -20, -25), V3(-19, -32, -19), V3(-15, -42, -11)},
             {4, 4, 3.5, 3}),
      kHippocampalGyrus);                        // 3
  painter.PaintTube(hippocampus, kHippocampus);  // 4

  painter.PaintEllipsoid(AxisAligned(V3(-24, -5, 6), V3(6, 23, 13)), kPutamen);  // 5
  const Ellipsoid pallidus = AxisAligned(V3(-18, -10, 2), V3(5, 15, 7));         // 6
  painter.Paint(pallidus.centre - V3::Constant(pallidus.Reach()),
                pallidus.centre + V3::Constant(pallidus.Reach()), [&](const V3& q) -> uint16_t {
                  if (!pallidus.Contains(q)) return kBackground;
                  return q.x() < -17.5 ? kGlobusPallidusLateralis : kGlobusPallidusMedialis;
                });

  painter.PaintEllipsoid(AxisAligned(V3(-13, 12, 12), V3(6, 11, 9)), kNucleusCaudatus);  // 7
  painter.PaintTube(
      Smooth({V3(-14, 6, 17), V3(-14, 2, 19), V3(-15, -14, 20), V3(-20, -30, 19), V3(-28, -40, 16),
              V3(-34, -44, 8), V3(-36, -38, -2), V3(-35, -28, -4), V3(-34, -20, -8)},
             {4.5, 4, 3, 2.5, 2.2, 2, 2, 1.8, 1.6}),
      kNucleusCaudatus);
  painter.PaintEllipsoid(AxisAligned(V3(-11, 7, 0), V3(6, 8, 4)), kNucleusAccumbensSepti);  // 8

  // 9: the callosum, a sagittal tube extruded laterally.
  {
    V3 lo, hi;
    TubeBounds(callosum, &lo, &hi);
    lo.x() = -kCallosumHalfWidth;
    lo.z() -= kCallosumDroop * kCallosumHalfWidth;
    painter.Paint(lo, hi, [&](const V3& q) -> uint16_t {
      if (-q.x() > kCallosumHalfWidth) return kBackground;
      const V3 sagittal(0, q.y(), q.z() + kCallosumDroop * -q.x());
      return callosum.Contains(sagittal) ? kCorpusCallosum : kBackground;
    });
  }

  // 10: lateral ventricle (main C and occipital horn), fourth ventricle.
  painter.PaintTube(
      Smooth({V3(-7, 28, 6), V3(-8, 16, 12), V3(-8, 0, 17), V3(-10, -16, 18), V3(-15, -32, 16),
              V3(-24, -42, 10), V3(-30, -38, 0), V3(-32, -28, -8), V3(-31, -17, -13)},
             {3, 4.5, 4.5, 4.5, 5, 6, 4.5, 3.5, 3}),
      kVentricles);
  painter.PaintTube(Smooth({V3(-24, -42, 10), V3(-22, -58, 7), V3(-18, -70, 5)}, {5.5, 4, 2.5}),
                    kVentricles);
  painter.PaintEllipsoid(AxisAligned(V3(0, -46, -35), V3(6, 8, 10)), kVentricles);

  // 11: fornix, hippocampal tail -> crus -> body -> column -> mamillary body.
  painter.PaintTube(
      Smooth({V3(-19, -40, -4), V3(-19, -40, 8), V3(-13, -35, 15), V3(-5, -24, 19), V3(-3, -10, 19),
              V3(-3, 0, 14), V3(-3, -2, 4), V3(-3, -6, -4), V3(-3, -11, -9)},
             std::vector<double>(9, 2.0)),
      kFornix);

  // 12: thalamus parcelled into its nuclei.
  {
    const Ellipsoid thalamus = Thalamus();
    const V3 r = V3::Constant(thalamus.Reach());
    painter.Paint(thalamus.centre - r, thalamus.centre + r, [&](const V3& q) -> uint16_t {
      const V3 local = thalamus.Local(q);
      return local.squaredNorm() <= 1 ? NearestSeed(ThalamusSeeds(), local) : kBackground;
    });
  }

  painter.PaintEllipsoid(AxisAligned(V3(0, -21, 3), V3(2.5, 19, 11)), kVentricles);  // 13

  // 14: hypothalamus and mamillary bodies.
  {
    const Ellipsoid hypothalamus = AxisAligned(V3(-4, -7, -7), V3(4, 8, 4.5));
    const V3 r = V3::Constant(hypothalamus.Reach());
    painter.Paint(hypothalamus.centre - r, hypothalamus.centre + r, [&](const V3& q) -> uint16_t {
      return hypothalamus.Contains(q) ? NearestSeed(HypothalamusSeeds(), q) : kBackground;
    });
  }
  painter.PaintEllipsoid(AxisAligned(V3(-3, -15, -12), V3(2.8, 2.8, 2.8)), kCorpusMamillare);

  // 15: small nuclei of the diencephalon and midbrain.
  painter.PaintEllipsoid(AxisAligned(V3(-11, -13, -5), V3(4, 5, 2.5)), kNucleusSubthalamicus);
  painter.PaintEllipsoid(AxisAligned(V3(-11, -19, -13), V3(3.5, 8, 2.5)), kSubstantiaNigra);
  {
    const Ellipsoid ruber = AxisAligned(V3(-5, -21, -9), V3(3.5, 4.5, 4));
    const V3 r = V3::Constant(ruber.Reach());
    painter.Paint(ruber.centre - r, ruber.centre + r, [&](const V3& q) -> uint16_t {
      if (!ruber.Contains(q)) return kBackground;
      return q.z() >= ruber.centre.z() ? kNucleusRuberTop : kNucleusRuberBottom;
    });
  }
  painter.PaintEllipsoid(AxisAligned(V3(-22, -25, -5), V3(3, 4, 2.5)), kCorpusGeniculatumLaterale);
  painter.PaintEllipsoid(AxisAligned(V3(-15, -26, -5), V3(2.5, 3, 2.5)), kCorpusGeniculatumMediale);
  // Its files say what it is, and it goes without a label table.
  v.set_description(kSyntheticAtlasNotice);
  return v;
}

}  // namespace pba
