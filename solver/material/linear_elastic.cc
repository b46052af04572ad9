#include "material/linear_elastic.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

#include "core/number_format.h"
#include "material/hyperelastic.h"
#include "pba/scene.h"

namespace pba {
namespace {

// Voigt index -> tensor index pair, order xx yy zz yz xz xy.
constexpr int kVoigtPair[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};

// Below this sine of the angle between axis_1 and axis_2 the 1-2 plane is
// not defined to any useful precision.
constexpr double kMinAxisSine = 1e-6;

Eigen::Vector3d Vector(const std::array<double, 3>& v) { return {v[0], v[1], v[2]}; }

Status RequireAxis(const std::array<double, 3>& axis, const std::string& field) {
  const Eigen::Vector3d v = Vector(axis);
  if (!v.allFinite() || v.norm() == 0) {
    return Status::InvalidArgument(field,
                                   "must be a non-zero direction (x, y, z) of finite numbers");
  }
  return Status::Ok();
}

}  // namespace

Matrix6d IsotropicElasticity(double e, double nu) {
  const double lambda = e * nu / ((1 + nu) * (1 - 2 * nu));
  const double mu = e / (2 * (1 + nu));
  Matrix6d d = Matrix6d::Zero();
  d.topLeftCorner<3, 3>().setConstant(lambda);
  for (int i = 0; i < 3; ++i) {
    d(i, i) = lambda + 2 * mu;
    d(i + 3, i + 3) = mu;
  }
  return d;
}

Matrix6d IsotropicCompliance(double e, double nu) {
  Matrix6d c = Matrix6d::Zero();
  c.topLeftCorner<3, 3>().setConstant(-nu / e);
  for (int i = 0; i < 3; ++i) {
    c(i, i) = 1 / e;
    c(i + 3, i + 3) = 2 * (1 + nu) / e;
  }
  return c;
}

ElasticityField::ElasticityField(std::vector<Matrix6d> d, std::vector<Matrix6d> compliance,
                                 std::vector<int> of_element)
    : d_(std::move(d)), compliance_(std::move(compliance)), of_element_(std::move(of_element)) {
  bool valid = d_.size() == compliance_.size() && !d_.empty();
  for (int k : of_element_) valid = valid && k >= 0 && k < static_cast<int>(d_.size());
  if (!valid) {
    std::fprintf(stderr,
                 "ElasticityField: %zu matrices, %zu compliances, a material out of range\n",
                 d_.size(), compliance_.size());
    std::abort();
  }
}

ElasticityField ElasticityField::Uniform(const Matrix6d& d, int elements) {
  return ElasticityField({d}, {d.inverse()}, std::vector<int>(elements, 0));
}

Status OrthotropicElasticParams::Validate(const std::string& path) const {
  const double e[3] = {e1_pa, e2_pa, e3_pa};
  static const char* kModuli[3] = {".e1_pa", ".e2_pa", ".e3_pa"};
  for (int i = 0; i < 3; ++i) PBA_RETURN_IF_ERROR(RequirePositive(e[i], path + kModuli[i]));
  PBA_RETURN_IF_ERROR(RequirePositive(g12_pa, path + ".g12_pa"));
  PBA_RETURN_IF_ERROR(RequirePositive(g13_pa, path + ".g13_pa"));
  PBA_RETURN_IF_ERROR(RequirePositive(g23_pa, path + ".g23_pa"));
  // |nu_ij| < sqrt(E_i / E_j) keeps each 2 x 2 minor of the compliance
  // positive (Jones, Mechanics of Composite Materials, 2nd ed., sec. 2.4).
  struct Ratio {
    const char* name;
    double value;
    int i, j;
  };
  const Ratio ratios[3] = {{"nu12", nu12, 0, 1}, {"nu13", nu13, 0, 2}, {"nu23", nu23, 1, 2}};
  for (const Ratio& r : ratios) {
    const std::string field = path + "." + r.name;
    PBA_RETURN_IF_ERROR(RequireFinite(r.value, field));
    const double bound = std::sqrt(e[r.i] / e[r.j]);
    if (!(std::abs(r.value) < bound)) {
      return Status::InvalidArgument(
          field, std::string("must satisfy |") + r.name + "| < sqrt(E" + std::to_string(r.i + 1) +
                     " / E" + std::to_string(r.j + 1) + ") = " + ShortNumber(bound) +
                     " for a positive definite compliance, got " + ShortNumber(r.value));
    }
  }
  // The determinant of the normal block, scaled by E1 E2 E3, must be > 0 too
  // (same source); no single ratio is to blame, so the block is named.
  const double nu21 = nu12 * e2_pa / e1_pa, nu31 = nu13 * e3_pa / e1_pa,
               nu32 = nu23 * e3_pa / e2_pa;
  const double delta = 1 - nu12 * nu21 - nu23 * nu32 - nu31 * nu13 - 2 * nu21 * nu32 * nu13;
  if (!(delta > 0)) {
    return Status::InvalidArgument(
        path,
        "the Poisson's ratios make the compliance indefinite: 1 - nu12 nu21 - nu23 nu32 - "
        "nu31 nu13 - 2 nu21 nu32 nu13 = " +
            ShortNumber(delta) +
            " must be > 0 (nu_ji = nu_ij E_j / E_i); lower nu12, nu13 or nu23");
  }
  PBA_RETURN_IF_ERROR(RequireAxis(axis_1, path + ".axis_1"));
  PBA_RETURN_IF_ERROR(RequireAxis(axis_2, path + ".axis_2"));
  const Eigen::Vector3d a = Vector(axis_1), b = Vector(axis_2);
  if (!(a.cross(b).norm() > kMinAxisSine * a.norm() * b.norm())) {
    return Status::InvalidArgument(path + ".axis_2",
                                   "is parallel to axis_1, so it does not fix the 1-2 plane; give "
                                   "a direction in that plane");
  }
  return Status::Ok();
}

Matrix6d OrthotropicCompliance(const OrthotropicElasticParams& p) {
  Matrix6d s = Matrix6d::Zero();
  s(0, 0) = 1 / p.e1_pa;
  s(1, 1) = 1 / p.e2_pa;
  s(2, 2) = 1 / p.e3_pa;
  s(0, 1) = s(1, 0) = -p.nu12 / p.e1_pa;
  s(0, 2) = s(2, 0) = -p.nu13 / p.e1_pa;
  s(1, 2) = s(2, 1) = -p.nu23 / p.e2_pa;
  s(3, 3) = 1 / p.g23_pa;
  s(4, 4) = 1 / p.g13_pa;
  s(5, 5) = 1 / p.g12_pa;
  return s;
}

Matrix6d OrthotropicElasticity(const OrthotropicElasticParams& p) {
  const Matrix6d s = OrthotropicCompliance(p);
  Matrix6d d = Matrix6d::Zero();
  d.topLeftCorner<3, 3>() = s.topLeftCorner<3, 3>().inverse();
  for (int i = 3; i < 6; ++i) d(i, i) = 1 / s(i, i);
  return d;
}

Eigen::Matrix3d MaterialFrame(const std::array<double, 3>& axis_1,
                              const std::array<double, 3>& axis_2) {
  const Eigen::Vector3d a = Vector(axis_1).normalized();
  const Eigen::Vector3d v = Vector(axis_2);
  const Eigen::Vector3d b = (v - a.dot(v) * a).normalized();
  Eigen::Matrix3d q;
  q << a, b, a.cross(b);
  return q;
}

Matrix6d StressRotation(const Eigen::Matrix3d& q) {
  Matrix6d m;
  for (int row = 0; row < 6; ++row) {
    const int i = kVoigtPair[row][0], j = kVoigtPair[row][1];
    for (int col = 0; col < 6; ++col) {
      const int k = kVoigtPair[col][0], l = kVoigtPair[col][1];
      // A shear column stands for both sigma_kl and sigma_lk.
      m(row, col) = k == l ? q(i, k) * q(j, k) : q(i, k) * q(j, l) + q(i, l) * q(j, k);
    }
  }
  return m;
}

Matrix6d RotateElasticity(const Matrix6d& d_material, const Eigen::Matrix3d& frame) {
  const Matrix6d m = StressRotation(frame);
  return m * d_material * m.transpose();
}

Matrix6d RotateCompliance(const Matrix6d& s_material, const Eigen::Matrix3d& frame) {
  // The strain transformation M^-T, with M^-1 the Bond matrix of Q^-1 = Q^T.
  const Matrix6d n = StressRotation(frame.transpose()).transpose();
  return n * s_material * n.transpose();
}

double VonMises(const Vector6d& s) {
  const double a = s(0) - s(1), b = s(1) - s(2), c = s(2) - s(0);
  return std::sqrt(0.5 * (a * a + b * b + c * c) + 3 * (s(3) * s(3) + s(4) * s(4) + s(5) * s(5)));
}

// The scene's linear elastic parameters (pba/scene.h), checked here with
// the law that uses them.
Status LinearElasticParams::Validate(const std::string& path) const {
  if (!(std::isfinite(youngs_modulus_pa) && youngs_modulus_pa > 0)) {
    return Status::InvalidArgument(
        path + ".youngs_modulus_pa",
        "Young's modulus must be a positive number of Pa, got " + ShortNumber(youngs_modulus_pa));
  }
  if (!std::isfinite(poissons_ratio) || poissons_ratio <= -1.0 || poissons_ratio >= 0.5) {
    std::string message =
        "Poisson's ratio must lie in (-1, 0.5), got " + ShortNumber(poissons_ratio);
    if (poissons_ratio == 0.5) {
      message += "; an incompressible material needs a hyperelastic model, not linear elasticity";
    }
    return Status::InvalidArgument(path + ".poissons_ratio", message);
  }
  return Status::Ok();
}

}  // namespace pba
