#include "material/hyperelastic.h"

#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace pba {
namespace {

// Voigt index -> tensor index pair (xx yy zz yz xz xy).
constexpr int kVoigtPairs[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};

}  // namespace

bool IsAdmissible(const Eigen::Matrix3d& f) { return f.allFinite() && f.determinant() > 0; }

void CheckAdmissible(const Eigen::Matrix3d& f, const char* where) {
  if (IsAdmissible(f)) return;
  std::fprintf(stderr, "pba: %s called with an inadmissible deformation gradient (det F = %g)\n",
               where, f.determinant());
  std::abort();
}

Status RequireFinite(double value, const std::string& field) {
  if (std::isfinite(value)) return Status::Ok();
  return Status::InvalidArgument(field, "must be a finite number");
}

Status RequirePositive(double value, const std::string& field) {
  PBA_RETURN_IF_ERROR(RequireFinite(value, field));
  if (value > 0) return Status::Ok();
  return Status::InvalidArgument(field, "must be > 0, got " + ShortNumber(value));
}

Status VolumetricParams::Validate(const std::string& path, int max_terms) const {
  PBA_RETURN_IF_ERROR(RequirePositive(d[0], path + ".d1"));
  for (int i = 1; i < 3; ++i) {
    const std::string field = path + ".d" + std::to_string(i + 1);
    PBA_RETURN_IF_ERROR(RequireFinite(d[i], field));
    if (d[i] < 0) return Status::InvalidArgument(field, "must be >= 0 (0 leaves the term out)");
    if (i >= max_terms && d[i] != 0) {
      return Status::InvalidArgument(
          field, "a model of order " + std::to_string(max_terms) + " has no such term");
    }
  }
  return Status::Ok();
}

ScalarDerivatives VolumetricEnergy(const VolumetricParams& params, double j) {
  // U = sum (1/D_i) (J-1)^(2i).
  ScalarDerivatives u;
  const double x = j - 1;
  for (int i = 1; i <= 3; ++i) {
    const double di = params.d[i - 1];
    if (di == 0) continue;
    const int n = 2 * i;
    u.value += std::pow(x, n) / di;
    u.first += n * std::pow(x, n - 1) / di;
    u.second += n * (n - 1) * std::pow(x, n - 2) / di;
  }
  return u;
}

InvariantState ComputeInvariants(const Eigen::Matrix3d& f) {
  InvariantState s;
  s.c = f.transpose() * f;
  s.j = f.determinant();
  const double i1 = s.c.trace();
  const double i2 = 0.5 * (i1 * i1 - s.c.squaredNorm());
  s.i1b = std::pow(s.j, -2.0 / 3.0) * i1;
  s.i2b = std::pow(s.j, -4.0 / 3.0) * i2;
  return s;
}

Vector6d SymmetricToVoigt(const Eigen::Matrix3d& t) {
  Vector6d v;
  for (int r = 0; r < 6; ++r) v(r) = t(kVoigtPairs[r][0], kVoigtPairs[r][1]);
  return v;
}

Eigen::Matrix3d VoigtToSymmetric(const Vector6d& v) {
  Eigen::Matrix3d t;
  t << v(0), v(5), v(4), v(5), v(1), v(3), v(4), v(3), v(2);
  return t;
}

Matrix6d FourthOrderToVoigt(const std::function<double(int, int, int, int)>& component) {
  Matrix6d m;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      m(r, c) =
          component(kVoigtPairs[r][0], kVoigtPairs[r][1], kVoigtPairs[c][0], kVoigtPairs[c][1]);
    }
  }
  return m;
}

