// The shape of tetrahedra as the objective of mesh improvement
// (mesh/improve.h): the smallest dihedral angle of a tetrahedron, alone or
// with its aspect ratio (TetMeasure), their gradients with respect to a
// corner, and the non-smooth ascent of the measure's smallest value over
// the tetrahedra around a node as that node moves. Coordinates in any
// length unit (metres in the solver); angles in radians.
#pragma once

#include <Eigen/Core>
#include <array>
#include <numbers>
#include <vector>

namespace pba {

// The quality of a tetrahedron that is inverted or flat to rounding.
inline constexpr double kInvalidTet = -1;
inline constexpr double kPi = std::numbers::pi;

// Smallest of the six interior dihedral angles of the tetrahedron
// (p0, p1, p2, p3) [rad], the same measure as TetDihedralRangeDegrees
// (mesh/quality.h); kInvalidTet unless it is positively oriented with
// 6 V > 1e-12 l^3, l its longest edge.
double TetQuality(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                  const Eigen::Vector3d& p3);

// What mesh improvement raises, higher being better:
//   angle_scale == 0: the smallest dihedral angle theta [rad] (TetQuality);
//   angle_scale > 0:  min(1 / A, theta / angle_scale), with A the aspect
//                     ratio (TetAspectRatio in mesh/quality.h: 1 for a
//                     regular tetrahedron, growing without bound as it
//                     flattens into a sliver or a cap or stretches into a
//                     needle, which keeps good dihedral angles).
// With angle_scale = theta_t A_t (ImproveOptions), a tetrahedron reaches
// 1 / A_t exactly when A <= A_t and theta >= theta_t. kInvalidTet where
// TetQuality is.
struct TetMeasure {
  double angle_scale = 0;
  double operator()(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                    const Eigen::Vector3d& p3) const;

  // The measure of targets theta_t [degrees] and A_t (0: the angle alone).
  static TetMeasure ForTargets(double target_min_dihedral_deg, double target_aspect_ratio) {
    TetMeasure measure;
    if (target_aspect_ratio > 0) {
      measure.angle_scale =
          target_min_dihedral_deg * (3.14159265358979323846 / 180) * target_aspect_ratio;
    }
    return measure;
  }
};

// The reciprocal aspect ratio 1 / A of the tetrahedron (x, p[0], p[1], p[2]),
// positively oriented, and its gradient with respect to the corner x [per
// length]: with S = 6 V and L the mean squared edge length,
//   1 / A = sqrt(2) S / L^(3/2),
//   d S / d x = -(p[1] - p[0]) x (p[2] - p[0]),
//   d L / d x = (1/3) sum_i (x - p[i]).
void InverseAspectRatioAndGradient(const Eigen::Vector3d& x,
                                   const std::array<Eigen::Vector3d, 3>& p, double* value,
                                   Eigen::Vector3d* gradient);

// The six dihedral angles [rad] of the tetrahedron (x, p[0], p[1], p[2]),
// along its edges (0,1), (0,2), (0,3), (1,2), (1,3), (2,3), and their
// gradients with respect to the corner x [rad per length]. For the angle
// theta along edge (i, j) between the faces (i, j, k) and (i, j, l), with
// h_k the distance from corner k to the edge's line, m_k the unit normal of
// face (i, j, k) pointing away from l, and s_k the position of k's
// projection along the edge (0 at i, 1 at j):
//   d theta / d x_k = m_k / h_k,
//   d theta / d x_i = -((1 - s_k) m_k / h_k + (1 - s_l) m_l / h_l),
//   d theta / d x_j = -(s_k m_k / h_k + s_l m_l / h_l)
// (moving k away from the tetrahedron opens the angle at the rate 1 / h_k;
// the gradients sum to zero, as a rigid translation leaves the angle
// unchanged, and are normal to the edge, as sliding i along the edge's line
// does too).
void DihedralAnglesAndGradients(const Eigen::Vector3d& x, const std::array<Eigen::Vector3d, 3>& p,
                                std::array<double, 6>* angle,
                                std::array<Eigen::Vector3d, 6>* gradient);

// The smallest TetMeasure over the star of a node, the tetrahedra
// (x, p[0], p[1], p[2]) that share the corner x, each positively oriented
// for the right x, as a function of x.
class StarObjective {
 public:
  // `star` is borrowed and must outlive the objective.
  explicit StarObjective(const std::vector<std::array<Eigen::Vector3d, 3>>& star,
                         TetMeasure measure = {})
      : star_(star), measure_(measure) {}

  // The smallest measure over the star with the node at x (kInvalidTet if
  // a tetrahedron is inverted or flat). Gives up as soon
  // as one tetrahedron is at or below `bar`, returning that one's quality:
  // the value then only tells that x is no better than `bar`.
  double Value(const Eigen::Vector3d& x, double bar = kInvalidTet) const;

  // Non-smooth steepest ascent from *x, where the value is `value` > 0
  // (Freitag & Ollivier-Gooch, IJNME 40 (1997) 3979-4002) over the terms
  // of the measure (the six angles of each tetrahedron, scaled by
  // 1 / angle_scale when it is not 0, and then its 1 / A too): the
  // direction is the shortest vector in the convex hull of the gradients of
  // the active terms (those within 1e-3 of the smallest), along which all of
  // them grow; the step goes to where the linearised growth of the active
  // terms meets the first inactive one (of the tetrahedra within 0.35 of
  // the smallest: 20 degrees), no further than half the shortest edge at x,
  // and is halved, up to 8 times, until the value grows. At most
  // `max_steps` steps; a step gaining less than 1e-4 ends the ascent.
  // Returns the value at the new *x, at least `value`.
  double Ascend(Eigen::Vector3d* x, double value, int max_steps = 10) const;

 private:
  const std::vector<std::array<Eigen::Vector3d, 3>>& star_;
  TetMeasure measure_;
};

}  // namespace pba
