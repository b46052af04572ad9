// The total-Lagrangian algebra the isoparametric solid elements share, for N
// nodes and Q integration points: the fully integrated element and the
// mean-dilatation element of fem/hex8_finite_strain.h (N = 8, Q = 8) and
// fem/tet10_finite_strain.h (N = 10, Q = 4). The element headers state the
// formulas; the derivation of the mean-dilatation terms is below.
//
// `Geometry` has grad (std::array<Eigen::Matrix<double, N, 3>, Q>, dN_a/dX
// at each point [1/m]), volume (std::array<double, Q>, w_q det J_q [m^3]) and
// min_jacobian; `Result` has force (3N), tangent (3N x 3N), energy, f
// (std::array<Eigen::Matrix3d, Q>), theta, and for the mean-dilatation
// element volume_gradient (3N), volumetric_weight and reference_volume. Unknowns u_e = (u0x u0y u0z
// u1x ...) [m].
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/LU>

#include "fem/strain_displacement.h"
#include "material/hyperelastic.h"

namespace pba {
namespace finite_strain_element {

// cof F by columns: (f2 x f3, f3 x f1, f1 x f2), no inverse needed.
inline Eigen::Matrix3d Cofactor(const Eigen::Matrix3d& f) {
  Eigen::Matrix3d cof;
  cof.col(0) = f.col(1).cross(f.col(2));
  cof.col(1) = f.col(2).cross(f.col(0));
  cof.col(2) = f.col(0).cross(f.col(1));
  return cof;
}

// [w]_x, the matrix of y -> w x y.
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return s;
}

// F at all Q points into result->f and the force, energy and (when
// `with_tangent`) tangent zeroed; false when the reference element is
// inverted or an F is not admissible. All F come first: the material must
// not see an inadmissible one.
template <int N, int Q, class Geometry, class Result>
bool StartElement(const Geometry& reference, const Eigen::Matrix<double, 3 * N, 1>& u,
                  bool with_tangent, Result* result) {
  if (!(reference.min_jacobian > 0)) return false;
  for (int q = 0; q < Q; ++q) {
    Eigen::Matrix3d& f = result->f[q];
    f.setIdentity();
    for (int a = 0; a < N; ++a) f += u.template segment<3>(3 * a) * reference.grad[q].row(a);
    if (!IsAdmissible(f)) return false;
  }
  result->force.setZero();
  result->energy = 0;
  if (with_tangent) result->tangent.setZero();
  return true;
}

// The initial-stress stiffness of stress `s` (Voigt) at one point of volume
// `dv`: (G_a . S G_b) I in block (a, b).
template <int N>
void AddGeometricStiffness(const Eigen::Matrix<double, N, 3>& grad, const Vector6d& s, double dv,
                           Eigen::Matrix<double, 3 * N, 3 * N>* tangent) {
  const Eigen::Matrix<double, N, N> geometric = dv * grad * VoigtToSymmetric(s) * grad.transpose();
  for (int a = 0; a < N; ++a) {
    for (int e = 0; e < N; ++e) {
      tangent->template block<3, 3>(3 * a, 3 * e).diagonal().array() += geometric(a, e);
    }
  }
}

// The whole energy W(F_q) at every point (C3D8, C3D10):
//   Pi = sum_q W(F_q) dV_q,  f = sum_q B_NL^T S_q dV_q,
//   K  = sum_q [B_NL^T C_q B_NL + (G_a . S_q G_b) I] dV_q.
// With `drop_pressure_stiffness` the tangent leaves out U'(J_q) d2J_q/dx2 at
// every point: the point's volumetric Hessian is U'' dJ dJ^T + U' d2J; with
// dJ = J C^-1 : delta E the first is U'' J^2 C^-1 (x) C^-1 in the material
// part, and U' d2J is what the J U' C^-1 parts of the material tangent and of
// S in the geometric term add up to. theta = v / V is reported for
// information.
template <int N, int Q, class Geometry, class Result>
bool FullIntegration(const Geometry& reference, const Eigen::Matrix<double, 3 * N, 1>& u,
                     const HyperelasticMaterial& material, bool with_tangent, Result* result,
                     bool drop_pressure_stiffness) {
  if (!StartElement<N, Q>(reference, u, with_tangent, result)) return false;
  double volume = 0, reference_volume = 0;
  for (int q = 0; q < Q; ++q) {
    const Eigen::Matrix3d& f = result->f[q];
    const Eigen::Matrix<double, N, 3>& grad = reference.grad[q];
    const double dv = reference.volume[q];
    const Vector6d s = material.Stress(f);
    const Eigen::Matrix<double, 6, 3 * N> b = GreenLagrangeB<N>(grad, f);
    result->force.noalias() += dv * b.transpose() * s;
    result->energy += dv * material.Energy(f);
    volume += dv * f.determinant();
    reference_volume += dv;
    if (!with_tangent) continue;
    Matrix6d c;
    Vector6d geometric_stress = s;
    if (drop_pressure_stiffness) {
      double w_iso = 0;
      material.Isochoric(f, &w_iso, &geometric_stress, &c);
      const double j = f.determinant();
      const Vector6d c_inv = SymmetricToVoigt((f.transpose() * f).inverse());
      c.noalias() += material.Volumetric(j).second * j * j * c_inv * c_inv.transpose();
    } else {
      c = material.Tangent(f);
    }
    result->tangent.noalias() += dv * b.transpose() * c * b;
    AddGeometricStiffness<N>(grad, geometric_stress, dv, &result->tangent);
  }
  result->theta = volume / reference_volume;
  return true;
}

// The mean-dilatation element (Pi as in fem/hex8_finite_strain.h). Derivation,
// with x_a = X_a + u_a the current positions, so F_q = sum_a x_a (x) G_a,q
// and dF_q/dx_a,i = e_i (x) G_a,q:
//
//   d(det F)/dF = cof F = (det F) F^-T (Jacobi's formula), hence
//     dv/dx_a = sum_q dV_q cof(F_q) G_a,q.
//   det F = (1/6) eps_ijm eps_kln F_ik F_jl F_mn, so
//     d2(det F)/dF_ik dF_jl = eps_ijm eps_kln F_mn and
//     d2v/dx_a,i dx_b,j = sum_q dV_q eps_ijm eps_kln F_mn G_ak G_bl
//                       = sum_q dV_q eps_ijm w_m,  w = F_q (G_a x G_b),
//                       = -sum_q dV_q [w]_x(i, j),
//     since [w]_x(i, j) = eps_imj w_m = -eps_ijm w_m. Each point's term is
//     skew in the node pair (block (b, a) = block (a, b)^T = -block (a, b),
//     blocks (a, a) = 0), as in analysis/average_nodal_pressure_model.cc.
//   d/dx [V U(v / V)] = U'(theta) dv/dx, and once more
//     (U''(theta) / V) (dv/dx)(dv/dx)^T + U'(theta) d2v/dx2.
//   The isochoric sum is the usual total-Lagrangian element of W_iso:
//     force B_NL^T S_iso, tangent material B_NL^T C_iso B_NL plus geometric
//     (G_a . S_iso G_b) I.
//
// V = sum_q dV_q by the same rule as v, so theta = 1 at u = 0 on any element,
// curved or not. On a homogeneous deformation theta = det F and Pi = V W(F),
// the fully integrated element's value. At u = 0, U'(1) = 0,
// dv/dx_a = V mean(G_a) and C_iso = the deviatoric part of the initial
// elasticity, so K is the B-bar stiffness with D = D_dev + K m m^T.
template <int N, int Q, class Geometry, class Result>
bool MeanDilatation(const Geometry& reference, const Eigen::Matrix<double, 3 * N, 1>& u,
                    const HyperelasticMaterial& material, bool with_tangent, Result* result,
                    bool drop_pressure_stiffness) {
  using Vector = Eigen::Matrix<double, 3 * N, 1>;
  using Matrix = Eigen::Matrix<double, 3 * N, 3 * N>;
  if (!StartElement<N, Q>(reference, u, with_tangent, result)) return false;
  const bool with_pressure_stiffness = with_tangent && !drop_pressure_stiffness;
  Vector volume_gradient = Vector::Zero();  // dv/dx
  Matrix volume_hessian;                    // d2v/dx2
  if (with_pressure_stiffness) volume_hessian.setZero();
  double volume = 0, reference_volume = 0;  // v, V
  for (int q = 0; q < Q; ++q) {
    const Eigen::Matrix3d& f = result->f[q];
    const Eigen::Matrix<double, N, 3>& grad = reference.grad[q];
    const double dv = reference.volume[q];
    double w_iso = 0;
    Vector6d s;
    Matrix6d c;
    material.Isochoric(f, &w_iso, &s, with_tangent ? &c : nullptr);
    const Eigen::Matrix<double, 6, 3 * N> b = GreenLagrangeB<N>(grad, f);
    result->force.noalias() += dv * b.transpose() * s;
    result->energy += dv * w_iso;
    volume += dv * f.determinant();
    reference_volume += dv;
    const Eigen::Matrix3d cof = Cofactor(f);
    for (int a = 0; a < N; ++a) {
      volume_gradient.template segment<3>(3 * a) += dv * cof * grad.row(a).transpose();
    }
    if (!with_tangent) continue;
    result->tangent.noalias() += dv * b.transpose() * c * b;
    AddGeometricStiffness<N>(grad, s, dv, &result->tangent);
    if (!with_pressure_stiffness) continue;
    for (int a = 0; a < N; ++a) {
      for (int e = a + 1; e < N; ++e) {
        const Eigen::Vector3d ga = grad.row(a).transpose(), ge = grad.row(e).transpose();
        const Eigen::Matrix3d block = -dv * Skew(f * ga.cross(ge));
        volume_hessian.template block<3, 3>(3 * a, 3 * e) += block;
        volume_hessian.template block<3, 3>(3 * e, 3 * a) += block.transpose();
      }
    }
  }
  result->theta = volume / reference_volume;
  const ScalarDerivatives vol = material.Volumetric(result->theta);
  result->volume_gradient = volume_gradient;
  result->volumetric_weight = vol.second / reference_volume;
  result->reference_volume = reference_volume;
  result->energy += reference_volume * vol.value;
  result->force += vol.first * volume_gradient;
  if (with_tangent) {
    result->tangent.noalias() +=
        (vol.second / reference_volume) * volume_gradient * volume_gradient.transpose();
    if (with_pressure_stiffness) result->tangent += vol.first * volume_hessian;
  }
  return true;
}

}  // namespace finite_strain_element
}  // namespace pba