void InvariantResponse(const InvariantState& state, const IsochoricInvariantEnergy& iso,
                       const ScalarDerivatives& vol, Vector6d* stress, Matrix6d* tangent) {
  // Psi(I1, I2, I3) = w(I1b, I2b) + U(J) with I1b = I1 I3^-1/3,
  // I2b = I2 I3^-2/3, J = I3^1/2. Chain rule to the derivatives in
  // (I1, I2, I3), then Holzapfel eqs. 6.32 (stress) and 6.193-6.196 (tangent).
  const Eigen::Matrix3d& c = state.c;
  const double i3 = state.j * state.j;
  const double i1 = state.i1b * std::cbrt(i3);
  const double i2 = state.i2b * std::pow(i3, 2.0 / 3.0);

  const double a1 = std::pow(i3, -1.0 / 3.0);                // dI1b/dI1
  const double a3 = -i1 * std::pow(i3, -4.0 / 3.0) / 3;      // dI1b/dI3
  const double a13 = -std::pow(i3, -4.0 / 3.0) / 3;          // d2I1b/dI1dI3
  const double a33 = 4 * i1 * std::pow(i3, -7.0 / 3.0) / 9;  // d2I1b/dI3^2
  const double b2 = std::pow(i3, -2.0 / 3.0);                // dI2b/dI2
  const double b3 = -2 * i2 * std::pow(i3, -5.0 / 3.0) / 3;  // dI2b/dI3
  const double b23 = -2 * std::pow(i3, -5.0 / 3.0) / 3;
  const double b33 = 10 * i2 * std::pow(i3, -8.0 / 3.0) / 9;
  const double j3 = 0.5 / state.j;            // dJ/dI3
  const double j33 = -0.25 / (state.j * i3);  // d2J/dI3^2

  const double p1 = iso.w1 * a1;
  const double p2 = iso.w2 * b2;
  const double p3 = iso.w1 * a3 + iso.w2 * b3 + vol.first * j3;

  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d c_inv = c.inverse();
  if (stress) {
    *stress = SymmetricToVoigt(2 * ((p1 + i1 * p2) * identity - p2 * c + i3 * p3 * c_inv));
  }
  if (!tangent) return;

  const double p11 = iso.w11 * a1 * a1;
  const double p12 = iso.w12 * a1 * b2;
  const double p22 = iso.w22 * b2 * b2;
  const double p13 = iso.w11 * a1 * a3 + iso.w12 * a1 * b3 + iso.w1 * a13;
  const double p23 = iso.w12 * b2 * a3 + iso.w22 * b2 * b3 + iso.w2 * b23;
  const double p33 = iso.w11 * a3 * a3 + 2 * iso.w12 * a3 * b3 + iso.w22 * b3 * b3 + iso.w1 * a33 +
                     iso.w2 * b33 + vol.second * j3 * j3 + vol.first * j33;

  const double d1 = 4 * (p11 + 2 * i1 * p12 + p2 + i1 * i1 * p22);
  const double d2 = -4 * (p12 + i1 * p22);
  const double d3 = 4 * (i3 * p13 + i1 * i3 * p23);
  const double d4 = 4 * p22;
  const double d5 = -4 * i3 * p23;
  const double d6 = 4 * (i3 * p3 + i3 * i3 * p33);
  const double d7 = -4 * i3 * p3;
  const double d8 = -4 * p2;

  *tangent = FourthOrderToVoigt([&](int i, int j, int k, int l) {
    const double ii = identity(i, j) * identity(k, l);
    const double ic = identity(i, j) * c(k, l) + c(i, j) * identity(k, l);
    const double iv = identity(i, j) * c_inv(k, l) + c_inv(i, j) * identity(k, l);
    const double cc = c(i, j) * c(k, l);
    const double cv = c(i, j) * c_inv(k, l) + c_inv(i, j) * c(k, l);
    const double vv = c_inv(i, j) * c_inv(k, l);
    const double v_odot_v = 0.5 * (c_inv(i, k) * c_inv(j, l) + c_inv(i, l) * c_inv(j, k));
    const double sym_identity =
        0.5 * (identity(i, k) * identity(j, l) + identity(i, l) * identity(j, k));
    return d1 * ii + d2 * ic + d3 * iv + d4 * cc + d5 * cv + d6 * vv + d7 * v_odot_v +
           d8 * sym_identity;
  });
}

}  // namespace pba
