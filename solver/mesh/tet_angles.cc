#include "mesh/tet_angles.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace pba {
namespace {

using Vec3 = Eigen::Vector3d;

// Corners (i, j) of each edge and the two others (k, l), edges in the order
// of DihedralAnglesAndGradients.
constexpr int kEdges[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2},
                              {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};

constexpr double kMinRelativeVolume = 1e-12;
// In the measure's units (radians for the angle alone; with the aspect
// ratio, a measure of about the same size: 1 / A_t is theta_t in radians
// near 15 degrees and A_t near 4):
// terms this close to the smallest count as active;
constexpr double kActive = 1e-3;
// tetrahedra whose measure is further than this above the star's (20
// degrees) are left out of the step's prediction, for speed; the line
// search still sees them;
constexpr double kNear = 0.35;
// a step that gains less than this ends the ascent (0.006 degrees).
constexpr double kConverged = 1e-4;

// The point of the convex hull of `g` nearest the origin, by Gilbert's
// algorithm (Frank-Wolfe with exact line search); `g` is not empty.
Vec3 ShortestInHull(const std::vector<Vec3>& g) {
  Vec3 d = *std::min_element(g.begin(), g.end(), [](const Vec3& a, const Vec3& b) {
    return a.squaredNorm() < b.squaredNorm();
  });
  for (int iteration = 0; iteration < 100; ++iteration) {
    const Vec3* vertex = &g.front();
    for (const Vec3& v : g) {
      if (v.dot(d) < vertex->dot(d)) vertex = &v;
    }
    const double gap = d.squaredNorm() - vertex->dot(d);
    if (gap <= 1e-10 * d.squaredNorm()) break;
    const Vec3 s = *vertex - d;
    d += std::clamp(-d.dot(s) / s.squaredNorm(), 0.0, 1.0) * s;
  }
  return d;
}

}  // namespace

double TetQuality(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) {
  const Vec3 e1 = p1 - p0, e2 = p2 - p0, e3 = p3 - p0;
  const double longest =
      std::max({e1.squaredNorm(), e2.squaredNorm(), e3.squaredNorm(), (p2 - p1).squaredNorm(),
                (p3 - p1).squaredNorm(), (p3 - p2).squaredNorm()});
  const double six_volume = e1.dot(e2.cross(e3));
  if (!(six_volume > kMinRelativeVolume * longest * std::sqrt(longest))) return kInvalidTet;
  // Outward area normals of the faces opposite corners 0..3; the angle along
  // the edge shared by faces k and l is pi minus the angle between their
  // normals (atan2: accurate near 0 and pi).
  const Vec3 n[4] = {(p2 - p1).cross(p3 - p1), e3.cross(e2), e1.cross(e3), e2.cross(e1)};
  // The smallest is found comparing the (cos, sin) pairs, scaled by the
  // areas, by their cross product (both lie in the upper half-plane), so
  // that only it goes through atan2.
  double sine = 0, cosine = -1;  // pi
  for (const auto& k : kEdges) {
    const Vec3& a = n[k[2]];
    const Vec3& b = n[k[3]];
    const double s = a.cross(b).norm(), c = -a.dot(b);
    if (c * sine - s * cosine > 0) {
      sine = s;
      cosine = c;
    }
  }
  return std::atan2(sine, cosine);
}

double TetMeasure::operator()(const Vec3& p0, const Vec3& p1, const Vec3& p2,
                              const Vec3& p3) const {
  const double angle = TetQuality(p0, p1, p2, p3);
  if (angle_scale == 0 || angle == kInvalidTet) return angle;
  const Vec3 e1 = p1 - p0, e2 = p2 - p0, e3 = p3 - p0;
  const double mean_squared =
      (e1.squaredNorm() + e2.squaredNorm() + e3.squaredNorm() + (p2 - p1).squaredNorm() +
       (p3 - p1).squaredNorm() + (p3 - p2).squaredNorm()) /
      6;
  const double inverse_aspect =
      std::sqrt(2.0) * e1.dot(e2.cross(e3)) / (mean_squared * std::sqrt(mean_squared));
  return std::min(inverse_aspect, angle / angle_scale);
}

void InverseAspectRatioAndGradient(const Vec3& x, const std::array<Vec3, 3>& p, double* value,
                                   Vec3* gradient) {
  const Vec3 n = (p[1] - p[0]).cross(p[2] - p[0]);
  const double six_volume = (p[0] - x).dot(n);
  const double mean_squared =
      ((p[0] - x).squaredNorm() + (p[1] - x).squaredNorm() + (p[2] - x).squaredNorm() +
       (p[1] - p[0]).squaredNorm() + (p[2] - p[0]).squaredNorm() + (p[2] - p[1]).squaredNorm()) /
      6;
  const double power = mean_squared * std::sqrt(mean_squared);  // L^(3/2)
  const Vec3 d_mean_squared = (3 * x - p[0] - p[1] - p[2]) / 3;
  *value = std::sqrt(2.0) * six_volume / power;
  *gradient =
      std::sqrt(2.0) * (-n / power - 1.5 * six_volume / (power * mean_squared) * d_mean_squared);
}

void DihedralAnglesAndGradients(const Vec3& x, const std::array<Vec3, 3>& p,
                                std::array<double, 6>* angle, std::array<Vec3, 6>* gradient) {
  const Vec3* corner[4] = {&x, &p[0], &p[1], &p[2]};
  for (int edge = 0; edge < 6; ++edge) {
    const int i = kEdges[edge][0], j = kEdges[edge][1];
    const int k = kEdges[edge][2], l = kEdges[edge][3];
    const Vec3 e = *corner[j] - *corner[i];
    const double length2 = e.squaredNorm();
    const Vec3 uk = *corner[k] - *corner[i], ul = *corner[l] - *corner[i];
    const double sk = uk.dot(e) / length2, sl = ul.dot(e) / length2;
    const Vec3 wk = uk - sk * e, wl = ul - sl * e;  // perpendiculars to the edge
    (*angle)[edge] = std::atan2(wk.cross(wl).norm(), wk.dot(wl));
    // The face normals, in the plane normal to the edge, away from the
    // other face.
    Vec3 mk = e.cross(wk).normalized(), ml = e.cross(wl).normalized();
    if (mk.dot(wl) > 0) mk = -mk;
    if (ml.dot(wk) > 0) ml = -ml;
    const Vec3 gk = mk / wk.norm(), gl = ml / wl.norm();
    Vec3 g;
    if (k == 0) {
      g = gk;
    } else if (l == 0) {
      g = gl;
    } else if (i == 0) {
      g = -((1 - sk) * gk + (1 - sl) * gl);
    } else {
      g = -(sk * gk + sl * gl);
    }
    (*gradient)[edge] = g;
  }
}

double StarObjective::Value(const Vec3& x, double bar) const {
  double smallest = kPi;
  for (const auto& p : star_) {
    smallest = std::min(smallest, measure_(x, p[0], p[1], p[2]));
    if (smallest <= bar) break;
  }
  return smallest;
}

double StarObjective::Ascend(Vec3* x, double value, int max_steps) const {
  if (!(value > 0) || star_.empty()) return value;
  double shortest = std::numeric_limits<double>::infinity();
  for (const auto& p : star_) {
    for (const Vec3& q : p) shortest = std::min(shortest, (q - *x).norm());
  }
  const double max_step = 0.5 * shortest;
  std::vector<double> angles;
  std::vector<Vec3> gradients, active;
  std::array<double, 6> a;
  std::array<Vec3, 6> g;
  const double scale = measure_.angle_scale > 0 ? 1 / measure_.angle_scale : 1;
  for (int step = 0; step < max_steps; ++step) {
    angles.clear();
    gradients.clear();
    for (const auto& p : star_) {
      if (measure_(*x, p[0], p[1], p[2]) > value + kNear) continue;
      DihedralAnglesAndGradients(*x, p, &a, &g);
      for (int i = 0; i < 6; ++i) {
        angles.push_back(scale * a[i]);
        gradients.push_back(scale * g[i]);
      }
      if (measure_.angle_scale > 0) {
        angles.emplace_back();
        gradients.emplace_back();
        InverseAspectRatioAndGradient(*x, p, &angles.back(), &gradients.back());
      }
    }
    const double smallest = *std::min_element(angles.begin(), angles.end());
    active.clear();
    for (std::size_t n = 0; n < angles.size(); ++n) {
      if (angles[n] < smallest + kActive) active.push_back(gradients[n]);
    }
    const Vec3 d = ShortestInHull(active);
    const double rate = d.squaredNorm();  // growth of each active angle per unit step
    if (!(rate > 0) || !std::isfinite(rate)) break;
    double alpha = max_step / std::sqrt(rate);
    for (std::size_t n = 0; n < angles.size(); ++n) {
      if (angles[n] < smallest + kActive) continue;
      const double closing = rate - gradients[n].dot(d);
      if (closing > 0) alpha = std::min(alpha, (angles[n] - smallest) / closing);
    }
    bool improved = false;
    for (int halving = 0; halving < 8 && !improved; ++halving, alpha /= 2) {
      const Vec3 trial = *x + alpha * d;
      const double q = Value(trial, value);
      if (q > value) {
        improved = true;
        const double gain = q - value;
        *x = trial;
        value = q;
        if (gain < kConverged) return value;
      }
    }
    if (!improved) break;
  }
  return value;
}

}  // namespace pba
